// Tests of the C API (include/stex/stex.h) through libstex.so only: status codes and last-error text,
// argument checks, parameter structs, models (load, save, analyse from files and memory), renders with row
// strides and progress/cancellation, point queries at pixel centres equal to renders bit for bit, the
// per-context model cache.
#include <dlfcn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "embed_test_util.h"

using namespace stex_embed_test;

namespace {

std::vector<double> centres(std::int64_t x0, std::int64_t y0, int width, int height) {
  std::vector<double> xy;
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      xy.push_back(double(x0 + i) + 0.5);
      xy.push_back(double(y0 + j) + 0.5);
    }
  return xy;
}

std::vector<float> points(stex_context* ctx, const stex_model* model, const stex_render_params& p,
                          const std::vector<double>& xy) {
  std::vector<float> out(xy.size() / 2 * channels_of(model));
  const stex_status s = stex_eval_points(ctx, model, &p, xy.size() / 2, xy.data(), out.data());
  if (s != STEX_OK) ADD_FAILURE() << stex_status_name(s) << ": " << stex_last_error();
  return out;
}

}  // namespace

TEST(CApi, StatusNamesAndVersions) {
  EXPECT_STREQ(stex_status_name(STEX_OK), "STEX_OK");
  EXPECT_STREQ(stex_status_name(STEX_CANCELLED), "STEX_CANCELLED");
  EXPECT_STREQ(stex_status_name(STEX_INVALID_ARGUMENT), "STEX_INVALID_ARGUMENT");
  EXPECT_STREQ(stex_status_name(STEX_RETRYABLE), "STEX_RETRYABLE");
  EXPECT_STREQ(stex_status_name(static_cast<stex_status>(99)), "STEX_UNKNOWN_STATUS");
  // The first group mirrors the CLI's exit codes (core/error.h).
  EXPECT_EQ(int(STEX_USAGE), 2);
  EXPECT_EQ(int(STEX_INPUT), 3);
  EXPECT_EQ(int(STEX_DEVICE), 4);
  EXPECT_EQ(int(STEX_LIMIT), 5);
  EXPECT_EQ(int(STEX_OUTPUT), 6);
  EXPECT_EQ(int(STEX_RETRYABLE), 75);
  EXPECT_EQ(stex_abi_version(), STEX_ABI_VERSION);
  EXPECT_STRNE(stex_version_string(), "");
}

TEST(CApi, ErrorsSetStatusAndThreadLocalMessage) {
  stex_model* m = reinterpret_cast<stex_model*>(0x1);
  EXPECT_STEX_STATUS(stex_model_load((tmp_dir() + "/does-not-exist.stex").c_str(), &m), STEX_INPUT);
  EXPECT_EQ(m, nullptr);  // output handles are NULL on failure
  const std::string message = stex_last_error();
  EXPECT_NE(message.find("stex_model_load: "), std::string::npos) << message;
  EXPECT_NE(message.find("does-not-exist.stex"), std::string::npos) << message;

  // Another thread has its own last error; a failure there does not touch this thread's.
  std::string other_before, other_after;
  std::thread t([&] {
    other_before = stex_last_error();
    stex_context_device_name(nullptr, nullptr);
    other_after = stex_last_error();
  });
  t.join();
  EXPECT_EQ(other_before, "");
  EXPECT_NE(other_after.find("stex_context_device_name"), std::string::npos) << other_after;
  EXPECT_EQ(std::string(stex_last_error()), message);

  // A successful call clears it.
  const char* name = nullptr;
  ASSERT_STEX_OK(stex_context_device_name(context(), &name));
  EXPECT_STREQ(stex_last_error(), "");
  EXPECT_NE(name, nullptr);
}

