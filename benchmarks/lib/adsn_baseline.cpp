// ADSN by FFT per frame, host (FFTW float, threads) and device (clFFT). See adsn_baseline.h.
#include "benchmarks/lib/adsn_baseline.h"

#include <fftw3.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <mutex>
#include <vector>

#include "analysis/fft.h"
#include "analysis/gaussian_model.h"
#include "core/error.h"
#include "kernels/shared/rng.h"
#include "runtime/buffer.h"
#include "runtime/program.h"

#if __has_include("analysis/device_fft.h")
#include "analysis/device_fft.h"
#define STEX_BENCH_DEVICE_FFT 1
#else
#define STEX_BENCH_DEVICE_FFT 0
#endif

namespace stex::bench {
namespace {

constexpr std::uint32_t k_noise_domain = 0x41444e42u;  // "ADNB", as kernels/bench_adsn.cl

// FFTW's planner is not thread-safe; its single-precision library is used by nothing else in stex.
std::mutex& fftwf_planner_mutex() {
  static std::mutex m;
  return m;
}

// Standard normal of domain pixel (px, py): the same draw as bench_adsn_noise (std:: transcendentals).
float white_noise(std::int64_t px, std::int64_t py, std::uint32_t seed_lo, std::uint32_t seed_hi) {
  const stex_uvec4 v = stex_draw(stex_cell_key(px, py), seed_lo, seed_hi, 0u, k_noise_domain);
  const float u1 = (float(v.x >> 8) + 0.5f) * 5.9604644775390625e-8f;
  const float u2 = float(v.y >> 8) * 5.9604644775390625e-8f;
  return std::sqrt(-2.0f * std::log(u1)) * std::cos(6.28318530718f * u2);
}

// t_u of the exemplar embedded at the origin of a dw x dh domain, per channel (planar, double).
std::vector<double> embedded_kernel(const NormalisedKernel& tu, int dw, int dh) {
  std::vector<double> out(std::size_t(dw) * std::size_t(dh) * std::size_t(tu.channels), 0.0);
  const std::size_t plane = std::size_t(tu.width) * std::size_t(tu.height);
  for (int c = 0; c < tu.channels; ++c)
    for (int j = 0; j < tu.height; ++j)
      for (int i = 0; i < tu.width; ++i)
        out[(std::size_t(c) * dh + std::size_t(j)) * dw + std::size_t(i)] =
            tu.t[std::size_t(c) * plane + std::size_t(j) * tu.width + std::size_t(i)];
  return out;
}

}  // namespace

struct AdsnFftwBaseline::Impl {
  int width = 0, height = 0, dw = 0, dh = 0, hw = 0, channels = 0, threads = 1;
  std::array<double, 4> mean{};
  float* real = nullptr;
  fftwf_complex* noise_hat = nullptr;
  fftwf_complex* product = nullptr;
  std::vector<std::complex<float>> kernel_hat;  // channels x (hw x dh), already divided by dw * dh
  fftwf_plan forward = nullptr, inverse = nullptr;
};

AdsnFftwBaseline::AdsnFftwBaseline(const Image& exemplar, int width, int height, int threads)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const NormalisedKernel tu = normalised_kernel(exemplar, true);
  m.width = width;
  m.height = height;
  m.dw = std::max(width, tu.width);
  m.dh = std::max(height, tu.height);
  m.hw = m.dw / 2 + 1;
  m.channels = tu.channels;
  m.threads = threads > 0 ? threads : omp_get_max_threads();
  m.mean = tu.mean;
  const std::size_t n = std::size_t(m.dw) * std::size_t(m.dh), nh = std::size_t(m.hw) * std::size_t(m.dh);
  m.real = fftwf_alloc_real(n);
  m.noise_hat = fftwf_alloc_complex(nh);
  m.product = fftwf_alloc_complex(nh);
  if (!m.real || !m.noise_hat || !m.product) throw Error(ErrorKind::Limit, "ADSN baseline: out of memory");
  {
    std::lock_guard<std::mutex> lock(fftwf_planner_mutex());
    static const int init = fftwf_init_threads();
    (void)init;
    fftwf_plan_with_nthreads(m.threads);
    fftwf_set_timelimit(2.0);
    m.forward = fftwf_plan_dft_r2c_2d(m.dh, m.dw, m.real, m.noise_hat, FFTW_MEASURE);
    m.inverse = fftwf_plan_dft_c2r_2d(m.dh, m.dw, m.product, m.real, FFTW_MEASURE);
  }
  if (!m.forward || !m.inverse) throw Error(ErrorKind::Internal, "ADSN baseline: FFTW planning failed");
  // FFT of the embedded t_u per channel (double, analysis/fft.h), scaled by 1/N for the unnormalised c2r.
  const std::vector<double> t = embedded_kernel(tu, m.dw, m.dh);
  m.kernel_hat.resize(nh * std::size_t(m.channels));
  std::vector<Complex> hat(nh);
  for (int c = 0; c < m.channels; ++c) {
    fft2d_r2c(m.dw, m.dh, t.data() + std::size_t(c) * n, hat.data());
    for (std::size_t k = 0; k < nh; ++k)
      m.kernel_hat[std::size_t(c) * nh + k] = std::complex<float>(hat[k] / double(n));
  }
}

