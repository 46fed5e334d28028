// Peak float throughput by the FMA micro-kernel (kernels/bench_fma_peak.cl). See fma_peak.h.
#include "benchmarks/lib/fma_peak.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "core/error.h"
#include "runtime/buffer.h"
#include "runtime/program.h"

namespace stex::bench {
namespace {
constexpr int k_chains = 12, k_lanes = 16;
constexpr std::size_t k_work_items = 8192;
constexpr double k_target_ms = 40.0;
}  // namespace

double peak_flops(std::size_t work_items, int iterations) {
  return double(work_items) * double(iterations) * k_chains * k_lanes * 2.0;
}

std::vector<float> run_peak_kernel(Context& ctx, bool fused, std::size_t work_items, int iterations, float m, float c,
                                   double* device_ms) {
  Kernel kernel(ctx.program("bench_fma_peak.cl", fused ? "-DBENCH_PEAK_FUSED=1" : "-DBENCH_PEAK_FUSED=0"),
                "bench_peak");
  Buffer<float> out(ctx, work_items, CL_MEM_WRITE_ONLY, "peak output");
  kernel.set_arg(0, cl_int(iterations));
  kernel.set_arg(1, cl_float(m));
  kernel.set_arg(2, cl_float(c));
  kernel.set_arg(3, out);
  const double ms = kernel.launch(ctx, NDRange(work_items));
  if (device_ms) *device_ms = ms;
  return out.read();
}

float peak_expected(bool fused, std::uint32_t gid, int iterations, float m, float c) {
  // -ffp-contract=off (top-level CMakeLists.txt) keeps a * m + c unfused on the host.
  const float base = float(gid & 63u) * 0.01f;
  float lane_sum[k_lanes] = {};
  for (int l = 0; l < k_lanes; ++l) {
    float acc[k_chains];
    for (int k = 0; k < k_chains; ++k) {
      const float init_k = float(k) * 0.1f + base;
      acc[k] = float(l) * 0.001f + init_k;
    }
    for (int it = 0; it < iterations; ++it)
      for (int k = 0; k < k_chains; ++k) {
        if (fused) {
          acc[k] = std::fma(acc[k], m, c);
        } else {
          const float prod = acc[k] * m;
          acc[k] = prod + c;
        }
      }
    float s = acc[0] + acc[1];
    for (int k = 2; k < k_chains; ++k) s = s + acc[k];
    lane_sum[l] = s;
  }
  float r = lane_sum[0];
  for (int l = 1; l < k_lanes; ++l) r += lane_sum[l];
  return r;
}

PeakResult measure_peak(Context& ctx, int repeats) {
  PeakResult res;
  res.work_items = k_work_items;
  // m < 1 keeps the recurrence bounded (it converges to c / (1 - m)): no overflow, no denormals.
  const float m = 0.999f, c = 0.001f;
  for (int fused = 1; fused >= 0; --fused) {
    // Calibrate: a short launch (it also pays the first-launch compile), then scale to ~k_target_ms.
    int iterations = 64;
    double ms = 0;
    run_peak_kernel(ctx, fused != 0, k_work_items, iterations, m, c, &ms);
    run_peak_kernel(ctx, fused != 0, k_work_items, iterations, m, c, &ms);
    iterations = int(std::clamp(double(iterations) * k_target_ms / std::max(ms, 1e-3), 64.0, 1e6));
    double best = 1e300;
    std::vector<float> out;
    for (int r = 0; r < std::max(1, repeats); ++r) {
      out = run_peak_kernel(ctx, fused != 0, k_work_items, iterations, m, c, &ms);
      best = std::min(best, ms);
    }
    // The FLOP count holds only if every iteration ran: a driver that cuts loops short (Mesa's llvmpipe caps
    // an invocation at 65535 loop passes, docs/portability.md root cause 9) would report a false peak.
    for (std::uint32_t gid : {0u, 63u, std::uint32_t(k_work_items - 1)})
      if (out[gid] != peak_expected(fused != 0, gid, iterations, m, c))
        throw Error(ErrorKind::Device, "the compute-floor kernel (kernels/bench_fma_peak.cl, " +
                                           std::to_string(iterations) + " iterations) computed a wrong value on "
                                           "this device: its loops were cut short or it rounds differently, so "
                                           "its peak would be false (docs/portability.md)");
    const double gflops = peak_flops(k_work_items, iterations) / (best * 1e6);
    if (fused) {
      res.gflops_fma = gflops;
      res.ms_fma = best;
      res.iterations_fma = iterations;
    } else {
      res.gflops_muladd = gflops;
      res.ms_muladd = best;
      res.iterations_muladd = iterations;
    }
  }
  return res;
}

}  // namespace stex::bench
