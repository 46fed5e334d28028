// The self-test's known-answer cases (selftest_cases.h): synthetic models of every kind, built in code from the
// counter RNG (kernels/shared/rng.h, domain STEX_DOMAIN_TEST, fixed salts), rendered on the device and with
// the kind's C++ reference over the same regions. Small on purpose: a row renders about 2000 pixels.
#include "runtime/selftest_cases.h"

#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/error.h"
#include "kernels/shared/rng.h"
#include "runtime/cs_rpn.h"
#include "runtime/cs_spot.h"
#include "runtime/gabor_params.h"
#include "runtime/gabor_renderer.h"
#include "runtime/lrp_reference.h"
#include "runtime/lrp_renderer.h"
#include "runtime/mix_model.h"
#include "runtime/mix_renderer.h"
#include "runtime/reference.h"
#include "runtime/surface.h"
#include "runtime/tb.h"
#include "runtime/texton_filter.h"
#include "runtime/texton_renderer.h"

namespace stex {
namespace {

float unit(std::uint32_t salt, std::int64_t i, std::int64_t j, std::uint32_t c = 0) {
  return selftest_unit(salt, i, j, c);
}
using selftest_detail::add;
using selftest_detail::append;
using selftest_detail::k_far;
using selftest_detail::k_near;
using selftest_detail::params;
using selftest_detail::Region;

// ---- texton (and the textons of mix and surface) ----

TextonModel synthetic_texton(int channels, int support, int order, std::uint32_t salt) {
  TextonModel m;
  m.channels = channels;
  m.support = support;
  m.order = order;
  m.alpha.resize(std::size_t(channels) * std::size_t(support) * std::size_t(support));
  const float amplitude = 0.08f / float(support);
  for (int c = 0; c < channels; ++c) {
    m.mean[std::size_t(c)] = 0.3f + 0.15f * float(c);
    for (int y = 0; y < support; ++y)
      for (int x = 0; x < support; ++x) {
        const float wave = 0.7f * std::cos(6.2831853f * (float(x) + 0.4f * float(y)) / 5.0f + float(c));
        m.alpha[(std::size_t(c) * std::size_t(support) + std::size_t(y)) * std::size_t(support) + std::size_t(x)] =
            amplitude * (unit(salt, x, y, std::uint32_t(c)) - 0.5f + wave) + 0.002f;
      }
  }
  m.exemplar_name = "selftest";
  return m;
}

// "splat", "gather", "gather-local", each optionally followed by " order N".
KnownAnswer texton_case(Context& ctx, const std::string& path) {
  std::string strategy = path;
  int order = 1;
  const std::size_t sp = path.find(" order ");
  if (sp != std::string::npos) {
    strategy = path.substr(0, sp);
    const std::string n = path.substr(sp + 7);
    order = n == "0" ? 0 : n == "1" ? 1 : n == "3" ? 3 : n == "5" ? 5 : -1;
    if (order < 0) throw Error(ErrorKind::Usage, "unknown self-test row 'texton " + path + "'");
  }
  TextonRenderOptions options;
  options.strategy = parse_texton_strategy(strategy);
  const TextonModel m = synthetic_texton(3, 12, order, 0x7e470001u + std::uint32_t(order));
  TextonRenderer renderer(ctx, m);
  KnownAnswer ka;
  for (const RenderParams& rp : {params(1.0), params(1.5)}) {
    const TextonReference ref(m, rp);
    for (const Region& r : {k_near, k_far}) {
      TextonRenderStats stats;
      append(ka.device, renderer.render(rp, r.x, r.y, r.w, r.h, options, &stats));
      append(ka.reference, ref.render(r.x, r.y, r.w, r.h));
      if (stats.strategy != options.strategy)
        ka.note = std::string("ran ") + texton_strategy_name(stats.strategy) + " (the device's fallback)";
    }
  }
  return ka;
}

// "filtered": the flat plane at scale < 1 (kernel texton_filtered_scaled); "mapped": a perspective camera and
// a UV map (kernel texton_filtered_mapped).
KnownAnswer filtered_case(Context& ctx, bool mapped) {
  const TextonModel m = synthetic_texton(3, 12, 1, 0x7e470100u);
  FilteredTextonRenderer renderer(ctx, m);
  KnownAnswer ka;
  if (!mapped) {
    const RenderParams rp = params(0.37);
    const FilteredTextonReference ref(m, rp);
    for (const Region& r : {k_near, k_far}) {
      append(ka.device, renderer.render_scaled(rp, r.x, r.y, r.w, r.h));
      append(ka.reference, ref.render_scaled(r.x, r.y, r.w, r.h));
    }
    return ka;
  }
  const RenderParams rp = params(1.0);
  const FilteredTextonReference ref(m, rp);
  const PerspectiveCamera cam = parse_camera("60,75,60", k_near.w, k_near.h);
  append(ka.device, renderer.render_camera(rp, cam, 0, 0, k_near.w, k_near.h));
  append(ka.reference, ref.render_camera(cam, 0, 0, k_near.w, k_near.h));
  // A sheared, rotated UV map far from the origin.
  UvMap map;
  map.width = k_far.w;
  map.height = k_far.h;
  for (int j = 0; j < map.height; ++j)
    for (int i = 0; i < map.width; ++i) {
      map.uv.push_back(1.0e6 + 1.7 * i - 0.6 * j + 0.01 * i * j);
      map.uv.push_back(-3.0e5 + 0.5 * i + 2.3 * j);
    }
  append(ka.device, renderer.render_uv_map(rp, map));
  append(ka.reference, ref.render_uv_map(map));
  return ka;
}

// ---- lrp ----

LrpStratum lrp_stratum(double delta, double amplitude, std::vector<int> sub_counts) {
  LrpStratum s;
  s.delta = delta;
  s.amplitude = amplitude;
  s.sub_counts = std::move(sub_counts);
  for (int c : s.sub_counts) s.size += c;
  return s;
}

// Strata only, or with structure (blocks of fixed-phase terms), turbulence and random placement.
LrpModel synthetic_lrp(bool structure) {
  const std::uint32_t salt = 0x1a900001u;
  LrpModel m;
  m.channels = 3;
  m.period = 32;
  m.mean = {0.5f, 0.45f, 0.4f, 0.0f};
  m.strata = {lrp_stratum(6.0, 0.04, {3, 2}), lrp_stratum(9.5, 0.025, {4})};
  auto freq = [&](int k, std::uint32_t c) { return std::int32_t(std::floor(unit(salt, k, 0, c) * 31.0f)) - 15; };
  for (int k = 0; k < 9; ++k) {
    m.freqs.push_back(freq(k, 0));
    m.freqs.push_back(freq(k, 1));
  }
  for (int s = 0; s < 3; ++s)
    for (int c = 0; c < m.channels; ++c) {
      const float theta = 6.2831853f * unit(salt, s, 1, std::uint32_t(c));
      m.colours.push_back(0.8f * std::cos(theta));
      m.colours.push_back(0.8f * std::sin(theta));
    }
  m.cosines = 9;
  if (structure) {
    m.ratio = 0.3;
    m.block = 8;
    m.jr = 2;
    const int terms = m.blocks() * m.blocks() * m.jr;
    for (int t = 0; t < terms; ++t) {
      m.terms.push_back(float(std::floor(unit(salt, t, 2) * 7.0f)) - 3.0f);
      m.terms.push_back(float(std::floor(unit(salt, t, 3) * 7.0f)) - 3.0f);
      for (int c = 0; c < 2 * m.channels; ++c) m.terms.push_back(0.04f * (unit(salt, t, 4, std::uint32_t(c)) - 0.5f));
    }
    m.sigma = 1.5;
    m.turbulence = {lrp_stratum(7.0, 0.05, {2})};
    m.turb_freqs = {3, -5, -7, 2};
    m.placement = true;
  }
  return m;
}

KnownAnswer lrp_case(Context& ctx) {
  KnownAnswer ka;
  const RenderParams rp = params();
  const LrpModel plain = synthetic_lrp(false), structured = synthetic_lrp(true);
  LrpNoise a(ctx, plain), b(ctx, structured);
  add(ka, a, LrpReference(plain, rp), rp, k_near);
  const LrpReference ref_b(structured, rp);
  add(ka, b, ref_b, rp, k_near);
  add(ka, b, ref_b, rp, k_far);
  return ka;
}

// ---- gabor ----

KnownAnswer gabor_case(Context& ctx, bool filtered) {
  GaborModel m;
  m.bandwidth = 0.08;
  m.components.resize(2);
  m.components[0] = GaborComponent{0.1, 0.4, 0.0, 1.0};
  m.components[1] = GaborComponent{0.2, 1.3, 0.5, 0.6};
  KnownAnswer ka;
  GaborNoise n(ctx, m);
  // Filtered: kernels convolved with the footprint of a minified view (wider envelopes, gains below 1).
  std::vector<RenderParams> rps = {params(1.0, 16.0), params(0.6, 16.0)};
  if (filtered) {
    rps = {params(0.6, 16.0), params(0.6, 16.0)};
    rps[0].scale = 0.125;
    rps[1].scale = 0.5;
    for (RenderParams& rp : rps) rp.filter = true;
  }
  for (const RenderParams& rp : rps) {
    const GaborReference ref(m, rp);
    add(ka, n, ref, rp, k_near);
    add(ka, n, ref, rp, k_far);
  }
  return ka;
}

// ---- mix ----

MixModel synthetic_mix(int order, bool image_map) {
  MixModel m;
  m.channels = 3;
  m.support = 10;
  m.order = order;
  m.levels = 3;
  for (int k = 0; k < m.levels; ++k) {
    const TextonModel t = synthetic_texton(3, 10, order, 0x3150001u + std::uint32_t(k));
    m.alpha.insert(m.alpha.end(), t.alpha.begin(), t.alpha.end());
  }
  m.mean0 = {0.3f, 0.4f, 0.5f, 0.0f};
  m.mean1 = {0.6f, 0.5f, 0.2f, 0.0f};
  m.map.type = MixMap::Type::Ramp;
  m.map.x0 = -30.0;
  m.map.x1 = 30.0;
  if (image_map) {
    m.map.type = MixMap::Type::Image;
    m.map.map_width = 5;
    m.map.map_height = 4;
    for (int i = 0; i < 20; ++i) m.map.grey.push_back(unit(0x3150100u, i, 0));
    m.map.scale = 7.0;
    m.map.origin_x = -9;
    m.map.origin_y = 4;
    m.map.name = "selftest";
  }
  return m;
}

KnownAnswer mix_case(Context& ctx, int order) {
  KnownAnswer ka;
  const RenderParams rp = params();
  const MixModel ramp = synthetic_mix(order, false), image = synthetic_mix(order, true);
  MixNoise a(ctx, ramp), b(ctx, image);
  const MixReference ref_a(ramp, rp);
  add(ka, a, ref_a, rp, k_near);
  add(ka, a, ref_a, rp, k_far);
  add(ka, b, MixReference(image, rp), rp, k_near);
  return ka;
}

// Filtered minified views (the box-prefiltered textons, kernel mix_filtered): orders 1 and 3, ramp and image maps.
KnownAnswer mix_filtered_case(Context& ctx) {
  KnownAnswer ka;
  RenderParams rp = params();
  rp.filter = true;
  for (int order : {1, 3}) {
    const MixModel ramp = synthetic_mix(order, order == 3);
    MixNoise n(ctx, ramp);
    for (double scale : {0.125, 0.45}) {
      rp.scale = scale;
      const MixReference ref(ramp, rp);
      add(ka, n, ref, rp, k_near);
      add(ka, n, ref, rp, k_far);
    }
  }
  return ka;
}

}  // namespace

KnownAnswer selftest_known_answer(Context& ctx, const SelftestRow& row) {
  const std::string& k = row.kind;
  const std::string& p = row.path;
  if (k == "texton" && p == "filtered") return filtered_case(ctx, false);
  if (k == "texton" && p == "mapped") return filtered_case(ctx, true);
  if (k == "texton") return texton_case(ctx, p);
  if (k == "lrp" && p == "gather") return lrp_case(ctx);
  if (k == "gabor" && (p == "gather" || p == "filtered")) return gabor_case(ctx, p == "filtered");
  if (k == "mix" && (p == "gather" || p == "gather order 0" || p == "gather order 3" || p == "gather order 5"))
    return mix_case(ctx, p == "gather" ? 1 : p.back() - '0');
  if (k == "mix" && p == "filtered") return mix_filtered_case(ctx);
  if (k == "cs-spot" && (p == "lattice" || p == "general")) return cs_spot_case(ctx, p == "general");
  if (k == "cs-rpn") {
    for (CsRpnVariant v : {CsRpnVariant::RandomPhase, CsRpnVariant::Gabor, CsRpnVariant::Phasor, CsRpnVariant::Fourier})
      if (p == cs_rpn_variant_name(v)) return cs_rpn_case(ctx, v);
  }
  if (k == "tb" && (p == "aligned" || p == "scaled")) return tb_case(ctx, false, p);
  if (k == "cs-tb" && (p == "aligned" || p == "sub-pixel" || p == "scaled")) return tb_case(ctx, true, p);
  if (k == "surface" && p == "points") return surface_case(ctx);
  throw Error(ErrorKind::Usage, "unknown self-test row '" + row.name() + "'");
}

float selftest_unit(std::uint32_t salt, std::int64_t i, std::int64_t j, std::uint32_t c) {
  const stex_uvec4 v = stex_draw(stex_cell_key(i, j), salt, 0x5e1f7e57u, c, STEX_DOMAIN_TEST);
  return stex_uniform24(v.x);
}

TextonModel selftest_texton(int channels, int support, int order, std::uint32_t salt) {
  return synthetic_texton(channels, support, order, salt);
}

}  // namespace stex