AdsnFftwBaseline::~AdsnFftwBaseline() {
  Impl& m = *impl_;
  std::lock_guard<std::mutex> lock(fftwf_planner_mutex());
  if (m.forward) fftwf_destroy_plan(m.forward);
  if (m.inverse) fftwf_destroy_plan(m.inverse);
  fftwf_free(m.real);
  fftwf_free(m.noise_hat);
  fftwf_free(m.product);
}

int AdsnFftwBaseline::channels() const { return impl_->channels; }

void AdsnFftwBaseline::render(std::uint64_t seed, float* planar) {
  Impl& m = *impl_;
  const std::uint32_t lo = stex_lo32(std::int64_t(seed)), hi = stex_hi32(std::int64_t(seed));
  const int dw = m.dw, dh = m.dh;
  float* real = m.real;
#pragma omp parallel for num_threads(m.threads) schedule(static)
  for (int j = 0; j < dh; ++j)
    for (int i = 0; i < dw; ++i) real[std::size_t(j) * dw + i] = white_noise(i, j, lo, hi);
  fftwf_execute(m.forward);
  const std::size_t nh = std::size_t(m.hw) * std::size_t(dh);
  const std::size_t plane = std::size_t(m.width) * std::size_t(m.height);
  auto* noise = reinterpret_cast<std::complex<float>*>(m.noise_hat);
  auto* prod = reinterpret_cast<std::complex<float>*>(m.product);
  for (int c = 0; c < m.channels; ++c) {
    const std::complex<float>* kh = m.kernel_hat.data() + std::size_t(c) * nh;
#pragma omp parallel for num_threads(m.threads) schedule(static)
    for (std::ptrdiff_t k = 0; k < std::ptrdiff_t(nh); ++k) prod[k] = noise[k] * kh[k];
    fftwf_execute(m.inverse);
    const float mean = float(m.mean[std::size_t(c)]);
    float* out = planar + std::size_t(c) * plane;
    const int width = m.width;
#pragma omp parallel for num_threads(m.threads) schedule(static)
    for (int j = 0; j < m.height; ++j)
      for (int i = 0; i < width; ++i) out[std::size_t(j) * width + i] = mean + real[std::size_t(j) * dw + i];
  }
}

#if STEX_BENCH_DEVICE_FFT

bool adsn_device_available() { return true; }

struct AdsnDeviceBaseline::Impl {
  Context* ctx = nullptr;
  int width = 0, height = 0, dw = 0, dh = 0, channels = 0;
  std::array<double, 4> mean{};
  std::unique_ptr<DeviceFft> fft;
  Buffer<cl_float2> noise, product, kernel_hat;
  Buffer<float> out;
  std::unique_ptr<Kernel> k_noise, k_multiply, k_finish;
  DeviceFft::Backend backend = DeviceFft::Backend::ClFft;
};

