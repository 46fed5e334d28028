// The synthetic pattern of the farm tests (tests/farm/helper/farm_synth.cpp and the in-process tests):
// a pure integer hash of (seed, x, y, channel) mapped to [0, 1) floats with 24 bits, so every value is
// exact in float and independent of how the image is cut into tiles.
#pragma once
#include <cstdint>
#include <vector>

namespace stex::farm::test {

inline std::uint32_t synth_hash(std::uint64_t seed, std::int64_t x, std::int64_t y, int c) {
  std::uint64_t h = seed * 0x9E3779B97F4A7C15ULL ^ std::uint64_t(x) * 0xBF58476D1CE4E5B9ULL ^
                    std::uint64_t(y) * 0x94D049BB133111EBULL ^ std::uint64_t(c + 1) * 0xD6E8FEB86659FD93ULL;
  h ^= h >> 31;
  h *= 0x7FB5D329728EA185ULL;
  h ^= h >> 27;
  h *= 0x81DADEF4BC2DD44DULL;
  h ^= h >> 33;
  return std::uint32_t(h);
}

inline float synth_value(std::uint64_t seed, std::int64_t x, std::int64_t y, int c) {
  return float(synth_hash(seed, x, y, c) >> 8) * (1.0f / 16777216.0f);
}

// Fills `out` (resized to w*h*channels) with the pattern over [x0, x0+w) x [y0, y0+h).
inline void synth_region(std::uint64_t seed, int channels, std::int64_t x0, std::int64_t y0, int w, int h,
                         std::vector<float>& out) {
  out.resize(std::size_t(w) * h * channels);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c)
        out[(std::size_t(y) * w + x) * channels + c] = synth_value(seed, x0 + x, y0 + y, c);
}

}  // namespace stex::farm::test
