// Host side of the S1-as-published baseline kernel (S1 §8). See s1_baseline.h and kernels/bench_s1_baseline.cl.
#include "benchmarks/lib/s1_baseline.h"

#include <cmath>
#include <string>

#include "core/error.h"
#include "runtime/texton_params.h"

namespace stex::bench {
namespace {
constexpr std::size_t k_local_x = 16, k_local_y = 4;  // as stex's gather (runtime/texton_renderer.cpp)
std::size_t round_up(std::size_t v, std::size_t m) { return (v + m - 1) / m * m; }
}  // namespace

S1Constants s1_constants(const TextonModel& model, double mni) {
  S1Constants k;
  k.r = double(model.support + model.order);
  k.lambda = mni / (k.r * k.r);
  k.cell = k.r / 1.6;
  k.cell_mean = k.lambda * k.cell * k.cell;
  return k;
}

S1BaselineRenderer::S1BaselineRenderer(Context& ctx, const TextonModel& model) : ctx_(ctx), model_(model) {
  validate_texton_model(model_);
  if (model_.order != 1) throw Error(ErrorKind::Usage, "the S1 baseline evaluates bilinear textons (order 1) only");
  // The padded planes are the renderer's (one (s+2)^2 plane per channel, zero frame of 1).
  const TextonSetup setup = make_texton_setup(model_, RenderParams{});
  alpha_ = Buffer<float>(ctx_, setup.alpha_padded, CL_MEM_READ_ONLY, "S1 baseline alpha");
  const std::size_t n = std::size_t(model_.support) * std::size_t(model_.support);
  for (int c = 0; c < model_.channels; ++c) {
    double s = 0;
    for (std::size_t i = 0; i < n; ++i) s += double(model_.alpha[std::size_t(c) * n + i]);
    sum_alpha_[std::size_t(c)] = s;
  }
  kernel_ = std::make_unique<Kernel>(
      ctx_.program("bench_s1_baseline.cl", "-DS1_CHANNELS=" + std::to_string(model_.channels)), "bench_s1_baseline");
}

double S1BaselineRenderer::render(double mni, std::uint32_t seed, int x0, int y0, int width, int height,
                                  float* planar) {
  validate_render_params(RenderParams{mni, 0.6, 0, 1.0});
  validate_region(x0, y0, width, height);
  const S1Constants k = s1_constants(model_, mni);
  const std::size_t count = std::size_t(width) * std::size_t(height) * std::size_t(model_.channels);
  if (out_.size() < count) out_ = Buffer<float>(ctx_, count, CL_MEM_WRITE_ONLY, "S1 baseline output");
  cl_float4 mean{}, lsa{};
  for (int c = 0; c < model_.channels; ++c) {
    mean.s[c] = model_.mean[std::size_t(c)];
    lsa.s[c] = float(k.lambda * sum_alpha_[std::size_t(c)]);
  }
  cl_uint a = 0;
  kernel_->set_arg(a++, alpha_);
  kernel_->set_arg(a++, cl_int(model_.support + 2));
  kernel_->set_arg(a++, cl_float(-1.0f));                  // t_lo: the bilinear texton reaches [-1, s)
  kernel_->set_arg(a++, cl_float(float(model_.support)));  // t_hi
  kernel_->set_arg(a++, cl_float(float(k.cell)));
  kernel_->set_arg(a++, cl_float(float(1.0 / k.cell)));
  kernel_->set_arg(a++, cl_float(float(k.cell_mean)));
  kernel_->set_arg(a++, cl_float(float(std::sqrt(k.cell_mean))));
  kernel_->set_arg(a++, cl_uint(seed));
  kernel_->set_arg(a++, cl_float(float(1.0 / std::sqrt(k.lambda))));
  kernel_->set_arg(a++, mean);
  kernel_->set_arg(a++, lsa);
  kernel_->set_arg(a++, cl_int(x0));
  kernel_->set_arg(a++, cl_int(y0));
  kernel_->set_arg(a++, cl_int(width));
  kernel_->set_arg(a++, cl_int(height));
  kernel_->set_arg(a++, cl_int(width));  // pitch
  kernel_->set_arg(a++, out_);
  const double ms = kernel_->launch(ctx_, NDRange(round_up(std::size_t(width), k_local_x), round_up(std::size_t(height), k_local_y)),
                                    NDRange(k_local_x, k_local_y));
  if (planar) out_.read(planar, count);
  return ms;
}

std::vector<float> S1BaselineRenderer::render_interleaved(double mni, std::uint32_t seed, int x0, int y0, int width,
                                                          int height, double* device_ms) {
  const int nc = model_.channels;
  const std::size_t plane = std::size_t(width) * std::size_t(height);
  std::vector<float> planar(plane * std::size_t(nc)), out(planar.size());
  const double ms = render(mni, seed, x0, y0, width, height, planar.data());
  if (device_ms) *device_ms = ms;
  for (std::size_t i = 0; i < plane; ++i)
    for (int c = 0; c < nc; ++c) out[i * std::size_t(nc) + std::size_t(c)] = planar[std::size_t(c) * plane + i];
  return out;
}

}  // namespace stex::bench
