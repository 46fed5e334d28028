// The known-answer cases of the self-test (runtime/selftest.h): per row, small synthetic models built in code
// and rendered on the device and with the C++ reference over the same regions and parameters.
// selftest_cases.cpp: texton (strategies, orders, filtered, mapped), lrp, gabor, mix; selftest_cases_cs.cpp:
// cs-spot, cs-rpn, tb, cs-tb, surface points.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/context.h"
#include "runtime/cs_rpn.h"
#include "runtime/model.h"
#include "runtime/noise_renderer.h"
#include "runtime/selftest.h"
#include "runtime/texton_params.h"

namespace stex {

struct KnownAnswer {
  std::vector<float> device, reference;  // the outputs of every sub-render, concatenated in one order
  std::string note;                      // what the device made the renderer do differently, if anything
};

// Renders row's cases on ctx's device and with the reference. Error(Usage) for an unknown row; device
// errors propagate.
KnownAnswer selftest_known_answer(Context& ctx, const SelftestRow& row);

// ---- shared by the two cases files ----

// Uniform in [0, 1) keyed by (i, j, c) and a salt (the counter RNG, domain STEX_DOMAIN_TEST): the synthetic
// models' only source of values.
float selftest_unit(std::uint32_t salt, std::int64_t i, std::int64_t j, std::uint32_t c = 0);
// A texton model of `channels`, `support`, `order`: small random coefficients plus an oriented wave.
TextonModel selftest_texton(int channels, int support, int order, std::uint32_t salt);

KnownAnswer cs_spot_case(Context& ctx, bool general);
KnownAnswer cs_rpn_case(Context& ctx, CsRpnVariant variant);
KnownAnswer tb_case(Context& ctx, bool cs, const std::string& path);
KnownAnswer surface_case(Context& ctx);

namespace selftest_detail {
struct Region {
  std::int64_t x, y;
  int w, h;
};
// Near the origin, on its negative side (chunks and cells of both signs), and far from it.
inline constexpr Region k_near{-37, -21, 48, 32};
inline constexpr Region k_far{1000000000003LL, -777777777LL, 24, 16};
inline constexpr std::uint64_t k_seed = 0x5e1f7e57c0ffee11ULL;

inline RenderParams params(double scale = 1.0, double mni = 30.0) {
  RenderParams rp;
  rp.seed = k_seed;
  rp.scale = scale;
  rp.mni = mni;
  return rp;
}

inline void append(std::vector<float>& to, const std::vector<float>& v) { to.insert(to.end(), v.begin(), v.end()); }

inline std::vector<float> device_render(NoiseRenderer& n, const RenderParams& rp, const Region& r) {
  std::vector<float> out(std::size_t(r.w) * std::size_t(r.h) * std::size_t(n.channels()));
  n.render(rp, r.x, r.y, r.w, r.h, out.data());
  return out;
}

// One sub-render of a NoiseRenderer against its reference (any class with render(x, y, w, h)).
template <class Reference>
void add(KnownAnswer& ka, NoiseRenderer& n, const Reference& ref, const RenderParams& rp, const Region& r) {
  append(ka.device, device_render(n, rp, r));
  append(ka.reference, ref.render(r.x, r.y, r.w, r.h));
}
}  // namespace selftest_detail

}  // namespace stex