TEST(CApi, InvalidArgumentsAreRejectedBeforeWork) {
  const stex_model* model = gravel_model();
  stex_context* ctx = context();
  ASSERT_NE(model, nullptr);
  std::vector<float> out(64 * 64, -7.0f);
  stex_render_params p = render_params();
  EXPECT_STEX_STATUS(stex_render(nullptr, model, &p, 0, 0, 8, 8, out.data(), 0, nullptr, nullptr),
                     STEX_INVALID_ARGUMENT);
  EXPECT_NE(std::string(stex_last_error()).find("context is NULL"), std::string::npos);
  EXPECT_STEX_STATUS(stex_render(ctx, nullptr, &p, 0, 0, 8, 8, out.data(), 0, nullptr, nullptr),
                     STEX_INVALID_ARGUMENT);
  EXPECT_STEX_STATUS(stex_render(ctx, model, &p, 0, 0, 8, 8, nullptr, 0, nullptr, nullptr),
                     STEX_INVALID_ARGUMENT);
  // Row strides: below a row, not a multiple of 4.
  EXPECT_STEX_STATUS(stex_render(ctx, model, &p, 0, 0, 8, 8, out.data(), 7 * 4, nullptr, nullptr),
                     STEX_INVALID_ARGUMENT);
  EXPECT_STEX_STATUS(stex_render(ctx, model, &p, 0, 0, 8, 8, out.data(), 8 * 4 + 2, nullptr, nullptr),
                     STEX_INVALID_ARGUMENT);
  // Parameter structs: not initialised, unknown strategy, unknown filter.
  stex_render_params bad = p;
  bad.struct_size = 0;
  EXPECT_STEX_STATUS(stex_render(ctx, model, &bad, 0, 0, 8, 8, out.data(), 0, nullptr, nullptr),
                     STEX_INVALID_ARGUMENT);
  EXPECT_NE(std::string(stex_last_error()).find("struct_size"), std::string::npos);
  bad = p;
  bad.strategy = 7;
  EXPECT_STEX_STATUS(stex_render(ctx, model, &bad, 0, 0, 8, 8, out.data(), 0, nullptr, nullptr),
                     STEX_INVALID_ARGUMENT);
  bad = p;
  bad.filter = 7;
  EXPECT_STEX_STATUS(stex_render(ctx, model, &bad, 0, 0, 8, 8, out.data(), 0, nullptr, nullptr),
                     STEX_INVALID_ARGUMENT);
  // Values out of range are STEX_USAGE and name the parameter.
  bad = p;
  bad.mni = -1.0;
  EXPECT_STEX_STATUS(stex_render(ctx, model, &bad, 0, 0, 8, 8, out.data(), 0, nullptr, nullptr), STEX_USAGE);
  EXPECT_NE(std::string(stex_last_error()).find("mni"), std::string::npos) << stex_last_error();
  bad = p;
  bad.scale = 0.0;
  EXPECT_STEX_STATUS(stex_render(ctx, model, &bad, 0, 0, 8, 8, out.data(), 0, nullptr, nullptr), STEX_USAGE);
  EXPECT_STEX_STATUS(stex_render(ctx, model, &p, 0, 0, 0, 8, out.data(), 0, nullptr, nullptr), STEX_USAGE);
  EXPECT_STEX_STATUS(
      stex_render(ctx, model, &p, std::int64_t(1) << 50, 0, 8, 8, out.data(), 0, nullptr, nullptr),
      STEX_USAGE);
  // Nothing was written by any of these calls.
  for (float v : out) ASSERT_EQ(v, -7.0f);
  // init functions reject sizes below the first version's.
  EXPECT_STEX_STATUS(stex_render_params_init(&p, 8), STEX_INVALID_ARGUMENT);
  EXPECT_STEX_STATUS(stex_render_params_init(nullptr, sizeof p), STEX_INVALID_ARGUMENT);
  stex_context* c = reinterpret_cast<stex_context*>(0x1);
  EXPECT_STEX_STATUS(stex_context_create_from_cl(nullptr, nullptr, nullptr, &c), STEX_INVALID_ARGUMENT);
  EXPECT_EQ(c, nullptr);
  EXPECT_STEX_STATUS(stex_context_create("no-such-device-name-xyz", &c), STEX_DEVICE);
  EXPECT_NE(std::string(stex_last_error()).find("available devices"), std::string::npos) << stex_last_error();
  stex_context_destroy(nullptr);
  stex_model_destroy(nullptr);
}