AdsnDeviceBaseline::AdsnDeviceBaseline(Context& ctx, const Image& exemplar, int width, int height)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const NormalisedKernel tu = normalised_kernel(exemplar, true);
  m.ctx = &ctx;
  m.width = width;
  m.height = height;
  m.dw = std::max(width, tu.width);
  m.dh = std::max(height, tu.height);
  m.channels = tu.channels;
  m.mean = tu.mean;
  const std::size_t n = std::size_t(m.dw) * std::size_t(m.dh);
  const std::vector<double> t = embedded_kernel(tu, m.dw, m.dh);
  std::vector<cl_float2> hat_f(n * std::size_t(m.channels));
  std::vector<Complex> hat(n);
  for (int c = 0; c < m.channels; ++c) {
    for (std::size_t k = 0; k < n; ++k) hat[k] = Complex(t[std::size_t(c) * n + k], 0.0);
    fft2d_forward(m.dw, m.dh, hat);
    for (std::size_t k = 0; k < n; ++k) hat_f[std::size_t(c) * n + k] = cl_float2{{float(hat[k].real()), float(hat[k].imag())}};
  }
  m.fft = std::make_unique<DeviceFft>(ctx);
  m.noise = Buffer<cl_float2>(ctx, n, CL_MEM_READ_WRITE, "ADSN noise");
  m.product = Buffer<cl_float2>(ctx, n, CL_MEM_READ_WRITE, "ADSN product");
  m.kernel_hat = Buffer<cl_float2>(ctx, hat_f, CL_MEM_READ_ONLY, "ADSN kernel spectrum");
  m.out = Buffer<float>(ctx, std::size_t(width) * std::size_t(height) * std::size_t(m.channels), CL_MEM_READ_WRITE,
                        "ADSN output");
  Program& program = ctx.program("bench_adsn.cl");
  m.k_noise = std::make_unique<Kernel>(program, "bench_adsn_noise");
  m.k_multiply = std::make_unique<Kernel>(program, "bench_adsn_multiply");
  m.k_finish = std::make_unique<Kernel>(program, "bench_adsn_finish");
}

AdsnDeviceBaseline::~AdsnDeviceBaseline() = default;

double AdsnDeviceBaseline::render(std::uint64_t seed, float* planar) {
  Impl& m = *impl_;
  Context& ctx = *m.ctx;
  auto round_up = [](std::size_t v, std::size_t q) { return (v + q - 1) / q * q; };
  const std::size_t n = std::size_t(m.dw) * std::size_t(m.dh);
  const std::size_t plane = std::size_t(m.width) * std::size_t(m.height);
  const auto t0 = std::chrono::steady_clock::now();
  m.k_noise->set_arg(0, cl_uint(stex_lo32(std::int64_t(seed))));
  m.k_noise->set_arg(1, cl_uint(stex_hi32(std::int64_t(seed))));
  m.k_noise->set_arg(2, cl_int(0));
  m.k_noise->set_arg(3, cl_int(0));
  m.k_noise->set_arg(4, cl_int(m.dw));
  m.k_noise->set_arg(5, cl_int(m.dh));
  m.k_noise->set_arg(6, m.noise);
  m.k_noise->launch(ctx, NDRange(round_up(std::size_t(m.dw), 16), round_up(std::size_t(m.dh), 4)), NDRange(16, 4));
  m.backend = m.fft->transform(m.dw, m.dh, m.noise.get(), false);
  for (int c = 0; c < m.channels; ++c) {
    m.k_multiply->set_arg(0, m.noise);
    m.k_multiply->set_arg(1, m.kernel_hat);
    m.k_multiply->set_arg(2, cl_int(std::size_t(c) * n));
    m.k_multiply->set_arg(3, m.product);
    m.k_multiply->set_arg(4, cl_int(n));
    m.k_multiply->launch(ctx, NDRange(round_up(n, 64)), NDRange(64));
    m.backend = m.fft->transform(m.dw, m.dh, m.product.get(), true);
    m.k_finish->set_arg(0, m.product);
    m.k_finish->set_arg(1, cl_int(m.dw));
    m.k_finish->set_arg(2, cl_int(m.width));
    m.k_finish->set_arg(3, cl_int(m.height));
    m.k_finish->set_arg(4, cl_float(float(m.mean[std::size_t(c)])));
    m.k_finish->set_arg(5, m.out);
    m.k_finish->set_arg(6, cl_int(std::size_t(c) * plane));
    m.k_finish->launch(ctx, NDRange(round_up(std::size_t(m.width), 16), round_up(std::size_t(m.height), 4)),
                       NDRange(16, 4));
  }
  ctx.finish();
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (planar) m.out.read(planar, plane * std::size_t(m.channels));
  return ms;
}

std::string AdsnDeviceBaseline::backend() const {
  return impl_->backend == DeviceFft::Backend::ClFft ? "clFFT" : "FFTW fallback";
}

#else

bool adsn_device_available() { return false; }
struct AdsnDeviceBaseline::Impl {};
AdsnDeviceBaseline::AdsnDeviceBaseline(Context&, const Image&, int, int) {
  throw Error(ErrorKind::Device, "ADSN on the device needs analysis/device_fft.h (clFFT), which this build lacks");
}
AdsnDeviceBaseline::~AdsnDeviceBaseline() = default;
double AdsnDeviceBaseline::render(std::uint64_t, float*) { return 0.0; }
std::string AdsnDeviceBaseline::backend() const { return "none"; }

#endif

}  // namespace stex::bench
