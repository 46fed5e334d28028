// Shared helpers of the embedding tests (embed_test_util.h).
#include "embed_test_util.h"

#include <cmath>

namespace stex_embed_test {

stex_context* context() {
  static stex_context* ctx = [] {
    stex_context* c = nullptr;
    if (stex_context_create(device_spec(), &c) != STEX_OK)
      ADD_FAILURE() << "stex_context_create: " << stex_last_error();
    return c;
  }();
  return ctx;
}

const stex_model* gravel_model() {
  static stex_model* model = [] {
    stex_analysis_params p;
    stex_analysis_params_init(&p, sizeof p);
    p.support = 16;
    p.iterations = 8;
    stex_model* m = nullptr;
    if (stex_model_analyse_file(gravel_path().c_str(), &p, &m) != STEX_OK)
      ADD_FAILURE() << "stex_model_analyse_file: " << stex_last_error();
    return m;
  }();
  return model;
}

std::vector<float> colour_exemplar(int width, int height) {
  // Oriented stripes plus a hashed speckle per channel: anisotropic and colourful, deterministic.
  std::vector<float> px(std::size_t(width) * height * 3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) {
        std::uint32_t h =
            std::uint32_t(x) * 73856093u ^ std::uint32_t(y) * 19349663u ^ std::uint32_t(c) * 83492791u;
        h ^= h >> 13;
        h *= 0x5bd1e995u;
        h ^= h >> 15;
        const float speckle = float(h & 0xffff) / 65535.0f;
        px[(std::size_t(y) * width + x) * 3 + c] =
            0.3f + 0.1f * float(c) + 0.2f * std::sin(0.7f * float(x) + 0.3f * float(y) + float(c)) +
            0.1f * speckle;
      }
  return px;
}

const stex_model* colour_model() {
  static stex_model* model = [] {
    const std::vector<float> px = colour_exemplar(48, 40);
    stex_analysis_params p;
    stex_analysis_params_init(&p, sizeof p);
    p.support = 8;
    p.iterations = 6;
    stex_model* m = nullptr;
    if (stex_model_analyse_pixels(px.data(), 48, 40, 3, 0, &p, &m) != STEX_OK)
      ADD_FAILURE() << "stex_model_analyse_pixels: " << stex_last_error();
    return m;
  }();
  return model;
}

std::vector<float> render(stex_context* ctx, const stex_model* model, const stex_render_params& params,
                          std::int64_t x, std::int64_t y, int width, int height) {
  std::vector<float> out(std::size_t(width) * height * channels_of(model));
  const stex_status s =
      stex_render(ctx, model, &params, x, y, width, height, out.data(), 0, nullptr, nullptr);
  if (s != STEX_OK) {
    ADD_FAILURE() << "stex_render: " << stex_status_name(s) << ": " << stex_last_error();
    return {};
  }
  return out;
}

}  // namespace stex_embed_test
