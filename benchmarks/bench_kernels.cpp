// Kernel-level Google Benchmarks (issue #5): one frame of 1024x1024 at MNI 30 with the texton of support 64
// analysed from the bundled exemplar (S1 Algorithm 1), for each evaluation strategy and baseline:
//   TextonSplat, TextonGather   stex's kernels (runtime/texton_renderer.h), device time (profiling events)
//   TextonGatherLocal           the gather with a work-group sharing its tile's impulses in local memory (the
//                               GPU default). On PoCL's CPU device it is slow, as expected - about as slow as
//                               TextonGather and ~100x the splat: local memory is ordinary RAM and its two
//                               barriers cost (docs/benchmarks.md); the figure is for comparison with a GPU
//                               run (STEX_DEVICE=gpu)
//   TextonSplatBlocks/S/B       the splat with S x B-pixel blocks per work-item (the renderer's default: 256 x 16)
//   S1Baseline                  S1 §8 as published (kernels/bench_s1_baseline.cl), device time
//   OmpSplat                    the plain C++ OpenMP tile splat on the host's threads, wall time
//   AdsnFftw, AdsnDevice        ADSN by FFT (FFTW float on the host; clFFT on the device), wall time
//   Dsn                         DSN on Z^2 (analysis/gaussian_synthesis.h), wall time
//   Tb, CsTb, CsSpot            tiling and blending (stationary, cyclostationary) and CS spot noise of the same
//                               exemplar (periods 32 x 32 for the CS kinds), 1024^2, device time (issue #8: tb <= 0.3 x
//                               TextonSplat); TbPixel: tb's per-pixel kernel (its GPU path) instead of the run
//                               kernel; Tb8, Tb16: the run kernel forced to 8 / 16 lanes; TbUnaligned: tb at
//                               scale 0.999 (bilinear fetches; TbUnalignedPixel: its per-pixel kernel); CsTbPixel: cs-tb's per-pixel kernel; CsTbSubpixel: periods 32.5 x 32.5; CsTbHist:
//                               cs-tb with the CS histogram transfer (per-pixel kernel)
//   PeakFma, PeakMulAdd         the device's peak micro-kernel (kernels/bench_fma_peak.cl), device time
// Device strategies report manual time (the kernel's device time), so the figures compare with `stex bench`.
// Counters: Mpixel/s (pixels per second / 1e6), for the peak kernels GFLOP/s, and for the splats cpu_ms (CPU
// time of the whole process per frame, all threads: the work of a frame, steadier than elapsed time when other
// processes share the cores; also for Tb, CsTb, CsSpot). With
// --benchmark_repetitions=N a "min" statistic (the least disturbed repetition) joins mean/median/stddev.
// Environment: STEX_DEVICE selects the device (as the CLI); STEX_BENCH_EXEMPLAR overrides the exemplar;
// STEX_BENCH_NO_PIN leaves the worker threads unpinned (else as `stex bench`: benchmarks/lib/worker_affinity.h).
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "analysis/gaussian_synthesis.h"
#include "analysis/image_io.h"
#include "analysis/texton.h"
#include "benchmarks/lib/adsn_baseline.h"
#include "benchmarks/lib/fma_peak.h"
#include "benchmarks/lib/lrp_baseline.h"
#include "analysis/lrp.h"
#include "runtime/lrp_renderer.h"
#include "benchmarks/lib/omp_splat.h"
#include "benchmarks/lib/s1_baseline.h"
#include "benchmarks/lib/worker_affinity.h"
#include "runtime/context.h"
#include "runtime/texton_params.h"
#include "runtime/texton_renderer.h"
#include "analysis/cs_spot_model.h"
#include "analysis/tb_model.h"
#include "runtime/cs_spot.h"
#include "runtime/tb.h"

namespace {

constexpr int k_size = 1024;
constexpr int k_support = 64;
constexpr double k_mni = 30.0;

// Worker pinning of the run (main(): as `stex bench`, unless STEX_BENCH_NO_PIN is set).
stex::bench::WorkerAffinity g_workers;

struct Fixture {
  std::unique_ptr<stex::Context> ctx;
  stex::Image exemplar;
  stex::TextonModel model;
  stex::RenderParams params;
  std::unique_ptr<stex::TextonRenderer> renderer;
  std::vector<float> image;