TEST(CApi, ParameterStructsCarryDefaultsAndEvolve) {
  stex_render_params p;
  std::memset(&p, 0xab, sizeof p);
  ASSERT_STEX_OK(stex_render_params_init(&p, sizeof p));
  EXPECT_EQ(p.struct_size, sizeof p);
  EXPECT_EQ(p.mni, 30.0);
  EXPECT_EQ(p.cell_factor, 0.6);
  EXPECT_EQ(p.scale, 1.0);
  EXPECT_EQ(p.seed, 0u);
  EXPECT_EQ(p.strategy, STEX_STRATEGY_AUTO);
  stex_analysis_params a;
  ASSERT_STEX_OK(stex_analysis_params_init(&a, sizeof a));
  EXPECT_EQ(a.support, 64);
  EXPECT_EQ(a.iterations, 50);
  EXPECT_EQ(a.order, 1);
  EXPECT_EQ(a.colour_correction, 1);
  EXPECT_EQ(a.linear, 0);

  // A caller built against a newer stex passes a larger struct: accepted when the unknown tail is zero.
  struct Newer {
    stex_render_params known;
    double future_field;
  } newer;
  std::memset(&newer, 0xab, sizeof newer);
  ASSERT_STEX_OK(stex_render_params_init(&newer.known, sizeof newer));  // zeroes the fields it does not know
  EXPECT_EQ(newer.known.struct_size, sizeof newer);
  EXPECT_EQ(newer.future_field, 0.0);
  EXPECT_EQ(newer.known.mni, 30.0);
  newer.known.seed = 5;
  const stex_model* model = gravel_model();
  std::vector<float> a_out(16 * 16), b_out(16 * 16);
  const stex_render_params plain = render_params(30.0, 5);
  ASSERT_STEX_OK(stex_render(context(), model, &plain, 3, 4, 16, 16, a_out.data(), 0, nullptr, nullptr));
  ASSERT_STEX_OK(
      stex_render(context(), model, &newer.known, 3, 4, 16, 16, b_out.data(), 0, nullptr, nullptr));
  EXPECT_EQ(bit_differences(a_out, b_out), 0u);
  newer.future_field = 1.0;
  EXPECT_STEX_STATUS(
      stex_render(context(), model, &newer.known, 3, 4, 16, 16, b_out.data(), 0, nullptr, nullptr),
      STEX_INVALID_ARGUMENT);
  // NULL parameters are the defaults.
  ASSERT_STEX_OK(stex_render(context(), model, nullptr, 3, 4, 16, 16, a_out.data(), 0, nullptr, nullptr));
  const stex_render_params defaults = render_params(30.0, 0);
  ASSERT_STEX_OK(stex_render(context(), model, &defaults, 3, 4, 16, 16, b_out.data(), 0, nullptr, nullptr));
  EXPECT_EQ(bit_differences(a_out, b_out), 0u);
}

