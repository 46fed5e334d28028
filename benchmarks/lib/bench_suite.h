// The `stex bench` suite (issue #5): the MNI / texton support / output size trade-off of texton noise
// (S1 §3.3 "Shot noise evaluation cost", §8, §9 Table 1) measured on one OpenCL device, side by side with the
// alternatives, and reported as tables, JSON, CSV, Markdown and an SVG plot (benchmarks/lib/bench_report.h).
//
// Per point (output size, texton support, MNI) it measures the stex default (the auto strategy of
// runtime/texton_renderer.h): device ms (OpenCL profiling events), wall ms (render() end to end: launch,
// read-back, interleave), fps and Mpixel/s from the device time, and the quality of the render against the
// Gaussian model (benchmarks/lib/quality.h: spectrum error against ADSN, excess kurtosis). At the comparison
// points (MNI in `compare_mni`) it also measures, on the same device or the same host:
//   splat, gather       stex's two strategies (bit-identical outputs, so their quality is the default's)
//   s1                  S1 §8 as published (kernels/bench_s1_baseline.cl: per-pixel regeneration, Gaussian counts)
//   omp                 the same tile-splat algorithm in plain C++ with OpenMP on the host's threads
//                       (benchmarks/lib/omp_splat.h; checked bit-identical to the stex render in the run)
//   adsn-fftw           ADSN by FFT on the host (FFTW float, threads; benchmarks/lib/adsn_baseline.h)
//   adsn-device         ADSN by FFT on the device (clFFT via analysis/device_fft.h)
//   dsn                 DSN on Z^2 (analysis/gaussian_synthesis.h, host, one thread)
//   tb, cs-tb           issue #8: tiling and blending of the same exemplar at its defaults (tile min(w, h) / 6;
//                       cs-tb with periods (32, 0), (0, 32)), device time of runtime/tb.h's two passes; it
//                       depends on neither MNI nor support, so its ratio to the texton default of the same
//                       point (size, device) is the "tb <= 0.3 x texton noise" (goal 4)
//   cs-spot             issue #8 (S4 §5.1): cyclostationary spot noise of the same exemplar (periods (32, 0),
//                       (0, 32), runtime/cs_spot.h), device time. No speed goal: its ratio to the texton default
//                       is reported. Its frame is at most k_cs_spot_bench_side pixels a side (a full 1024^2
//                       frame costs seconds on a CPU device); when smaller than the point's, its
//                       Measurement::frame_* say so and its ratio is per pixel (see Measurement)
//   cs-rpn-*            issue #8 (S4 §4.2, Fig. 1 left, Fig. 4): cyclostationary random-phase noise from user
//                       spectra (runtime/cs_rpn.h), one key per variant (random-phase, gabor, phasor, fourier;
//                       `--compare cs-rpn` names all four): periods (128, 0), (0, 128), 2 x 1 spectra (bi-lobes
//                       at 0 and 90 degrees, F = 0.09, W = 0.008, T = 64; the tool's defaults otherwise), device
//                       time, no speed goal (ratios reported as a note), a frame of at most
//                       k_cs_spot_bench_side a side as cs-spot. Gabor and phasor depend on the point's MNI
//                       (their impulses per kernel area), random-phase and fourier on neither MNI nor support
// Each measurement: one untimed warm-up (kernel compilation, plans), then up to `repeat` timed runs, stopped
// early once their total passes `budget_ms`; the median is reported. The compared time of an OpenCL strategy
// is its device time; of a host strategy, its wall time. Ratios are time / (stex default's time), where a
// baseline's runs alternate with runs of the stex default and the ratio uses those (ref_ms): on a shared or
// virtualised machine whose speed drifts, both sides of a ratio then see the same conditions.
// The device's peak is measured at the start and at the end of the run; the larger is reported and used.
//
// Compute floor: FLOP per pixel of the algorithm = MNI x (8 C + 6) + 3 C for C channels: each of the MNI
// impulses covering a pixel costs, per channel, the bilinear fetch (4 mul + 3 add) and the accumulation
// (1 add), and its weights (1 - fx)(1 - fy), fx(1 - fy), (1 - fx) fy, fx fy (2 sub + 4 mul); the final
// normalisation mean + (acc - lambda sum alpha) / sqrt(lambda) is 3 per channel. Hashing, counting and
// coordinate arithmetic are not counted (they are what a good strategy amortises). Floor = FLOP / the device's
// measured FMA peak (benchmarks/lib/fma_peak.h); a strategy's fraction of the floor = floor / its time.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "benchmarks/lib/fma_peak.h"
#include "benchmarks/lib/worker_affinity.h"
#include "runtime/context.h"