  Fixture() {
    const char* dev = std::getenv("STEX_DEVICE");
    ctx = stex::Context::create(dev ? dev : "");
    const char* ex = std::getenv("STEX_BENCH_EXEMPLAR");
    exemplar = stex::load_exemplar(ex ? ex : STEX_SOURCE_DIR "/data/gravel.png");
    stex::TextonParams tp;
    tp.support = k_support;
    model = stex::analyse_texton(exemplar, tp);
    params.mni = k_mni;
    params.seed = 1;
    renderer = std::make_unique<stex::TextonRenderer>(*ctx, model);
    image.resize(std::size_t(k_size) * k_size * std::size_t(model.channels));
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

// CPU time of the whole process (every thread: PoCL's workers, OpenMP's) in ms: on a shared machine the
// work a frame costs, less sensitive than elapsed time to other processes taking the cores.
double process_cpu_ms() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return (double(u.ru_utime.tv_sec) + double(u.ru_stime.tv_sec)) * 1e3 +
         (double(u.ru_utime.tv_usec) + double(u.ru_stime.tv_usec)) * 1e-3;
}

// Adds the counter "cpu_ms": process CPU ms per iteration since `start`.
void set_cpu(benchmark::State& state, double start) {
  state.counters["cpu_ms"] =
      benchmark::Counter((process_cpu_ms() - start) / double(std::max<std::int64_t>(1, state.iterations())));
}

void set_pixels(benchmark::State& state) {
  state.counters["Mpixel/s"] = benchmark::Counter(double(k_size) * k_size * 1e-6 * double(state.iterations()),
                                                  benchmark::Counter::kIsRate);
}

void texton(benchmark::State& state, stex::TextonStrategy strategy, int strip = 0, int band = 0) {
  Fixture& f = fixture();
  stex::TextonRenderOptions opt;
  opt.strategy = strategy;
  if (strip > 0) opt.splat_strip = strip;
  if (band > 0) opt.splat_band = band;
  f.renderer->render(f.params, 0, 0, k_size, k_size, f.image.data(), opt);  // warm-up (compilation)
  const double cpu0 = process_cpu_ms();
  for (auto _ : state) {
    const stex::TextonRenderStats st = f.renderer->render(f.params, 0, 0, k_size, k_size, f.image.data(), opt);
    state.SetIterationTime(st.device_ms / 1000.0);
  }
  set_cpu(state, cpu0);
  set_pixels(state);
}

void BM_TextonSplat(benchmark::State& state) { texton(state, stex::TextonStrategy::Splat); }
void BM_TextonGather(benchmark::State& state) { texton(state, stex::TextonStrategy::Gather); }
void BM_TextonGatherLocal(benchmark::State& state) { texton(state, stex::TextonStrategy::GatherLocal); }
// The splat's block shape (strip x band pixels per work-item): outputs never depend on it, speed does.
void BM_TextonSplatBlocks(benchmark::State& state) {
  texton(state, stex::TextonStrategy::Splat, int(state.range(0)), int(state.range(1)));
}

// LRP noise (issue #7): J = 50, L = 4, r = 0 on the exemplar, 512^2 pixels, PoCL kernel (device time) vs
// the plain C++ -ffast-math OpenMP build of the same algorithm (benchmarks/lib/lrp_baseline.h, wall time on
// the host's threads). docs/lrp.md reports the ratio.
constexpr int k_lrp_size = 512;
struct LrpFixture {
  std::unique_ptr<stex::Context> ctx;
  stex::LrpModel model;
  stex::RenderParams params;
  std::unique_ptr<stex::LrpNoise> renderer;
  std::vector<float> image;
  LrpFixture() {
    const char* dev = std::getenv("STEX_DEVICE");
    ctx = stex::Context::create(dev ? dev : "");
    const char* ex = std::getenv("STEX_BENCH_EXEMPLAR");
    stex::LrpParams lp;  // S3's model (J = 50, L = 4, uniform amplitudes), as docs/lrp.md's measurements
    lp.amplitudes = stex::LrpAmplitudes::Paper;
    lp.strata = 4;
    model = stex::analyse_lrp(stex::load_exemplar(ex ? ex : STEX_SOURCE_DIR "/data/gravel.png"), lp);
    params.seed = 1;
    renderer = std::make_unique<stex::LrpNoise>(*ctx, model);
    image.resize(std::size_t(k_lrp_size) * k_lrp_size * std::size_t(model.channels));
  }
};
LrpFixture& lrp_fixture() {
  static LrpFixture f;
  return f;
}
void lrp_pixels(benchmark::State& state) {
  state.counters["Mpixel/s"] = benchmark::Counter(double(k_lrp_size) * k_lrp_size * 1e-6 * double(state.iterations()),
                                                  benchmark::Counter::kIsRate);
}
void BM_LrpDevice(benchmark::State& state) {
  LrpFixture& f = lrp_fixture();
  f.renderer->render(f.params, 0, 0, k_lrp_size, k_lrp_size, f.image.data());  // warm-up (compilation)
  for (auto _ : state)
    state.SetIterationTime(f.renderer->render(f.params, 0, 0, k_lrp_size, k_lrp_size, f.image.data()).device_ms / 1000.0);
  lrp_pixels(state);
}
void BM_LrpFastMath(benchmark::State& state) {
  LrpFixture& f = lrp_fixture();
  const stex::LrpSetup setup = stex::make_lrp_setup(f.model, f.params);
  for (auto _ : state) stex::bench::lrp_fastmath_render(setup, 0, 0, k_lrp_size, k_lrp_size, f.image.data());
  lrp_pixels(state);
}
void BM_LrpFastMathPolyCos(benchmark::State& state) {  // the baseline with the kernel's cos/sin polynomial
  LrpFixture& f = lrp_fixture();
  const stex::LrpSetup setup = stex::make_lrp_setup(f.model, f.params);
  for (auto _ : state) stex::bench::lrp_fastmath_polycos_render(setup, 0, 0, k_lrp_size, k_lrp_size, f.image.data());
  lrp_pixels(state);
}

// Issue #8: tiling and blending and CS spot noise, 1024^2 on the exemplar of the texton benchmarks (the CS
// kinds with periods (32, 0), (0, 32): speed does not depend on whether the exemplar is really periodic).
void noise_kind(benchmark::State& state, stex::NoiseRenderer& r) {
  Fixture& f = fixture();
  r.render(f.params, 0, 0, k_size, k_size, f.image.data());  // warm-up (compilation)
  const double cpu0 = process_cpu_ms();
  for (auto _ : state) state.SetIterationTime(r.render(f.params, 0, 0, k_size, k_size, f.image.data()).device_ms / 1000.0);
  set_cpu(state, cpu0);
  set_pixels(state);
}
const stex::Lattice k_bench_periods{32.0, 0.0, 0.0, 32.0};
void BM_Tb(benchmark::State& state) {
  static stex::TbNoise r(*fixture().ctx, stex::tb_from_exemplar(fixture().exemplar, stex::TbParams{}));
  noise_kind(state, r);
}
// The run kernel forced to 8 lanes (float8); BM_Tb picks 16 on tiles of >= 16 pixels.
void BM_Tb8(benchmark::State& state) {
  static stex::TbNoise r(*fixture().ctx, stex::tb_from_exemplar(fixture().exemplar, stex::TbParams{}));
  r.run_lanes = 8;
  noise_kind(state, r);
}
// ... and forced to 16 lanes (float16: BM_Tb's choice here, whatever the device's vector width).
void BM_Tb16(benchmark::State& state) {
  static stex::TbNoise r(*fixture().ctx, stex::tb_from_exemplar(fixture().exemplar, stex::TbParams{}));
  r.run_lanes = 16;
  noise_kind(state, r);
}
// tb's per-pixel kernel (the GPU path, TbNoise::run_mode = 0) on the same device, and at scale 0.999 (not
// aligned: 3 bilinear fetches of 4 texels; tb's renders at any scale but 1).
void BM_TbPixel(benchmark::State& state) {
  static stex::TbNoise r(*fixture().ctx, stex::tb_from_exemplar(fixture().exemplar, stex::TbParams{}));
  r.run_mode = 0;
  noise_kind(state, r);
}
// Frames of r at scale 0.999 (not aligned: bilinear fetches), device time.
void tb_at_unaligned_scale(benchmark::State& state, stex::TbNoise& r) {
  Fixture& f = fixture();
  stex::RenderParams p = f.params;
  p.scale = 0.999;
  r.render(p, 0, 0, k_size, k_size, f.image.data());
  const double cpu0 = process_cpu_ms();
  for (auto _ : state) state.SetIterationTime(r.render(p, 0, 0, k_size, k_size, f.image.data()).device_ms / 1000.0);
  set_cpu(state, cpu0);
  set_pixels(state);
}
void BM_TbUnaligned(benchmark::State& state) {
  static stex::TbNoise r(*fixture().ctx, stex::tb_from_exemplar(fixture().exemplar, stex::TbParams{}));
  tb_at_unaligned_scale(state, r);
}
// ... and tb's general per-pixel kernel at that scale (the GPU path; the CPU path before the run kernel took
// bilinear fetches).
void BM_TbUnalignedPixel(benchmark::State& state) {
  static stex::TbNoise r(*fixture().ctx, stex::tb_from_exemplar(fixture().exemplar, stex::TbParams{}));
  r.run_mode = 0;
  tb_at_unaligned_scale(state, r);
}
void BM_CsTb(benchmark::State& state) {
  static stex::TbNoise r(*fixture().ctx, stex::tb_from_exemplar(fixture().exemplar, stex::TbParams{}, &k_bench_periods));
  noise_kind(state, r);
}
// cs-tb with sub-pixel periods (as --estimate-periods gives): bilinear fetches, the run kernel's general path.
void BM_CsTbSubpixel(benchmark::State& state) {
  static const stex::Lattice periods{32.5, 0.0, 0.0, 32.5};
  static stex::TbNoise r(*fixture().ctx, stex::tb_from_exemplar(fixture().exemplar, stex::TbParams{}, &periods));
  noise_kind(state, r);
}
// cs-tb's aligned per-pixel kernel (the GPU path; the CPU path before cs-tb's run kernel) on the same device.
void BM_CsTbPixel(benchmark::State& state) {
  static stex::TbNoise r(*fixture().ctx, stex::tb_from_exemplar(fixture().exemplar, stex::TbParams{}, &k_bench_periods));
  r.run_mode = 0;
  noise_kind(state, r);
}
// cs-tb with the cyclostationary histogram transfer (S4 §5.3.2, δ = 1): T_P(x)^-1 instead of the LUT (the
// per-pixel kernel: the run kernel has no CS histogram path).
void BM_CsTbHist(benchmark::State& state) {
  static stex::TbNoise r(*fixture().ctx, [] {
    stex::TbParams p;
    p.histogram = 2;
    return stex::tb_from_exemplar(fixture().exemplar, p, &k_bench_periods);
  }());
  noise_kind(state, r);
}
void BM_CsSpot(benchmark::State& state) {
  static stex::CsSpotNoise r(*fixture().ctx, stex::cs_spot_from_exemplar(fixture().exemplar, k_bench_periods));
  noise_kind(state, r);
}

void BM_S1Baseline(benchmark::State& state) {
  Fixture& f = fixture();
  stex::bench::S1BaselineRenderer s1(*f.ctx, f.model);
  s1.render(k_mni, 1, 0, 0, k_size, k_size, nullptr);
  for (auto _ : state) state.SetIterationTime(s1.render(k_mni, 1, 0, 0, k_size, k_size, nullptr) / 1000.0);
  set_pixels(state);
}

void BM_OmpSplat(benchmark::State& state) {
  Fixture& f = fixture();
  const stex::TextonSetup setup = stex::make_texton_setup(f.model, f.params);
  stex::bench::OmpSplatOptions opt;
  opt.tile = int(state.range(0));
  const double cpu0 = process_cpu_ms();
  const stex::bench::ScopedPinToCpu0 pin(g_workers.openmp_pinned);  // one thread per CPU, as PoCL's workers
  for (auto _ : state) stex::bench::omp_splat_render(setup, 0, 0, k_size, k_size, f.image.data(), opt);
  set_cpu(state, cpu0);
  set_pixels(state);
}

void BM_AdsnFftw(benchmark::State& state) {
  Fixture& f = fixture();
  stex::bench::AdsnFftwBaseline adsn(f.exemplar, k_size, k_size);
  for (auto _ : state) adsn.render(1, f.image.data());
  set_pixels(state);
}

void BM_AdsnDevice(benchmark::State& state) {
  Fixture& f = fixture();
  if (!stex::bench::adsn_device_available()) {
    state.SkipWithError("no device FFT in this build (analysis/device_fft.h)");
    return;
  }
  stex::bench::AdsnDeviceBaseline adsn(*f.ctx, f.exemplar, k_size, k_size);
  adsn.render(1, nullptr);
  for (auto _ : state) state.SetIterationTime(adsn.render(1, nullptr) / 1000.0);
  set_pixels(state);
}

void BM_Dsn(benchmark::State& state) {
  Fixture& f = fixture();
  for (auto _ : state) benchmark::DoNotOptimize(stex::synthesize_dsn(f.model, 0, 0, k_size, k_size, k_mni, 1));
  set_pixels(state);
}

void peak(benchmark::State& state, bool fused) {
  Fixture& f = fixture();
  const std::size_t items = 8192;
  const int iterations = 2048;
  stex::bench::run_peak_kernel(*f.ctx, fused, items, iterations, 0.999f, 0.001f);
  double flops = 0;
  for (auto _ : state) {
    double ms = 0;
    stex::bench::run_peak_kernel(*f.ctx, fused, items, iterations, 0.999f, 0.001f, &ms);
    state.SetIterationTime(ms / 1000.0);
    flops += stex::bench::peak_flops(items, iterations);
  }
  state.counters["GFLOP/s"] = benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsRate);
}
void BM_PeakFma(benchmark::State& state) { peak(state, true); }
void BM_PeakMulAdd(benchmark::State& state) { peak(state, false); }

// The fastest repetition (with --benchmark_repetitions=N): on a shared machine the least disturbed run.
double min_of(const std::vector<double>& v) { return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end()); }

}  // namespace