TEST(CApi, ModelInfoAnalyseSaveLoadRoundTrip) {
  const stex_model* gravel = gravel_model();
  ASSERT_NE(gravel, nullptr);
  stex_model_info info{};
  info.struct_size = sizeof info;
  ASSERT_STEX_OK(stex_model_get_info(gravel, &info));
  EXPECT_EQ(info.channels, 1);
  EXPECT_EQ(info.support, 16);
  EXPECT_EQ(info.iterations, 8);
  EXPECT_EQ(info.exemplar_width, 512);
  EXPECT_EQ(info.exemplar_height, 512);
  EXPECT_GT(info.mean[0], 0.0f);
  EXPECT_EQ(info.mean[1], 0.0f);

  const std::string path = tmp_dir() + "/gravel16.stex";
  ASSERT_STEX_OK(stex_model_save(gravel, path.c_str()));
  stex_model* loaded = nullptr;
  ASSERT_STEX_OK(stex_model_load(path.c_str(), &loaded));
  stex_model_info info2{};
  info2.struct_size = sizeof info2;
  ASSERT_STEX_OK(stex_model_get_info(loaded, &info2));
  EXPECT_EQ(std::memcmp(&info, &info2, sizeof info), 0);
  const stex_render_params p = render_params(25.0, 9);
  EXPECT_EQ(bit_differences(render(context(), gravel, p, -40, 17, 48, 32),
                            render(context(), loaded, p, -40, 17, 48, 32)),
            0u);
  stex_model_destroy(loaded);

  // Saving where no file can be written, loading a corrupt file.
  EXPECT_STEX_STATUS(stex_model_save(gravel, (tmp_dir() + "/no/such/dir/m.stex").c_str()), STEX_OUTPUT);
  const std::string corrupt = tmp_dir() + "/corrupt.stex";
  {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    bytes[bytes.size() / 2] ^= 0x40;
    std::ofstream(corrupt, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  }
  stex_model* m = nullptr;
  EXPECT_STEX_STATUS(stex_model_load(corrupt.c_str(), &m), STEX_INPUT);
  EXPECT_EQ(m, nullptr);

  // An output struct smaller than the first version is refused.
  stex_model_info tiny{};
  tiny.struct_size = 16;
  EXPECT_STEX_STATUS(stex_model_get_info(gravel, &tiny), STEX_INVALID_ARGUMENT);
}

TEST(CApi, AnalysePixelsHonoursStrideAndRejectsBadPixels) {
  const int w = 48, h = 40;
  const std::vector<float> packed = colour_exemplar(w, h);
  // The same pixels with 5 floats of garbage after each row.
  const std::size_t stride_floats = std::size_t(w) * 3 + 5;
  std::vector<float> strided(stride_floats * h, 12345.0f);
  for (int y = 0; y < h; ++y)
    std::memcpy(&strided[std::size_t(y) * stride_floats], &packed[std::size_t(y) * w * 3],
                sizeof(float) * w * 3);
  stex_analysis_params p;
  ASSERT_STEX_OK(stex_analysis_params_init(&p, sizeof p));
  p.support = 8;
  p.iterations = 6;
  stex_model* m = nullptr;
  ASSERT_STEX_OK(stex_model_analyse_pixels(strided.data(), w, h, 3, stride_floats * sizeof(float), &p, &m));
  const stex_render_params rp = render_params(30.0, 3);
  EXPECT_EQ(bit_differences(render(context(), m, rp, 0, 0, 40, 24),
                            render(context(), colour_model(), rp, 0, 0, 40, 24)),
            0u);
  stex_model_info info{};
  info.struct_size = sizeof info;
  ASSERT_STEX_OK(stex_model_get_info(m, &info));
  EXPECT_EQ(info.channels, 3);
  EXPECT_EQ(info.exemplar_width, w);
  EXPECT_EQ(info.exemplar_height, h);
  stex_model_destroy(m);

  // A different seed gives a different model (the analysis is not ignoring its parameters).
  p.seed = 77;
  ASSERT_STEX_OK(stex_model_analyse_pixels(packed.data(), w, h, 3, 0, &p, &m));
  EXPECT_NE(bit_differences(render(context(), m, rp, 0, 0, 16, 16),
                            render(context(), colour_model(), rp, 0, 0, 16, 16)),
            0u);
  stex_model_destroy(m);
  p.seed = 0;

  std::vector<float> bad = packed;
  bad[(5 * w + 7) * 3 + 1] = std::nanf("");
  m = reinterpret_cast<stex_model*>(0x1);
  EXPECT_STEX_STATUS(stex_model_analyse_pixels(bad.data(), w, h, 3, 0, &p, &m), STEX_INPUT);
  EXPECT_EQ(m, nullptr);
  EXPECT_NE(std::string(stex_last_error()).find("pixel (7, 5) channel 1"), std::string::npos)
      << stex_last_error();
  p.pixel_budget = std::uint64_t(w) * h - 1;
  EXPECT_STEX_STATUS(stex_model_analyse_pixels(packed.data(), w, h, 3, 0, &p, &m), STEX_LIMIT);
  p.pixel_budget = std::uint64_t(1) << 26;
  p.support = 64;  // larger than the 48 x 40 exemplar
  EXPECT_STEX_STATUS(stex_model_analyse_pixels(packed.data(), w, h, 3, 0, &p, &m), STEX_INPUT);
  p.support = 8;
  p.iterations = 0;
  EXPECT_STEX_STATUS(stex_model_analyse_pixels(packed.data(), w, h, 3, 0, &p, &m), STEX_USAGE);
  p.iterations = 6;
  EXPECT_STEX_STATUS(stex_model_analyse_pixels(packed.data(), w, h, 5, 0, &p, &m), STEX_INVALID_ARGUMENT);
  EXPECT_STEX_STATUS(stex_model_analyse_pixels(packed.data(), w, h, 3, 4, &p, &m), STEX_INVALID_ARGUMENT);
  EXPECT_STEX_STATUS(stex_model_analyse_file((tmp_dir() + "/missing.png").c_str(), &p, &m), STEX_INPUT);
}

TEST(CApi, RenderStrideTilesAndStrategiesAgreeBitForBit) {
  const stex_model* model = colour_model();
  const int w = 70, h = 45, nc = 3;
  const std::int64_t x0 = -1234567, y0 = 89;
  const stex_render_params p = render_params(20.0, 42);
  const std::vector<float> whole = render(context(), model, p, x0, y0, w, h);
  ASSERT_EQ(whole.size(), std::size_t(w) * h * nc);

  // The texture is not constant (a render of zeros would pass everything else).
  float lo = whole[0], hi = whole[0];
  for (float v : whole) lo = std::min(lo, v), hi = std::max(hi, v);
  EXPECT_GT(hi - lo, 0.05f);

  // Strided output: same pixels, padding untouched.
  const std::size_t stride_floats = std::size_t(w) * nc + 9;
  std::vector<float> strided(stride_floats * h, -99.0f);
  ASSERT_STEX_OK(
      stex_render(context(), model, &p, x0, y0, w, h, strided.data(), stride_floats * 4, nullptr, nullptr));
  for (int j = 0; j < h; ++j) {
    for (std::size_t k = 0; k < std::size_t(w) * nc; ++k)
      ASSERT_EQ(std::memcmp(&strided[j * stride_floats + k], &whole[j * std::size_t(w) * nc + k], 4), 0);
    for (std::size_t k = std::size_t(w) * nc; k < stride_floats; ++k)
      ASSERT_EQ(strided[j * stride_floats + k], -99.0f);
  }

  // Tiles (odd sizes) assemble into the whole, bit for bit.
  std::vector<float> assembled(whole.size());
  for (int ty = 0; ty < h; ty += 17)
    for (int tx = 0; tx < w; tx += 23) {
      const int tw = std::min(23, w - tx), th = std::min(17, h - ty);
      const std::vector<float> tile = render(context(), model, p, x0 + tx, y0 + ty, tw, th);
      for (int j = 0; j < th; ++j)
        std::memcpy(&assembled[((std::size_t(ty) + j) * w + tx) * nc], &tile[std::size_t(j) * tw * nc],
                    sizeof(float) * tw * nc);
    }
  EXPECT_EQ(bit_differences(whole, assembled), 0u);

  // Strategies.
  const std::vector<float> splat =
      render(context(), model, render_params(20.0, 42, STEX_STRATEGY_SPLAT), x0, y0, w, h);
  const std::vector<float> gather =
      render(context(), model, render_params(20.0, 42, STEX_STRATEGY_GATHER), x0, y0, w, h);
  EXPECT_EQ(bit_differences(whole, splat), 0u);
  EXPECT_EQ(bit_differences(whole, gather), 0u);
  // And the seed matters.
  EXPECT_GT(bit_differences(whole, render(context(), model, render_params(20.0, 43), x0, y0, w, h)),
            whole.size() / 2);
}

TEST(CApi, PointQueriesAtPixelCentresEqualTheRender) {
  for (const stex_model* model : {gravel_model(), colour_model()}) {
    const int nc = channels_of(model);
    for (std::int64_t x0 : {std::int64_t(0), std::int64_t(-37), std::int64_t(1000000007)}) {
      const std::int64_t y0 = -x0 / 3 + 5;
      const int w = 33, h = 21;
      const stex_render_params p = render_params(30.0, 7);
      const std::vector<float> img = render(context(), model, p, x0, y0, w, h);
      const std::vector<float> vals = points(context(), model, p, centres(x0, y0, w, h));
      ASSERT_EQ(vals.size(), std::size_t(w) * h * nc);
      EXPECT_EQ(bit_differences(img, vals), 0u) << "x0 = " << x0 << ", channels " << nc;
    }
  }
}

TEST(CApi, PointQueriesRoundToTheFixedPointGrid) {
  // X = round(x * 2^16): an offset of 0.4 / 2^16 from a centre rounds back to it; 1 / 2^16 is the next grid
  // point.
  const stex_model* model = gravel_model();
  const stex_render_params p = render_params(30.0, 2);
  const double u = 1.0 / 65536.0;
  std::vector<double> centre, near, next;
  for (int k = 0; k < 40; ++k) {
    const double x = 3.5 + 7.0 * k, y = -10.5 + 3.0 * k;
    centre.insert(centre.end(), {x, y});
    near.insert(near.end(), {x + 0.4 * u, y - 0.4 * u});
    next.insert(next.end(), {x + u, y});
  }
  const std::vector<float> a = points(context(), model, p, centre), b = points(context(), model, p, near),
                           c = points(context(), model, p, next);
  EXPECT_EQ(bit_differences(a, b), 0u);
  EXPECT_GT(bit_differences(a, c), 20u);  // order 1 is continuous but not flat: the next grid point differs

  // Bad positions: named by index; count 0 is fine.
  std::vector<double> bad = {0.5, 0.5, 1.5, std::nan("")};
  std::vector<float> out(2);
  EXPECT_STEX_STATUS(stex_eval_points(context(), model, &p, 2, bad.data(), out.data()), STEX_USAGE);
  EXPECT_NE(std::string(stex_last_error()).find("point 1: y"), std::string::npos) << stex_last_error();
  bad[3] = 1e15;
  EXPECT_STEX_STATUS(stex_eval_points(context(), model, &p, 2, bad.data(), out.data()), STEX_USAGE);
  ASSERT_STEX_OK(stex_eval_points(context(), model, &p, 0, nullptr, nullptr));
  EXPECT_STEX_STATUS(stex_eval_points(context(), model, &p, 1, nullptr, out.data()), STEX_INVALID_ARGUMENT);
}

namespace {

struct ProgressLog {
  std::vector<double> fractions;
  int cancel_at_call = -1;  // cancel when this many calls were made before (0 = the first call)
};

int record_progress(double fraction, void* user) {
  ProgressLog* log = static_cast<ProgressLog*>(user);
  log->fractions.push_back(fraction);
  return int(log->fractions.size()) - 1 == log->cancel_at_call ? 1 : 0;
}

}  // namespace

TEST(CApi, ProgressReportsAndCancels) {
  const stex_model* model = gravel_model();
  const stex_render_params p = render_params();
  const int w = 96, h = 200;
  std::vector<float> out(std::size_t(w) * h, -5.0f);
  ProgressLog log;
  ASSERT_STEX_OK(stex_render(context(), model, &p, 0, 0, w, h, out.data(), 0, record_progress, &log));
  ASSERT_GE(log.fractions.size(), 4u);
  EXPECT_EQ(log.fractions.front(), 0.0);
  EXPECT_EQ(log.fractions.back(), 1.0);
  for (std::size_t i = 1; i < log.fractions.size(); ++i) EXPECT_GE(log.fractions[i], log.fractions[i - 1]);
  // Chunking for progress does not change a bit.
  EXPECT_EQ(bit_differences(out, render(context(), model, p, 0, 0, w, h)), 0u);

  // Cancel before any work: nothing written.
  std::vector<float> untouched(std::size_t(w) * h, -5.0f);
  ProgressLog cancel_first;
  cancel_first.cancel_at_call = 0;
  EXPECT_STEX_STATUS(
      stex_render(context(), model, &p, 0, 0, w, h, untouched.data(), 0, record_progress, &cancel_first),
      STEX_CANCELLED);
  EXPECT_EQ(cancel_first.fractions.size(), 1u);
  for (float v : untouched) ASSERT_EQ(v, -5.0f);
  EXPECT_NE(std::string(stex_last_error()).find("cancelled"), std::string::npos);

  // Cancel midway: no further callbacks, STEX_CANCELLED; the context stays usable.
  ProgressLog cancel_mid;
  cancel_mid.cancel_at_call = 2;
  EXPECT_STEX_STATUS(
      stex_render(context(), model, &p, 0, 0, w, h, out.data(), 0, record_progress, &cancel_mid),
      STEX_CANCELLED);
  EXPECT_EQ(cancel_mid.fractions.size(), 3u);
  EXPECT_LT(cancel_mid.fractions.back(), 1.0);
  EXPECT_EQ(bit_differences(render(context(), model, p, 0, 0, 8, 8), render(context(), model, p, 0, 0, 8, 8)),
            0u);
}

TEST(CApi, ModelCacheEvictionKeepsResultsRight) {
  // More models than the per-context cache holds, used round robin, against a fresh context per model.
  std::vector<stex_model*> models;
  const std::vector<float> px = colour_exemplar(48, 40);
  for (int k = 0; k < 6; ++k) {
    stex_analysis_params a;
    stex_analysis_params_init(&a, sizeof a);
    a.support = 6 + k;
    a.iterations = 3;
    a.seed = std::uint64_t(k);
    stex_model* m = nullptr;
    ASSERT_STEX_OK(stex_model_analyse_pixels(px.data(), 48, 40, 3, 0, &a, &m));
    models.push_back(m);
  }
  const stex_render_params p = render_params(15.0, 11);
  std::vector<std::vector<float>> expected;
  for (stex_model* m : models) {
    stex_context* fresh = nullptr;
    ASSERT_STEX_OK(stex_context_create(device_spec(), &fresh));
    expected.push_back(render(fresh, m, p, 5, 6, 20, 12));
    stex_context_destroy(fresh);
  }
  for (int round = 0; round < 2; ++round)
    for (std::size_t k = 0; k < models.size(); ++k)
      EXPECT_EQ(bit_differences(render(context(), models[k], p, 5, 6, 20, 12), expected[k]), 0u) << k;
  // Distinct models give distinct images (the cache does not confuse them).
  EXPECT_GT(bit_differences(expected[0], expected[1]), 0u);
  for (stex_model* m : models) stex_model_destroy(m);
  // A new model allocated after the old ones were freed is not confused with them either.
  stex_analysis_params a;
  stex_analysis_params_init(&a, sizeof a);
  a.support = 7;
  a.iterations = 3;
  a.seed = 99;
  stex_model* m = nullptr;
  ASSERT_STEX_OK(stex_model_analyse_pixels(px.data(), 48, 40, 3, 0, &a, &m));
  stex_context* fresh = nullptr;
  ASSERT_STEX_OK(stex_context_create(device_spec(), &fresh));
  EXPECT_EQ(bit_differences(render(context(), m, p, 5, 6, 20, 12), render(fresh, m, p, 5, 6, 20, 12)), 0u);
  stex_context_destroy(fresh);
  stex_model_destroy(m);
}

// The analysis lives in libstex_analysis.so, loaded once per process on the first analysis call
// (capi/analysis_bridge.h). The parent runs this binary again with $STEX_ANALYSIS_LIBRARY naming a missing
// file or a library without the bridge function; in that fresh process (CApiChild.AnalysisUnavailable)
// analysis gives STEX_UNAVAILABLE naming what was tried, every time, while loading a model file still works.
TEST(CApiChild, AnalysisUnavailable) {
  const char* expect = std::getenv("STEX_EMBED_CHILD_EXPECT");
  const char* model_path = std::getenv("STEX_EMBED_CHILD_MODEL");
  if (!expect || !model_path) GTEST_SKIP() << "run by CApi.AnalysisLibraryMissingOrForeignIsUnavailable";
  const std::vector<float> pixels = colour_exemplar(32, 32);
  stex_model* m = reinterpret_cast<stex_model*>(0x1);
  EXPECT_STEX_STATUS(stex_model_analyse_pixels(pixels.data(), 32, 32, 3, 0, nullptr, &m), STEX_UNAVAILABLE);
  EXPECT_EQ(m, nullptr);
  const std::string message = stex_last_error();
  EXPECT_NE(message.find("stex_model_analyse_pixels: the analysis library"), std::string::npos) << message;
  EXPECT_NE(message.find(expect), std::string::npos) << message;
  EXPECT_STEX_STATUS(stex_model_analyse_file("/nonexistent.png", nullptr, &m), STEX_UNAVAILABLE);
  ASSERT_STEX_OK(stex_model_load(model_path, &m));
  const char* kind = nullptr;
  ASSERT_STEX_OK(stex_model_kind(m, &kind));
  EXPECT_STREQ(kind, "texton");
  stex_model_destroy(m);
  if (!::testing::Test::HasFailure()) std::ofstream(std::string(model_path) + ".child-ok") << "ok\n";
}

namespace {

// Runs CApiChild.AnalysisUnavailable in a new process of this binary; its exit status.
int run_child(const std::string& library, const std::string& expect, const std::string& model) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setenv("STEX_ANALYSIS_LIBRARY", library.c_str(), 1);
    ::setenv("STEX_EMBED_CHILD_EXPECT", expect.c_str(), 1);
    ::setenv("STEX_EMBED_CHILD_MODEL", model.c_str(), 1);
    ::execl("/proc/self/exe", "test_embed", "--gtest_filter=CApiChild.AnalysisUnavailable", "--gtest_color=no",
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (!WIFEXITED(status)) return 100 + WTERMSIG(status);
  // The child's test ran to the end (a filter that matched nothing would also exit 0).
  if (WEXITSTATUS(status) == 0 && std::remove((model + ".child-ok").c_str()) != 0) return 99;
  return WEXITSTATUS(status);
}

}  // namespace

TEST(CApi, AnalysisLibraryMissingOrForeignIsUnavailable) {
  EXPECT_STREQ(stex_status_name(STEX_UNAVAILABLE), "STEX_UNAVAILABLE");
  const std::string model = tmp_dir() + "/unavailable_child.stex";
  ASSERT_STEX_OK(stex_model_save(colour_model(), model.c_str()));
  EXPECT_EQ(run_child("/nonexistent/libstex_analysis.so.0", "/nonexistent/libstex_analysis.so.0", model), 0);
  Dl_info self{};
  ASSERT_NE(dladdr(reinterpret_cast<void*>(&stex_version_string), &self), 0);
  EXPECT_EQ(run_child(self.dli_fname, "has no stex_analysis_bridge_v1", model), 0) << self.dli_fname;
}
