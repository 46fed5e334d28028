// The self-test's known-answer cases of cs-spot, cs-rpn, tb, cs-tb and surface points (selftest_cases.h).
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/error.h"
#include "runtime/cs_rpn.h"
#include "runtime/cs_spot.h"
#include "runtime/selftest_cases.h"
#include "runtime/surface.h"
#include "runtime/tb.h"

namespace stex {
namespace {

using selftest_detail::add;
using selftest_detail::append;
using selftest_detail::k_far;
using selftest_detail::k_near;
using selftest_detail::k_seed;
using selftest_detail::params;

// A cyclostationary histogram transfer of mode cs: 2 x 2 bins of 16 non-decreasing quantiles per channel.
CsHistTable synthetic_hist(int channels, std::uint32_t salt) {
  CsHistTable t;
  t.mode = 2;
  t.delta = 1;
  t.m0 = t.m1 = 2;
  t.q = 16;
  t.channels = channels;
  for (int b = 0; b < 4 * channels; ++b) {
    float v = 0.05f;
    for (int k = 0; k < t.q; ++k) {
      v += 0.05f * selftest_unit(salt, b, k);
      t.quantiles.push_back(v);
    }
  }
  return t;
}

// ---- cs-spot ----

CsSpotModel synthetic_cs_spot(bool hist) {
  const std::uint32_t salt = 0xc5500001u;
  CsSpotModel m;
  m.t0x = 13.71;
  m.t0y = -5.23;
  m.t1x = 6.14;
  m.t1y = 15.92;
  m.width = m.height = 20;
  m.channels = 3;
  for (int j = 0; j < m.height; ++j)
    for (int i = 0; i < m.width; ++i) {
      // A window going to zero at the borders times random values.
      const double w = std::sin(3.14159265358979 * (i + 0.5) / m.width) * std::sin(3.14159265358979 * (j + 0.5) / m.height);
      for (int c = 0; c < m.channels; ++c)
        m.spot.push_back(float(w * 0.2 * (selftest_unit(salt, i, j, std::uint32_t(c)) - 0.5)));
    }
  m.n0 = m.n1 = 4;
  for (int k = 0; k < m.n0 * m.n1 * m.channels; ++k) m.mean.push_back(0.45f + 0.1f * selftest_unit(salt, k, -1));
  m.amplitude = 1.3;
  if (hist) m.hist = synthetic_hist(m.channels, salt + 1);
  return m;
}

}  // namespace

// "lattice": periods x scale <= 4096 output pixels (the fast path: kernels cs_spot_weights + cs_spot);
// "general": scale 300 puts the periods beyond it (cs_spot_general).
KnownAnswer cs_spot_case(Context& ctx, bool general) {
  KnownAnswer ka;
  const CsSpotModel plain = synthetic_cs_spot(false), hist = synthetic_cs_spot(true);
  const RenderParams rp = params(general ? 300.0 : 1.0);
  CsSpotNoise a(ctx, plain), b(ctx, hist);
  const CsSpotReference ref_a(plain, rp);
  add(ka, a, ref_a, rp, k_near);
  add(ka, a, ref_a, rp, k_far);
  add(ka, b, CsSpotReference(hist, rp), rp, k_near);
  return ka;
}

// ---- cs-rpn ----

KnownAnswer cs_rpn_case(Context& ctx, CsRpnVariant variant) {
  const std::uint32_t salt = 0xc5900001u;
  CsRpnModel m;
  m.variant = variant;
  m.t0x = 40.3;
  m.t0y = 6.1;
  m.t1x = -5.2;
  m.t1y = 37.9;
  m.k0 = 2;
  m.k1 = 1;
  m.bin = 1.0 / 32.0;  // every bin on the grid k / 32: valid for the Fourier variant too
  m.bandwidth = 0.06;
  m.spacing = 12.0;
  m.cosines = 8;
  m.mean = 0.5;
  for (int g = 0; g < 2; ++g) {
    CsRpnSpectrum s;
    s.energy = 0.02 + 0.01 * g;
    for (int b = 0; b < 5; ++b) {
      const int kx = 1 + int(selftest_unit(salt, g, b, 0) * 12.0f), ky = int(selftest_unit(salt, g, b, 1) * 17.0f) - 8;
      s.bins.push_back(float(kx) / 32.0f);
      s.bins.push_back(float(ky) / 32.0f);
      s.bins.push_back(0.2f + selftest_unit(salt, g, b, 2));
    }
    s.source = "selftest";
    m.spectra.push_back(s);
  }
  KnownAnswer ka;
  CsRpnNoise n(ctx, m);
  for (const RenderParams& rp : {params(1.0, 12.0), params(0.6, 12.0)}) {
    const CsRpnReference ref(m, rp);
    add(ka, n, ref, rp, k_near);
    if (rp.scale == 1.0) add(ka, n, ref, rp, k_far);
  }
  return ka;
}

namespace {

// ---- tb, cs-tb ----

// 64 x 64 x 3, tile 16 (a run of 16 lanes at scale 1). cs-tb: integer or sub-pixel periods, optionally the
// cs histogram transfer.
TbModel synthetic_tb(bool cs, bool integer_periods, bool hist) {
  const std::uint32_t salt = 0x7b000001u;
  TbModel m;
  m.cs = cs;
  m.tile = 16.0;
  m.width = m.height = 64;
  m.channels = 3;
  for (int j = 0; j < m.height; ++j)
    for (int i = 0; i < m.width; ++i)
      for (int c = 0; c < m.channels; ++c) {
        const auto u = [&](std::uint32_t k) { return selftest_unit(salt, i, j, std::uint32_t(c) * 4 + k); };
        m.gauss.push_back(0.5f + 0.33f * (u(0) + u(1) + u(2) - 1.5f));  // about N(0.5, 1/6^2)
      }
  m.lut_size = 64;
  for (int c = 0; c < m.channels; ++c)
    for (int i = 0; i < m.lut_size; ++i) {
      const double t = double(i) / (m.lut_size - 1);
      m.lut.push_back(float(0.1 + 0.02 * c + 0.8 * t * t * (3.0 - 2.0 * t)));
    }
  m.pca = {0.45f, 0.5f, 0.55f, 0.6f, 0.8f, 0.0f, -0.8f, 0.6f, 0.0f, 0.0f, 0.0f, 1.0f};
  if (!cs) {
    m.mean = {0.5f, 0.5f, 0.5f};
    return m;
  }
  if (integer_periods) {
    m.t0x = 11.0, m.t0y = 2.0, m.t1x = -3.0, m.t1y = 10.0;
  } else {
    m.t0x = 11.37, m.t0y = 2.21, m.t1x = -3.41, m.t1y = 9.83;
  }
  m.n0 = m.n1 = 3;
  for (int k = 0; k < m.n0 * m.n1 * m.channels; ++k) m.mean.push_back(0.45f + 0.1f * selftest_unit(salt, k, -1));
  if (hist) m.hist = synthetic_hist(m.channels, salt + 1);
  return m;
}

}  // namespace

// "aligned": scale 1 (tb, or cs-tb with integer periods): the run kernel with 16 and 8 lanes on CPUs, the
// aligned per-pixel kernel elsewhere. "sub-pixel" (cs-tb): scale 1, sub-pixel periods. "scaled": scale 0.43
// (the per-pixel kernel: tiles under 8 output pixels) and 1.9 (bilinear fetches).
KnownAnswer tb_case(Context& ctx, bool cs, const std::string& path) {
  KnownAnswer ka;
  const bool aligned = path == "aligned";
  const TbModel m = synthetic_tb(cs, aligned, false);
  TbNoise n(ctx, m);
  const std::vector<double> scales = path == "scaled" ? std::vector<double>{0.43, 1.9} : std::vector<double>{1.0};
  for (double scale : scales) {
    const RenderParams rp = params(scale);
    const TbReference ref(m, rp);
    add(ka, n, ref, rp, k_near);
    add(ka, n, ref, rp, k_far);
  }
  if (path != "scaled") {  // the 8-lane run kernel too (auto picks 16 lanes for this tile)
    n.run_lanes = 8;
    add(ka, n, TbReference(m, params()), params(), k_near);
  }
  if (cs) {
    const TbModel h = synthetic_tb(true, aligned, true);
    TbNoise nh(ctx, h);
    const RenderParams rp = params(scales.back());
    add(ka, nh, TbReference(h, rp), rp, k_near);
  }
  return ka;
}

// ---- surface points ----

KnownAnswer surface_case(Context& ctx) {
  const std::uint32_t salt = 0x5f000001u;
  const TextonModel m = selftest_texton(3, 10, 1, salt);
  SurfaceParams sp;
  sp.seed = k_seed;
  sp.texel = 0.01;
  std::vector<float> pos, frames;
  int k = 0;
  for (double offset : {-0.37, 1000.0})
    for (int z = 0; z < 4; ++z)
      for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x, ++k) {
          const int xyz[3] = {x, y, z};
          for (int a = 0; a < 3; ++a)
            pos.push_back(float(offset + 0.013 * xyz[a] + 0.05 * selftest_unit(salt, k, a, 1)));
          double normal[3], tangent[3];
          for (int a = 0; a < 3; ++a) {
            normal[a] = selftest_unit(salt, k, a, 2) - 0.5;
            tangent[a] = selftest_unit(salt, k, a, 3) - 0.5;
          }
          normal[2] += 0.7;  // never zero
          const auto f = surface_frame(normal, tangent, std::size_t(k));
          frames.insert(frames.end(), f.begin(), f.end());
        }
  const std::size_t count = pos.size() / 3, nc = std::size_t(m.channels);
  KnownAnswer ka;
  ka.device.resize(count * nc);
  ka.reference.resize(count * nc);
  const SurfaceReference ref(m, sp);
  for (std::size_t i = 0; i < count; ++i) ref.eval(&pos[3 * i], &frames[9 * i], &ka.reference[nc * i]);
  SurfaceRenderer dev(ctx, m);
  dev.eval(sp, count, pos.data(), frames.data(), ka.device.data());
  return ka;
}

}  // namespace stex