BENCHMARK(BM_TextonSplat)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_TextonSplatBlocks)
    ->Args({256, 16})
    ->Args({128, 32})
    ->Args({128, 64})
    ->Args({256, 64})
    ->Args({64, 64})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->ComputeStatistics("min", min_of);
BENCHMARK(BM_TextonGather)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(3)->ComputeStatistics("min", min_of);
BENCHMARK(BM_TextonGatherLocal)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(3)->ComputeStatistics("min", min_of);
BENCHMARK(BM_S1Baseline)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(3)->ComputeStatistics("min", min_of);
BENCHMARK(BM_OmpSplat)->Arg(64)->Arg(128)->Arg(256)->UseRealTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_AdsnFftw)->UseRealTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_AdsnDevice)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_Dsn)->UseRealTime()->Unit(benchmark::kMillisecond)->Iterations(3)->ComputeStatistics("min", min_of);
BENCHMARK(BM_PeakFma)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_PeakMulAdd)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);

BENCHMARK(BM_LrpDevice)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(5)->ComputeStatistics("min", min_of);
BENCHMARK(BM_LrpFastMath)->UseRealTime()->Unit(benchmark::kMillisecond)->Iterations(5)->ComputeStatistics("min", min_of);
BENCHMARK(BM_LrpFastMathPolyCos)->UseRealTime()->Unit(benchmark::kMillisecond)->Iterations(5)->ComputeStatistics("min", min_of);

BENCHMARK(BM_Tb)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_Tb8)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_Tb16)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_TbPixel)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_TbUnaligned)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_TbUnalignedPixel)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_CsTb)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_CsTbSubpixel)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_CsTbPixel)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_CsTbHist)->UseManualTime()->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);
BENCHMARK(BM_CsSpot)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(2)->ComputeStatistics("min", min_of);

int main(int argc, char** argv) {
  // Before any OpenCL call (the fixture creates the device on first use).
  g_workers = stex::bench::pin_pocl_workers(std::getenv("STEX_BENCH_NO_PIN") == nullptr);
  stex::bench::pin_openmp_threads(g_workers);
  benchmark::AddCustomContext("worker_threads", stex::bench::describe(g_workers));
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
