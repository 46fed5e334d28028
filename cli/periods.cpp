// `stex periods`: the period vectors of a near-regular exemplar (S4 §6, analysis/cs_lattice.h), for a user to
// check before analysing and rendering with a cyclostationary method:
//   stex periods EXEMPLAR [--periods x0,y0,x1,y1] [--json] [--plot PNG]
// prints the estimate (or the refinement of --periods), its confidence, the candidate lattices with their
// distance d, and any warning; --plot draws the lattice over the exemplar beside the map of d around it
// (S4 Fig. 10).
//   stex periods --corpus N [--seed S] [--tolerance PX] [--failures DIR] [--json]
// measures the estimator on N synthetic near-regular exemplars with known lattices (analysis/near_regular.h):
// success rate (the primitive lattice within the tolerance), super-lattices and time per exemplar.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/cs_lattice.h"
#include "analysis/image_io.h"
#include "analysis/near_regular.h"
#include "analysis/period_plot.h"

#include "cli/commands.h"
#include "core/error.h"

namespace stex::cli {

namespace {

struct PeriodsOptions {
  std::string exemplar;
  std::string periods;
  bool json = false;
  std::string plot;
  int corpus = 0;
  unsigned long long seed = 1;
  double tolerance = 0.1;
  std::string failures;
};

nlohmann::ordered_json lattice_json(const Lattice& t) { return {{t.t0x, t.t0y}, {t.t1x, t.t1y}}; }

nlohmann::ordered_json estimate_json(const PeriodEstimate& e, bool refined) {
  nlohmann::ordered_json j;
  j["periods"] = lattice_json(e.periods);
  j["area"] = lattice_area(e.periods);
  j["confidence"] = e.confidence;
  j["low_confidence"] = e.confidence < k_low_confidence;
  j["d"] = e.d;
  j["d_random_pairs"] = e.d_stationary;
  j["d_finer"] = std::isfinite(e.d_finer) ? nlohmann::ordered_json(e.d_finer) : nlohmann::ordered_json(nullptr);
  j["from"] = refined ? "refinement of --periods" : "estimated";
  j["initial"] = lattice_json(e.initial);
  j["d_initial"] = e.d_initial;
  j["evaluations"] = e.evaluations;
  j["candidates"] = nlohmann::ordered_json::array();
  for (const PeriodCandidate& c : e.candidates)
    j["candidates"].push_back({{"periods", lattice_json(c.periods)}, {"area", lattice_area(c.periods)}, {"d", c.d},
                               {"source", c.source}});
  j["warnings"] = e.warnings;
  return j;
}

void print_lattice_line(const char* label, const Lattice& t) {
  const double l0 = std::hypot(t.t0x, t.t0y), l1 = std::hypot(t.t1x, t.t1y);
  const double angle = std::acos(std::clamp((t.t0x * t.t1x + t.t0y * t.t1y) / (l0 * l1), -1.0, 1.0)) * 180.0 / 3.14159265358979323846;
  std::printf("%s t0 = (%.3f, %.3f), t1 = (%.3f, %.3f)  |t0| %.3f, |t1| %.3f, angle %.2f deg, cell %.2f px^2\n", label,
              t.t0x, t.t0y, t.t1x, t.t1y, l0, l1, angle, lattice_area(t));
}

void run_one(const PeriodsOptions& o, const GlobalOptions& global) {
  if (o.exemplar.empty()) throw Error(ErrorKind::Usage, "stex periods needs an EXEMPLAR (or --corpus N)");
  std::vector<std::string> load_warnings;
  const Image ex = load_exemplar(o.exemplar, {}, &load_warnings);
  const bool refined = !o.periods.empty();
  const PeriodEstimate e = refined ? refine_periods(ex, parse_lattice(o.periods)) : estimate_periods(ex);
  if (!o.plot.empty()) write_period_plot(o.plot, flatten_lighting(ex), e);

  if (o.json) {
    nlohmann::ordered_json j = estimate_json(e, refined);
    j["exemplar"] = o.exemplar;
    j["size"] = {ex.width, ex.height};
    if (!o.plot.empty()) j["plot"] = o.plot;
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  for (const std::string& w : load_warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  for (const std::string& w : e.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (global.quiet) return;
  std::printf("periods of %s (%dx%d), %s\n", o.exemplar.c_str(), ex.width, ex.height,
              refined ? "refined from --periods" : "estimated");
  print_lattice_line(" ", e.periods);
  char finer[64] = "not searched: no repetition";
  if (std::isfinite(e.d_finer)) std::snprintf(finer, sizeof finer, "%.5g", e.d_finer);
  std::printf("  confidence %.3f%s  (d %.5g at the periods, %.5g for random pairs, %s for the best finer lattice)\n",
              e.confidence, e.confidence < k_low_confidence ? " LOW" : "", e.d, e.d_stationary, finer);
  std::printf("  candidates (area px^2, d, source):\n");
  for (const PeriodCandidate& c : e.candidates)
    std::printf("    (%.3f, %.3f) (%.3f, %.3f)  %10.2f  %.5g  %s\n", c.periods.t0x, c.periods.t0y, c.periods.t1x,
                c.periods.t1y, lattice_area(c.periods), c.d, c.source.c_str());
  if (!o.plot.empty()) std::printf("  plot: %s\n", o.plot.c_str());
}

void run_corpus(const PeriodsOptions& o, const GlobalOptions& global) {
  if (!o.exemplar.empty() || !o.periods.empty() || !o.plot.empty())
    throw Error(ErrorKind::Usage, "--corpus measures the estimator on generated exemplars: give no EXEMPLAR, --periods or --plot");
  if (!(o.tolerance > 0.0)) throw Error(ErrorKind::Usage, "--tolerance must be > 0 pixels");
  const std::vector<NearRegularSpec> specs = near_regular_corpus(o.corpus, o.seed);
  int ok = 0, super = 0, super_confident = 0, wrong_confident = 0, errors = 0;
  std::vector<double> times;
  nlohmann::ordered_json cases = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const NearRegularSpec& s = specs[i];
    const Image img = make_near_regular(s);
    const auto t0 = std::chrono::steady_clock::now();
    PeriodEstimate e;
    std::string error;
    try {
      e = estimate_periods(img);
    } catch (const Error& err) {
      error = err.what();
    }
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    times.push_back(ms);
    // The truth: the lattice of the cells as drawn (each laid with its own sub-pixel shift).
    const Lattice truth = realised_lattice(s);
    double err_px = 0.0, err_nominal = 0.0;
    const bool match = error.empty() && lattices_match(truth, e.periods, o.tolerance, &err_px);
    if (error.empty()) lattices_match(s.lattice, e.periods, o.tolerance, &err_nominal);
    // A super-lattice: every estimated vector is a lattice vector of the truth (within 0.5 px), the cell larger.
    bool is_super = false;
    if (error.empty() && !match) {
      double a, b;
      bool on = true;
      const double v[2][2] = {{e.periods.t0x, e.periods.t0y}, {e.periods.t1x, e.periods.t1y}};
      for (const auto& q : v) {
        lattice_coords(truth, q[0], q[1], &a, &b);
        const double ex = q[0] - (std::round(a) * truth.t0x + std::round(b) * truth.t1x);
        const double ey = q[1] - (std::round(a) * truth.t0y + std::round(b) * truth.t1y);
        if (std::hypot(ex, ey) > 0.5) on = false;
      }
      is_super = on && lattice_area(e.periods) > 1.5 * lattice_area(truth);
    }
    ok += match;
    errors += !error.empty();
    super += is_super;
    super_confident += is_super && e.confidence >= k_low_confidence;
    wrong_confident += error.empty() && !match && e.confidence >= k_low_confidence;
    if (!match && !global.quiet && !o.json)
      std::printf("miss %zu: %s\n  got %s\n", i, describe(s).c_str(),
                  error.empty() ? ("(" + std::to_string(e.periods.t0x) + ", " + std::to_string(e.periods.t0y) + ") (" +
                                   std::to_string(e.periods.t1x) + ", " + std::to_string(e.periods.t1y) +
                                   ") error " + std::to_string(err_px) + " px, confidence " +
                                   std::to_string(e.confidence) + (is_super ? " SUPER-LATTICE" : ""))
                                      .c_str()
                                : ("error: " + error).c_str());
    if (!match && !o.failures.empty())
      write_image_atomic(o.failures + "/miss_" + std::to_string(i) + ".png", img);
    if (o.json)
      cases.push_back({{"case", i},
                       {"spec", describe(s)},
                       {"truth", lattice_json(truth)},
                       {"nominal", lattice_json(s.lattice)},
                       {"estimate", error.empty() ? lattice_json(e.periods) : nlohmann::ordered_json(nullptr)},
                       {"error", error.empty() ? nlohmann::ordered_json(err_px) : nlohmann::ordered_json(error)},
                       {"error_nominal", error.empty() ? nlohmann::ordered_json(err_nominal) : nlohmann::ordered_json(nullptr)},
                       {"confidence", e.confidence},
                       {"autocorrelation_peaks", {e.peak0, e.peak1}},
                       {"d", e.d},
                       {"d_finer", std::isfinite(e.d_finer) ? nlohmann::ordered_json(e.d_finer) : nlohmann::ordered_json(nullptr)},
                       {"d_random_pairs", e.d_stationary},
                       {"match", match},
                       {"super_lattice", is_super},
                       {"ms", ms}});
  }
  std::vector<double> sorted = times;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted.empty() ? 0.0 : sorted[sorted.size() / 2];
  const double worst = sorted.empty() ? 0.0 : sorted.back();
  const int n = int(specs.size());
  if (o.json) {
    nlohmann::ordered_json j;
    j["corpus"] = n;
    j["seed"] = o.seed;
    j["tolerance_px"] = o.tolerance;
    j["matched"] = ok;
    j["success_rate"] = n ? double(ok) / n : 0.0;
    j["errors"] = errors;
    j["super_lattices"] = super;
    j["super_lattices_confident"] = super_confident;
    j["wrong_confident"] = wrong_confident;
    j["ms_median"] = median;
    j["ms_max"] = worst;
    j["cases"] = cases;
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf("corpus %d (seed %llu): %d matched within %.3g px (%.1f %%), %d errors, %d super-lattices (%d above the "
              "warning threshold), %d wrong with confidence >= %.2f; estimation %.1f ms median, %.1f ms max\n",
              n, o.seed, ok, o.tolerance, n ? 100.0 * ok / n : 0.0, errors, super, super_confident, wrong_confident,
              k_low_confidence, median, worst);
}

}  // namespace

void add_periods(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<PeriodsOptions>();
  CLI::App* cmd = app.add_subcommand(
      "periods",
      "Estimate the period vectors of a near-regular exemplar (S4 §6): the primitive lattice, its confidence and the "
      "candidates; --plot draws it. --corpus N measures the estimator on generated exemplars.");
  cmd->add_option("exemplar", o->exemplar, "Exemplar image");
  cmd->add_option("--periods", o->periods, "Refine these periods (x0,y0,x1,y1 pixels) instead of estimating them");
  cmd->add_flag("--json", o->json, "Print JSON");
  cmd->add_option("--plot", o->plot, "Write a PNG: the lattice over the exemplar, beside the map of d around it");
  cmd->add_option("--corpus", o->corpus, "Measure the estimator on N generated near-regular exemplars")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--seed", o->seed, "Seed of the generated corpus (default 1)");
  cmd->add_option("--tolerance", o->tolerance, "Corpus: a match is within this many pixels (default 0.1)");
  cmd->add_option("--failures", o->failures, "Corpus: write the exemplars it misses to this directory");
  cmd->callback([o, &global]() {
    if (o->corpus > 0)
      run_corpus(*o, global);
    else
      run_one(*o, global);
  });
}

}  // namespace stex::cli
