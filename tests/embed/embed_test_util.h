// Shared helpers of the embedding tests (tests/embed): one stex context per test binary on the test device,
// models analysed once (the bundled gravel exemplar, a synthetic colour exemplar in memory), status
// assertions that print stex_last_error(), and bit-exact comparison. Uses the public C API only.
#pragma once
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "stex/stex.h"
#include "test_device.h"

#define ASSERT_STEX_OK(call)                                                               \
  do {                                                                                     \
    const stex_status status_ = (call);                                                    \
    ASSERT_EQ(status_, STEX_OK) << stex_status_name(status_) << ": " << stex_last_error(); \
  } while (0)

#define EXPECT_STEX_STATUS(call, expected)                                                            \
  do {                                                                                                \
    const stex_status status_ = (call);                                                               \
    EXPECT_EQ(status_, expected) << "got " << stex_status_name(status_) << ": " << stex_last_error(); \
  } while (0)

namespace stex_embed_test {

inline std::string gravel_path() { return std::string(STEX_SOURCE_DIR) + "/data/gravel.png"; }
inline std::string tmp_dir() { return STEX_TEST_TMP_DIR; }

// The device spec of every context the tests create: STEX_TEST_DEVICE (tests/test_device.h), "" = the
// default device (the C API does not read STEX_DEVICE itself).
inline const char* device_spec() {
  static const std::string spec = stex::test::test_device_spec();
  return spec.c_str();
}

// The shared context (on device_spec()). Never destroyed (the process ends).
stex_context* context();

// Gravel (1 channel) analysed with support 16, 8 iterations.
const stex_model* gravel_model();
// A synthetic 3-channel 48 x 40 exemplar from memory, support 8, 6 iterations.
const stex_model* colour_model();
// The synthetic exemplar itself (interleaved, 3 channels).
std::vector<float> colour_exemplar(int width, int height);

inline stex_render_params render_params(double mni = 30.0, std::uint64_t seed = 1,
                                        int strategy = STEX_STRATEGY_AUTO) {
  stex_render_params p;
  stex_render_params_init(&p, sizeof p);
  p.mni = mni;
  p.seed = seed;
  p.strategy = strategy;
  return p;
}

inline int channels_of(const stex_model* m) {
  stex_model_info info{};
  info.struct_size = sizeof info;
  if (stex_model_get_info(m, &info) != STEX_OK) return 0;
  return info.channels;
}

// Number of floats whose bits differ (-0 != +0, NaN-safe); size mismatch counts as everything.
inline std::size_t bit_differences(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) return a.size() > b.size() ? a.size() : b.size();
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(float)) != 0) ++n;
  return n;
}

// Packed render through the C API (fails the test on error).
std::vector<float> render(stex_context* ctx, const stex_model* model, const stex_render_params& params,
                          std::int64_t x, std::int64_t y, int width, int height);

}  // namespace stex_embed_test
