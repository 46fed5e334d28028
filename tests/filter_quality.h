// Shared by the filter-quality tests of every kind (issue 31 item 4; docs/filtering.md): the 16 x 16
// supersampled box reference of a render, and the two measures its acceptance is stated in.
#pragma once
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/render_params.h"

namespace stex::test {

// The mean of 16 x 16 point evaluations per output pixel, at the sub-pixel centres (i + (2a + 1)/32,
// j + (2b + 1)/32) in 2^16 fixed units per output pixel: the box filter of the pixel applied to the same
// realisation. eval(fx, fy, out) writes `channels` values at a fixed-point position. Summed in double.
// `k` (a power of two up to 256) samples per axis instead of 16: a finer reference, for scales where 16
// samples per pixel are more than a texel apart.
template <class Eval>
std::vector<float> box_supersampled(Eval&& eval, int channels, std::int64_t x, std::int64_t y, int w, int h,
                                    int k = 16) {
  std::vector<float> out(std::size_t(w) * std::size_t(h) * std::size_t(channels));
  std::vector<float> v(std::size_t(channels) + 4);
  const std::int64_t half_step = 32768 / k;  // (2a + 1) / (2k) of a pixel, exact in 2^16 units
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      double acc[16] = {};
      for (int b = 0; b < k; ++b)
        for (int a = 0; a < k; ++a) {
          eval((x + i) * 65536 + (2 * a + 1) * half_step, (y + j) * 65536 + (2 * b + 1) * half_step, v.data());
          for (int c = 0; c < channels; ++c) acc[c] += v[std::size_t(c)];
        }
      for (int c = 0; c < channels; ++c)
        out[(std::size_t(j) * std::size_t(w) + std::size_t(i)) * std::size_t(channels) + std::size_t(c)] =
            float(acc[c] / (double(k) * double(k)));
    }
  return out;
}

// The parameters of a minified view (scale < 1) of a filter test: filtered or point-sampled.
inline RenderParams minified(double scale, std::uint64_t seed, bool filter, double mni = 30.0) {
  RenderParams rp;
  rp.seed = seed;
  rp.scale = scale;
  rp.mni = mni;
  rp.filter = filter;
  return rp;
}

// RMS of a - b (same sizes).
inline double rms_diff(const std::vector<float>& a, const std::vector<float>& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
  return std::sqrt(s / double(a.size()));
}

// Standard deviation of the values (all channels together).
inline double stddev(const std::vector<float>& a) {
  double m = 0, q = 0;
  for (float v : a) m += v;
  m /= double(a.size());
  for (float v : a) q += (v - m) * (v - m);
  return std::sqrt(q / double(a.size()));
}

}  // namespace stex::test
