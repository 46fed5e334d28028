/* Peak arithmetic throughput of an OpenCL device, measured (issue #5 "compute floor": the peak is measured on
 * the device, not taken from a catalogue). Used by `stex bench` (benchmarks/lib/fma_peak.h) to turn the
 * FLOP count of texton noise (S1 §8: MNI bilinear taps per pixel) into a time floor.
 *
 * Each work-item runs BENCH_PEAK_CHAINS independent recurrences a <- a * m + c on float16 vectors (16 lanes x
 * 12 accumulators in flight: more than the 4-cycle x 2-port x 16-lane FMA pipeline of an AVX-512 core holds,
 * and plenty for GPU ALUs), `iterations` times, then reduces its accumulators in a fixed order into out[gid],
 * so that nothing is dead code and the host can check the value bit for bit
 * (tests/kernels/test_bench_baselines.cpp).
 *
 * Build option -DBENCH_PEAK_FUSED=1 (default): the step is fma(a, m, c), 2 FLOP per lane in one instruction:
 * the device's peak. -DBENCH_PEAK_FUSED=0: a * m + c with contraction off (pragma below), 2 FLOP in two
 * instructions: the peak of code that may not fuse, like stex's bit-identical texton kernels
 * (docs/ARCHITECTURE.md "Determinism across host and device").
 * FLOP per launch = global size x iterations x BENCH_PEAK_CHAINS x 16 x 2.
 */
#pragma OPENCL FP_CONTRACT OFF

#ifndef BENCH_PEAK_FUSED
#define BENCH_PEAK_FUSED 1
#endif
#define BENCH_PEAK_CHAINS 12

static inline float16 bench_peak_step(float16 a, float16 m, float16 c) {
#if BENCH_PEAK_FUSED
  return fma(a, m, c);
#else
  return a * m + c;
#endif
}

__kernel void bench_peak(const int iterations, const float m, const float c, __global float* out) {
  const uint gid = (uint)get_global_id(0);
  const float16 lanes = (float16)(0.0f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f, 8.0f, 9.0f, 10.0f, 11.0f, 12.0f,
                                  13.0f, 14.0f, 15.0f);
  const float16 vm = (float16)(m), vc = (float16)(c);
  /* Accumulator k, lane l starts at 0.001 l + (0.1 k + 0.01 (gid mod 64)); the host repeats these float ops. */
  const float base = (float)(gid & 63u) * 0.01f;
  float16 a0 = lanes * 0.001f + (float16)(0.0f * 0.1f + base);
  float16 a1 = lanes * 0.001f + (float16)(1.0f * 0.1f + base);
  float16 a2 = lanes * 0.001f + (float16)(2.0f * 0.1f + base);
  float16 a3 = lanes * 0.001f + (float16)(3.0f * 0.1f + base);
  float16 a4 = lanes * 0.001f + (float16)(4.0f * 0.1f + base);
  float16 a5 = lanes * 0.001f + (float16)(5.0f * 0.1f + base);
  float16 a6 = lanes * 0.001f + (float16)(6.0f * 0.1f + base);
  float16 a7 = lanes * 0.001f + (float16)(7.0f * 0.1f + base);
  float16 a8 = lanes * 0.001f + (float16)(8.0f * 0.1f + base);
  float16 a9 = lanes * 0.001f + (float16)(9.0f * 0.1f + base);
  float16 a10 = lanes * 0.001f + (float16)(10.0f * 0.1f + base);
  float16 a11 = lanes * 0.001f + (float16)(11.0f * 0.1f + base);
  for (int it = 0; it < iterations; ++it) {
    a0 = bench_peak_step(a0, vm, vc);
    a1 = bench_peak_step(a1, vm, vc);
    a2 = bench_peak_step(a2, vm, vc);
    a3 = bench_peak_step(a3, vm, vc);
    a4 = bench_peak_step(a4, vm, vc);
    a5 = bench_peak_step(a5, vm, vc);
    a6 = bench_peak_step(a6, vm, vc);
    a7 = bench_peak_step(a7, vm, vc);
    a8 = bench_peak_step(a8, vm, vc);
    a9 = bench_peak_step(a9, vm, vc);
    a10 = bench_peak_step(a10, vm, vc);
    a11 = bench_peak_step(a11, vm, vc);
  }
  /* Fixed reduction order: accumulators 0..11 lane-wise, then lanes 0..15. */
  float16 s = a0 + a1;
  s = s + a2;
  s = s + a3;
  s = s + a4;
  s = s + a5;
  s = s + a6;
  s = s + a7;
  s = s + a8;
  s = s + a9;
  s = s + a10;
  s = s + a11;
  float r = s.s0;
  r += s.s1;
  r += s.s2;
  r += s.s3;
  r += s.s4;
  r += s.s5;
  r += s.s6;
  r += s.s7;
  r += s.s8;
  r += s.s9;
  r += s.sa;
  r += s.sb;
  r += s.sc;
  r += s.sd;
  r += s.se;
  r += s.sf;
  out[gid] = r;
}
