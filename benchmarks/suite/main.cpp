// `stex bench [--mni LIST] [--support LIST] [--size LIST] [--exemplar PATH] [--repeat N] [--json FILE]
//  [--csv FILE] [--svg FILE] [--markdown FILE] [--compare LIST] [--compare-mni LIST] [--no-table1] [--quick]
//  [--cold-pairs] [--no-pin]
//  [--full]`: the MNI / texton support / output size trade-off of texton noise (S1 §3.3, §8, §9 Table 1) on the
// selected OpenCL device, side by side with the baselines, with the compute floor and the goals
// (issue #5). The program `stex-bench`, which `stex bench` runs (cli/bench.cpp), so that the suite and its
// baselines (OpenMP, FFTW) are not linked into `stex`. A thin client of benchmarks/lib/bench_suite.h and
// bench_report.h: parse, run, print, write. docs/benchmarks.md explains every column and how to reproduce the
// published numbers.
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "benchmarks/lib/bench_report.h"
#include "benchmarks/lib/bench_suite.h"
#include "cli/app_main.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "runtime/context.h"
#include "runtime/device.h"

namespace stex::cli {
namespace {

struct BenchCliOptions {
  std::string mni, support, size, compare, compare_mni, exemplar = "data/gravel.png";
  std::string json, csv, svg, markdown;
  int repeat = 5;
  double budget_ms = 1500;
  std::uint64_t seed = 1;
  bool quick = false, full = false, no_table1 = false, no_quality = false, cold_pairs = false, no_pin = false;
};

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(s);
  while (std::getline(in, item, ',')) {
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

double parse_number(const std::string& s, const char* what) {
  try {
    std::size_t used = 0;
    const double v = std::stod(s, &used);
    if (used == s.size()) return v;
  } catch (const std::exception&) {
  }
  throw Error(ErrorKind::Usage, std::string(what) + ": '" + s + "' is not a number");
}

std::vector<double> parse_mni_list(const std::string& s, const char* what) {
  std::vector<double> out;
  for (const std::string& item : split_list(s)) out.push_back(parse_number(item, what));
  if (out.empty()) throw Error(ErrorKind::Usage, std::string(what) + " needs at least one value");
  return out;
}

void write_text(const std::string& path, const std::string& text) {
  write_file_atomic(path, text.data(), text.size());
}

void run_bench_cli(const BenchCliOptions& o, const GlobalOptions& global) {
  using namespace stex::bench;
  BenchConfig cfg = o.quick ? quick_config() : BenchConfig{};
  if (o.full) {
    cfg.mni = all_mni();
    cfg.supports = all_supports();
    cfg.sizes = all_sizes();
    cfg.compare_mni.clear();
  }
  if (!o.mni.empty()) cfg.mni = parse_mni_list(o.mni, "--mni");
  if (!o.support.empty()) {
    cfg.supports.clear();
    for (const std::string& item : split_list(o.support)) {
      const double v = parse_number(item, "--support");
      if (v != double(int(v)) || v < 1) throw Error(ErrorKind::Usage, "--support: '" + item + "' is not a positive integer");
      cfg.supports.push_back(int(v));
    }
  }
  if (!o.size.empty()) {
    cfg.sizes.clear();
    for (const std::string& item : split_list(o.size)) cfg.sizes.push_back(parse_output_size(item));
  }
  if (!o.compare.empty()) {
    cfg.compare.clear();
    for (const std::string& item : split_list(o.compare)) {
      if (item == "all") {
        cfg.compare = all_baselines();
      } else if (item != "none") {
        for (Strategy st : parse_strategies(item)) cfg.compare.push_back(st);
      }
    }
  }
  if (!o.compare_mni.empty()) cfg.compare_mni = o.compare_mni == "all" ? std::vector<double>{}
                                                                         : parse_mni_list(o.compare_mni, "--compare-mni");
  if (o.repeat < 1) throw Error(ErrorKind::Usage, "--repeat must be at least 1");
  if (!o.quick || o.repeat != 5) cfg.repeat = o.repeat;
  cfg.warm_pairs = !o.cold_pairs;
  if (o.budget_ms != 1500) cfg.budget_ms = o.budget_ms;
  if (o.no_table1) cfg.table1 = false;
  if (o.no_quality) cfg.quality = false;
  cfg.exemplar = o.exemplar;
  cfg.seed = o.seed;

  // Before the process's first OpenCL call: PoCL reads POCL_AFFINITY when it creates the device.
  cfg.workers = pin_pocl_workers(!o.no_pin);
  std::unique_ptr<Context> ctx = Context::create(global.device);
  auto progress = [&](const std::string& line) {
    if (!global.quiet) std::fprintf(stderr, "stex bench: %s\n", line.c_str());
  };
  const BenchReport report = run_bench(*ctx, cfg, progress);
  if (!o.json.empty()) write_text(o.json, to_json(report));
  if (!o.csv.empty()) write_text(o.csv, to_csv(report));
  if (!o.svg.empty()) write_text(o.svg, to_svg(report));
  if (!o.markdown.empty()) write_text(o.markdown, to_markdown(report));
  if (!global.quiet) std::fputs(format_terminal(report).c_str(), stdout);
}

void add_bench_options(CLI::App& app, GlobalOptions& global) {
  app.description(
      "Measure texton noise on the selected device across MNI, texton support and output size: ms per frame "
      "(device and wall), fps, Mpixel/s, quality against the Gaussian model (spectrum error vs ADSN, excess "
      "kurtosis), the fraction of the device's compute floor, side by side with stex's strategies, S1 as "
      "published, a plain C++ OpenMP splat, ADSN by FFT and DSN; reports the issue's goals. Default run (about "
      "a minute on 2 cores): 1024x1024, supports 32,64,128,256, MNI 1,4,16,30,120, baselines at MNI 30, plus "
      "S1's Table 1 points (1024^2, HD, 4K x supports 64, 256 at MNI 30). See docs/benchmarks.md.");
  CLI::App* sub = &app;
  auto o = std::make_shared<BenchCliOptions>();
  sub->add_option("--mni", o->mni, "MNI values, comma-separated (default 1,4,16,30,120; the issue's axis: "
                                   "1,2,4,8,16,30,60,120)");
  sub->add_option("--support", o->support, "Texton supports, comma-separated (default 32,64,128,256)");
  sub->add_option("--size", o->size,
                  "Output sizes, comma-separated: WxH, N (NxN), hd (1920x1080), 4k (3840x2160) (default 1024x1024)");
  sub->add_option("--exemplar", o->exemplar, "Exemplar the textons are analysed from (default data/gravel.png)");
  sub->add_option("--repeat", o->repeat, "Timed runs per measurement after one warm-up; the median is reported "
                                         "(the JSON adds the minimum; default 5)");
  sub->add_option("--budget-ms", o->budget_ms,
                  "Stop repeating a measurement once its timed runs exceed this many ms (default 1500)");
  sub->add_option("--compare", o->compare,
                  "Baselines: splat,gather,s1,omp,adsn-fftw,adsn-device,dsn,tb,cs-tb (tiling and blending, issue #8), "
                  "cs-spot (cyclostationary spot noise, issue #8; on a frame of at most 256x256), "
                  "cs-rpn-random-phase,cs-rpn-gabor,cs-rpn-phasor,cs-rpn-fourier or cs-rpn for the four (cs random-phase "
                  "noise from fixed spectra, issue #8; at most 256x256), gabor,gabor-filtered-8,gabor-filtered-64 (the "
                  "default Gabor model at scale 1 and filtered at scales 1/8 and 1/64: the cost of filtering; at most "
                  "256x256), lrp,lrp-filtered-8 (the default LRP analysis of the exemplar at scale 1 and filtered at 1/8; at "
                  "most 256x256), cs-rpn-random-phase-filtered-8,cs-rpn-gabor-filtered-8 (those cs-rpn models filtered at "
                  "1/8), texton-filtered-8,texton-filtered-64 (the point's texton at scales 1/8 and 1/64 through the box "
                  "prefilter, over the full output size), mix,mix-filtered-8 (the exemplar mixed with its transpose, 17 "
                  "levels, at scale 1 and filtered at 1/8; at most 256x256), all or none (default all)");
  sub->add_option("--compare-mni", o->compare_mni, "MNI values at which the baselines run, or all (default 30)");
  sub->add_option("--seed", o->seed, "Seed of the renders (default 1)");
  sub->add_option("--json", o->json, "Write the full report as JSON");
  sub->add_option("--csv", o->csv, "Write one CSV row per (point, strategy)");
  sub->add_option("--svg", o->svg, "Write the plot of fps against quality, one curve per texton support (SVG)");
  sub->add_option("--markdown", o->markdown, "Write the tables as Markdown (docs/bench/)");
  sub->add_flag("--no-table1", o->no_table1, "Skip S1's Table 1 points (HD and 4K)");
  sub->add_flag("--no-quality", o->no_quality, "Skip the quality measures");
  sub->add_flag("--cold-pairs", o->cold_pairs,
                "Time each baseline run right after a run of the stex default and vice versa (strict alternation: "
                "each frame starts with the other's data in the caches); default: each timed run follows an "
                "untimed run of the same strategy");
  sub->add_flag("--no-pin", o->no_pin,
                "Leave PoCL's worker threads (and the OpenMP baseline's) free to migrate; default: POCL_AFFINITY=1 "
                "(worker i on CPU i; the environment's POCL_AFFINITY wins) when the process may use every CPU, "
                "since a guest scheduler that packs threads onto one vCPU makes frame times bimodal "
                "(docs/benchmarks.md)");
  sub->add_flag("--quick", o->quick, "A short run: 1024x1024, support 64, MNI 30, every baseline, 2 runs");
  sub->add_flag("--full", o->full, "The issue's full axes: every MNI, support and size, baselines everywhere "
                                   "(tens of minutes on 2 cores)");
  sub->callback([o, &global] { run_bench_cli(*o, global); });
}

}  // namespace
}  // namespace stex::cli

int main(int argc, char** argv) {
  stex::configure_kernel_cache();
  CLI::App app{"", "stex bench"};
  stex::cli::GlobalOptions global;
  stex::cli::add_global_options(app, global);
  stex::cli::add_bench_options(app, global);
  return stex::cli::run_app(app, argc, argv, "stex bench");
}