namespace stex::bench {

enum class Strategy {
  Default, Splat, Gather, S1, Omp, AdsnFftw, AdsnDevice, Dsn, Tb, CsTb, CsSpot,
  CsRpnRandomPhase, CsRpnGabor, CsRpnPhasor, CsRpnFourier, Gabor, GaborFiltered8, GaborFiltered64, Lrp, LrpFiltered8,
  CsRpnRandomPhaseFiltered8, CsRpnGaborFiltered8, TextonFiltered8, TextonFiltered64, Mix, MixFiltered8
};

// "stex", "splat", "gather", "s1", "omp", "adsn-fftw", "adsn-device", "dsn", "tb", "cs-tb", "cs-spot",
// "cs-rpn-random-phase", "cs-rpn-gabor", "cs-rpn-phasor", "cs-rpn-fourier", "gabor", "gabor-filtered-8",
// "gabor-filtered-64" (the default Gabor model at scale 1, and filtered at scales 1/8 and 1/64: the cost of
// filtering is the ratio of these rows, same output size), "lrp", "lrp-filtered-8" (the default LRP analysis
// of the exemplar at scale 1 and filtered at 1/8), "cs-rpn-random-phase-filtered-8", "cs-rpn-gabor-filtered-8" (the
// cs-rpn rows' models filtered at 1/8).
const char* strategy_key(Strategy s);
// Human-readable label ("S1 as published (per pixel)", ...).
const char* strategy_label(Strategy s);
// Parses a key (not "stex"); throws stex::Error(Usage) listing the valid keys.
Strategy parse_strategy(const std::string& key);
// The strategies a --compare item names: "cs-rpn" the four cs-rpn variants, any other key its strategy.
std::vector<Strategy> parse_strategies(const std::string& key);
// The baselines, in report order.
const std::vector<Strategy>& all_baselines();

struct OutputSize {
  int width = 0, height = 0;
};
// "1024x1024", "1920x1080", ...; and the short names "1024" (1024x1024), "hd" (1920x1080), "4k" (3840x2160).
OutputSize parse_output_size(const std::string& text);
std::string size_label(const OutputSize& s);  // "1024^2", "HD", "4K" or "WxH"

// The axes.
const std::vector<double>& all_mni();          // 1 2 4 8 16 30 60 120
const std::vector<int>& all_supports();        // 32 64 128 256
const std::vector<OutputSize>& all_sizes();    // 1024^2, HD, 4K

struct BenchConfig {
  std::vector<double> mni{1, 4, 16, 30, 120};
  std::vector<int> supports{32, 64, 128, 256};
  std::vector<OutputSize> sizes{{1024, 1024}};
  std::string exemplar = "data/gravel.png";
  int repeat = 5;
  double budget_ms = 1500;
  // Paired measurements (a baseline against the stex default): time each run after an untimed run of the same
  // strategy (warm caches, as in a sequence of its own frames). false: strict alternation, each frame right
  // after the other strategy's (`stex bench --cold-pairs`).
  bool warm_pairs = true;
  std::vector<Strategy> compare = all_baselines();
  std::vector<double> compare_mni{30};  // empty: compare at every point
  bool table1 = true;  // add S1 Table 1's points (1024^2, HD, 4K x supports 64, 256 at MNI 30; default only)
  bool quality = true;
  std::uint64_t seed = 1;
  int analysis_iterations = 50;
  // What the caller did about worker threads before it created the device (pin_pocl_workers; `stex bench`
  // pins unless --no-pin). run_bench copies it into the report, pins the OpenMP pool alike and counts.
  WorkerAffinity workers;
};

// The bench frame of cs-spot and cs-rpn: at most this many pixels a side (origin (0, 0), as the point's frame).
inline constexpr int k_cs_spot_bench_side = 256;

// The short configuration of --quick: 1024^2, support 64, MNI 30, every baseline, 2 runs, no Table 1.
BenchConfig quick_config();

struct Measurement {
  Strategy strategy = Strategy::Default;
  std::string label;  // for the default: "stex (splat)" etc.
  bool ok = false;
  std::string note;   // error message, or a remark (backend, bit-identity)
  double ms = 0;      // compared time (device ms for OpenCL strategies, wall for host strategies), median
  double device_ms = -1;  // profiling-event time (OpenCL strategies), else -1
  double wall_ms = 0;     // median wall time end to end
  // Baselines: the stex default's median time measured in alternation with this baseline's runs (default,
  // baseline, default, baseline, ...; with BenchConfig::warm_pairs each timed run after an untimed one of the
  // same strategy), so that both see the same machine; ratios use it. 0: not paired.
  double ref_ms = 0;
  // The minima of the same runs (ms_min of the compared times, ref_min_ms of the paired default's; 0: not
  // measured / not paired). Interference on a shared machine only adds time, and on the 2-vCPU VMs of this
  // project it is bimodal frame by frame (a frame runs at one worker's speed when the second vCPU is not
  // there: docs/benchmarks.md), so the ratio of minima is the steadier estimate of the code's own cost;
  // the goals are judged on the medians and the minima are reported beside them.
  double ms_min = 0, ref_min_ms = 0;
  // The frame this strategy rendered, when smaller than the point's (cs-spot, cs-rpn: k_cs_spot_bench_side); 0: the
  // point's. Then fps and Mpixel/s are of this frame, and the ratio to the default is per pixel:
  // (ms / frame pixels) / (default ms / point pixels).
  int frame_width = 0, frame_height = 0;
  int runs = 0;
  double spectrum_error = -1;  // -1: not measured
  double kurtosis = 0;
  bool has_quality = false;
};

struct BenchPoint {
  OutputSize size;
  int support = 0;
  double mni = 0;
  bool table1_only = false;  // added for Table 1 (not on the configured grid)
  double flops = 0;          // algorithm FLOP for the frame (see the header)
  std::vector<Measurement> results;  // results[0] is the stex default
};

struct MachineInfo {
  std::string cpu;  // /proc/cpuinfo "model name"
  int host_threads = 0;
  std::string device, device_type, platform, driver;
  unsigned compute_units = 0;
  WorkerAffinity workers;  // PoCL / OpenMP worker pinning of the run (worker_affinity.h)
};

struct Goal {
  std::string name, target;
  bool applicable = false;  // measured, and on the kind of device the goal is about
  bool met = false;
  double value = 0;
  std::string detail;
};

struct TextonInfo {
  int support = 0;
  double analysis_ms = 0, rme = 0, variance_kept = 0;
};

struct BenchReport {
  MachineInfo machine;
  PeakResult peak;
  BenchConfig config;
  std::string default_strategy;  // what auto resolves to on the device
  int channels = 0;
  std::string exemplar_desc;
  std::vector<TextonInfo> textons;
  std::vector<BenchPoint> points;
  std::vector<Goal> goals;
  std::vector<std::string> notes;
  double total_seconds = 0;
};

double flops_per_pixel(double mni, int channels);

// Time of m relative to the point's stex default: m.ms / m.ref_ms when paired, else over the point's default;
// per pixel when m rendered a smaller frame (Measurement::frame_*). 0 when there is no default.
double time_vs_default(const BenchPoint& p, const Measurement& m);
// Pixels of the frame m rendered (the point's unless Measurement::frame_* are set).
double frame_pixels(const BenchPoint& p, const Measurement& m);

// Runs the suite. `progress` (may be empty) receives one line per measurement.
BenchReport run_bench(Context& ctx, const BenchConfig& config,
                      const std::function<void(const std::string&)>& progress = {});

// Recomputes report.goals from report.points (run_bench calls it; exposed for tests of the report).
void evaluate_goals(BenchReport& report);

}  // namespace stex::bench
