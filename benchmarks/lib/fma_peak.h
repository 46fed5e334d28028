// The device's peak float throughput, measured with kernels/bench_fma_peak.cl (issue #5 "compute floor":
// measured on the device, not a catalogue number). Two figures: the FMA peak (fma(a, m, c): 2 FLOP per lane
// per instruction; the device's peak) and the mul+add peak without contraction (the ceiling of stex's
// bit-identical kernels, which may not fuse). Method: 12 independent float16 recurrences per work-item,
// 8192 work-items, the iteration count calibrated so that one launch takes ~40 ms; best of `repeats`
// launches by profiling events. FLOP = work-items x iterations x 12 x 16 x 2.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "runtime/context.h"

namespace stex::bench {

struct PeakResult {
  double gflops_fma = 0;     // GFLOP/s, FMA counted as 2 FLOP
  double gflops_muladd = 0;  // GFLOP/s, separate mul and add
  double ms_fma = 0, ms_muladd = 0;  // best launch
  std::size_t work_items = 0;
  int iterations_fma = 0, iterations_muladd = 0;
};

PeakResult measure_peak(Context& ctx, int repeats = 3);

// One launch of the peak kernel (fused or mul+add) with `work_items` work-items; returns out[] and the device
// time. FLOP of the launch: peak_flops(work_items, iterations).
std::vector<float> run_peak_kernel(Context& ctx, bool fused, std::size_t work_items, int iterations, float m, float c,
                                   double* device_ms = nullptr);
double peak_flops(std::size_t work_items, int iterations);

// What work-item `gid` must write, computed on the host with the same float operations (std::fma for the
// fused kernel; separate, unfused mul and add otherwise): the kernel's correctness check.
float peak_expected(bool fused, std::uint32_t gid, int iterations, float m, float c);

}  // namespace stex::bench
