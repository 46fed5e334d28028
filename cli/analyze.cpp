// `stex analyze EXEMPLAR -o MODEL.stex [--support S] [--iterations N] [--seed N] [--order 0|1|3|5] [--linear]`:
// texton analysis (S1 Algorithm 1 + §4.3 colour, analysis/texton.h) of an exemplar into a model file
// (docs/model-format.md), printing the report (RME, variance kept, timings). With `--order 0` and any of
// `--mask disc:R|square:S|PATH`, `--tolerance T`, `--max-iterations N`: S2's SOT on that support mask with
// the tolerance stop (S2 Algorithm 2, analysis/sot.h; docs/s2.md). And `stex export-texton MODEL -o IMAGE`:
// the texton coefficients as an image for viewing. Thin clients of analysis/; errors are stex::Error, mapped
// to exit codes by main.cpp.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/cs_lattice.h"
#include "analysis/cs_spot_model.h"
#include "analysis/expected_psd.h"
#include "analysis/gabor_model.h"
#include "analysis/image_io.h"
#include "analysis/kind_choice.h"
#include "analysis/lrp.h"
#include "analysis/lrp_psd.h"
#include "model/codecs.h"
#include "model/kinds.h"
#include "analysis/sot.h"
#include "analysis/tb_model.h"
#include "analysis/texton.h"
#include "cli/commands.h"
#include "core/error.h"

namespace stex::cli {
namespace {

struct AnalyzeOptions {
  std::string exemplar, output;
  std::string method = "auto";  // the model kind to analyse into (one run_analyze_* per kind), or auto
  // --method auto's period estimate, when it picked a cyclostationary kind without --periods: the method
  // uses it instead of estimating again.
  bool have_auto_periods = false;
  PeriodEstimate auto_periods;
  int support = 64, iterations = 50, order = 1;
  std::uint64_t seed = 0;
  bool linear = false, no_colour_correction = false;
  std::uint64_t pixel_budget = std::uint64_t(1) << 26;
  // SOT (S2 Algorithm 2, analysis/sot.h): any of these selects it; it needs --order 0.
  std::string mask;
  double tolerance = 0.0;
  int max_iterations = 0;
  bool iterations_given = false;
  // LRP (S3, analysis/lrp.h documents each): --method lrp
  LrpParams lrp;
  std::string psd;        // continuous-spectrum mode: ring:F,W | bilobe:F,A,W | gauss:FX,FY,W[;...]
  bool psd_image = false;  // the positional image is a PSD (zero frequency at its centre)
  int psd_size = 256;
  std::string amplitudes = "fit";  // lrp: fit | paper | psd | psd-energy (analysis/lrp.h LrpAmplitudes)
  // Cyclostationary kinds (S4, analysis/cs_lattice.h, analysis/cs_spot_model.h): --method cs-spot
  std::string periods;          // "x0,y0,x1,y1": the user's period vectors (used as given)
  bool estimate_periods = false; // estimate them (the default when --periods is absent)
  int border = -1;              // spot border taper (texels; -1: min(w, h) / 8)
  double tile = -1.0;           // tb, cs-tb: triangle-grid side (pixels; -1: min(w, h) / 6)
  bool json = false;            // report as JSON on stdout
  // Histogram transfer (S4 §5.3, analysis/cs_hist.h): "" = the method's default (cs-spot none, tb and cs-tb
  // stationary); --delta N (the §5.3.3 neighbourhood) implies cs.
  std::string histogram;
  int delta = -1;
};

// The histogram mode (0 none, 1 stationary, 2 cs) and delta of a cs-spot / tb / cs-tb analysis.
void resolve_histogram(const AnalyzeOptions& o, int* mode, int* delta) {
  const bool tb = o.method == "tb" || o.method == "cs-tb";
  *mode = o.histogram.empty() ? (o.delta >= 0 ? 2 : (tb ? 1 : 0)) : parse_cs_hist_mode(o.histogram);
  if (o.delta >= 0 && *mode != 2)
    throw Error(ErrorKind::Usage, "--delta is the neighbourhood of the cyclostationary transfer: it needs --histogram cs");
  if (tb && *mode == 0)
    throw Error(ErrorKind::Usage, "tiling and blending always transfers the histogram: --histogram stationary or cs");
  if (o.method == "tb" && *mode == 2)
    throw Error(ErrorKind::Usage, "--method tb is stationary: --histogram cs and --delta need --method cs-tb or cs-spot");
  *delta = o.delta >= 0 ? o.delta : 1;
}

void warn(const std::string& w) { std::fprintf(stderr, "stex: warning: %s\n", w.c_str()); }

// S2 Algorithm 2 on a support mask with the tolerance stop (analysis/sot.h).
void run_sot(const AnalyzeOptions& o, const GlobalOptions& global) {
  if (o.order != 0)
    throw Error(ErrorKind::Usage,
                "--mask, --tolerance and --max-iterations compute S2's SOT: they need --order 0");
  if (o.max_iterations > 0 && o.iterations_given)
    throw Error(ErrorKind::Usage,
                "give either --iterations or --max-iterations (the cap of the SOT), not both");
  LoadOptions lo;
  lo.linear = o.linear;
  lo.pixel_budget = o.pixel_budget;
  SotParams sp;
  sp.mask = o.mask.empty() ? square_mask(o.support) : parse_support_mask(o.mask, lo);
  sp.max_iterations = o.max_iterations > 0 ? o.max_iterations : o.iterations;
  sp.tolerance = o.tolerance;
  sp.seed = o.seed;
  sp.colour_correction = !o.no_colour_correction;
  std::vector<std::string> warnings;
  SotReport rep;
  TextonModel model = analyse_sot_file(o.exemplar, lo, sp, &rep, &warnings);
  for (const auto& w : warnings) warn(w);
  for (const auto& w : rep.warnings) warn(w);
  save_model(model, o.output);
  if (global.quiet) return;
  std::printf("SOT model (S2 Algorithm 2): %s\n", o.output.c_str());
  std::printf("  exemplar        %s (%dx%d, %d channel%s%s), sha256 %.16s...\n", model.exemplar_name.c_str(),
              model.exemplar_width, model.exemplar_height, model.channels, model.channels == 1 ? "" : "s",
              model.linear ? ", linear light" : "", model.exemplar_hash.c_str());
  std::printf("  support         %s: %zu pixels in a %dx%d box, order 0, seed %llu\n",
              sp.mask.description.c_str(), rep.support_pixels, model.support, model.support,
              static_cast<unsigned long long>(model.analysis_seed));
  std::printf("  iterations      %d of at most %d (%s)\n", rep.iterations, sp.max_iterations,
              rep.converged ? "stopped: the RME changed by less than the tolerance" : "the cap");
  std::printf("  mean           ");
  for (int c = 0; c < model.channels; ++c) std::printf(" %.6f", model.mean[c]);
  std::printf("\n");
  std::printf("  RME             %.4f (before colour correction; %.4f after)\n", rep.rme, rep.rme_corrected);
  std::printf("  variance kept   %.4f (before colour correction)\n", rep.variance_kept);
  std::printf("  time            %.1f ms\n", rep.ms_total);
}

void run_analyze(const AnalyzeOptions& o, const GlobalOptions& global) {
  if (!o.mask.empty() || o.tolerance != 0.0 || o.max_iterations > 0) {
    run_sot(o, global);
    return;
  }
  LoadOptions lo;
  lo.linear = o.linear;
  lo.pixel_budget = o.pixel_budget;
  TextonParams tp;
  tp.support = o.support;
  tp.iterations = o.iterations;
  tp.seed = o.seed;
  tp.order = o.order;
  tp.colour_correction = !o.no_colour_correction;
  std::vector<std::string> warnings;
  TextonReport rep;
  TextonModel model = analyse_texton_file(o.exemplar, lo, tp, &rep, &warnings);
  for (const auto& w : warnings) warn(w);
  for (const auto& w : rep.warnings) warn(w);
  save_model(model, o.output);
  if (global.quiet) return;
  std::printf("texton model: %s\n", o.output.c_str());
  std::printf("  exemplar        %s (%dx%d, %d channel%s%s), sha256 %.16s...\n", model.exemplar_name.c_str(),
              model.exemplar_width, model.exemplar_height, model.channels, model.channels == 1 ? "" : "s",
              model.linear ? ", linear light" : "", model.exemplar_hash.c_str());
  std::printf("  support         %dx%d, order %d (%s), %d iterations, seed %llu\n", model.support,
              model.support, model.order, model.order == 1   ? "bilinear"
                                                  : model.order == 0 ? "nearest/SOT"
                                                  : model.order == 3 ? "cubic B-spline"
                                                                     : "quintic B-spline",
              model.iterations,
              static_cast<unsigned long long>(model.analysis_seed));
  std::printf("  mean           ");
  for (int c = 0; c < model.channels; ++c) std::printf(" %.6f", model.mean[c]);
  std::printf("\n");
  std::printf("  RME             %.4f (before colour correction; %.4f after)\n", rep.rme, rep.rme_corrected);
  std::printf("  variance kept   %.4f (before colour correction)\n", rep.variance_kept);
  std::printf(
      "  time            %.1f ms total: periodic component + spectra %.1f ms, %d iterations %.1f ms, "
      "report %.1f ms, colour correction %.1f ms\n",
      rep.ms_total, rep.ms_periodic, model.iterations, rep.ms_iterations, rep.ms_report, rep.ms_correction);
}

// The model's expected PSD (its random-phase strata, analysis/lrp_psd.h) against the target's outside the
// fixed-phase region R (all of it for r = 0).
PsdComparison lrp_psd_check(const LrpModel& model, const LrpSpectrum& target) {
  std::vector<double> ref = target.psd;
  if (model.ratio > 0.0) {  // R's frequencies are the structure's: compare the strata with the rest
    const std::vector<char> in_r = lrp_region_mask(target, model.ratio);
    for (std::size_t i = 0; i < ref.size(); ++i)
      if (in_r[i]) ref[i] = 0.0;
  }
  return compare_psd(lrp_expected_welch_psd(model), ref, model.period);
}

// `stex analyze --method lrp --json`: the model, its strata and the per-bin ratios of its expected spectrum.
nlohmann::ordered_json lrp_json(const AnalyzeOptions& o, const LrpModel& m, const PsdComparison& c) {
  nlohmann::ordered_json j;
  j["method"] = "lrp";
  j["model"] = o.output;
  j["period"] = m.period;
  j["amplitudes"] = m.amplitudes;
  j["strata"] = m.strata.size();
  j["cosines"] = m.cosines;
  nlohmann::ordered_json psd;
  psd["reference"] = o.psd.empty() && !o.psd_image ? "exemplar Welch PSD" : "given PSD";
  psd.update(psd_comparison_json(c));
  j["psd"] = psd;
  return j;
}

// S3: local random-phase noise by example, or from an analytic PSD / PSD image (analysis/lrp.h).
void run_lrp(const AnalyzeOptions& o, const GlobalOptions& global) {
  LoadOptions lo;
  lo.linear = o.linear;
  lo.pixel_budget = o.pixel_budget;
  std::vector<std::string> warnings;
  LrpReport rep;
  LrpModel model;
  LrpSpectrum target;  // what the model's spectrum is compared with: the exemplar's Welch PSD or the given PSD
  LrpParams prm = o.lrp;
  prm.amplitudes = parse_lrp_amplitudes(o.amplitudes);
  if (!o.psd.empty()) {
    if (!o.exemplar.empty()) throw Error(ErrorKind::Usage, "--psd takes no exemplar image (use --psd-image IMAGE for a PSD image)");
    target = lrp_analytic_psd(o.psd, o.psd_size);
    model = lrp_from_spectrum(target, prm, &rep);
    model.source = o.psd;
    model.stex_version = STEX_VERSION_STRING;
  } else if (o.exemplar.empty()) {
    throw Error(ErrorKind::Usage, "an exemplar image is required (or --psd SPEC)");
  } else if (o.psd_image) {
    const Image img = load_exemplar(o.exemplar, lo, &warnings);
    target = lrp_psd_from_image(img);
    model = lrp_from_spectrum(target, prm, &rep);
    model.source = "psd-image";
    const auto slash = o.exemplar.find_last_of('/');
    model.exemplar_name = slash == std::string::npos ? o.exemplar : o.exemplar.substr(slash + 1);
    model.exemplar_hash = sha256_file_hex(o.exemplar);
    model.stex_version = STEX_VERSION_STRING;
  } else {
    model = analyse_lrp_file(o.exemplar, lo, prm, &rep, &warnings, &target);
  }
  for (const auto& w : warnings) warn(w);
  save_container(to_container(model), o.output);
  // the strata's expected spectrum against the target (the structure part, r > 0, is left out of both)
  const PsdComparison check = lrp_psd_check(model, target);
  if (o.json) {
    std::printf("%s\n", lrp_json(o, model, check).dump(2).c_str());
    return;
  }
  if (global.quiet) return;
  std::printf("LRP model (S3): %s\n", o.output.c_str());
  std::printf("  source          %s%s%s, %d channel%s, T = %d (%d Welch crop%s, Hann window)\n", model.source.c_str(),
              model.exemplar_name.empty() ? "" : " ", model.exemplar_name.c_str(), model.channels,
              model.channels == 1 ? "" : "s", rep.period, rep.crops, rep.crops == 1 ? "" : "s");
  std::printf("  budget          J = %d cosines: J_R = %d fixed-phase, %d over %zu strata\n", o.lrp.cosines, rep.jr,
              o.lrp.cosines - rep.jr, rep.strata.size());
  for (std::size_t s = 0; s < rep.strata.size(); ++s) {
    const auto& st = rep.strata[s];
    std::printf("  stratum %zu       energy %.3f, |S| %d (eroded %d, %.2f bins), J_S %d, Delta %.2f px, A_S %.5f\n", s,
                st.energy_share, st.size, st.eroded_size, st.erosion, st.js, st.delta, st.amplitude);
  }
  if (model.block > 0)
    std::printf("  structure       r = %.3f: |R| %d (%.3f of the energy), blocks %dx%d px, error %.5f; turbulence %.2f px, "
                "placement %s\n",
                model.ratio, rep.region_size, rep.region_share, model.block, model.block, model.structure_error, model.sigma,
                model.placement ? "on" : "off");
  for (std::size_t s = 0; s < rep.turbulence.size(); ++s) {
    const auto& st = rep.turbulence[s];
    std::printf("  turbulence %zu    energy %.3f, |S| %d, J_T %d, Delta %.2f px (whole spectrum, S3 §5.2)\n", s,
                st.energy_share, st.size, st.js, st.delta);
  }
  std::printf("  spectrum        amplitudes %s; expected radial PSD / %s, 24 bins: %s\n", model.amplitudes.c_str(),
              o.psd.empty() && !o.psd_image ? "exemplar's Welch PSD" : "the given PSD",
              psd_comparison_summary(check).c_str());
  std::printf("  time            %.1f ms\n", rep.ms);
}

// Gabor noise from the exemplar's power spectrum (analysis/gabor_model.h): 64 x 64 frequency bins, each an
// anisotropic component whose lobe std a / (2 sqrt(pi)) is one bin (a = 2 sqrt(pi) / 64), every bin with
// power inside 0.5 cycles per pixel kept (1602); the model's mean and std are the exemplar's. `stex gabor --exemplar` exposes the grid and bandwidth.
void run_analyze_gabor(const AnalyzeOptions& o, const GlobalOptions& global) {
  LoadOptions lo;
  lo.linear = o.linear;
  lo.pixel_budget = o.pixel_budget;
  constexpr int k_grid = 64;
  double mean = 0.0, sd = 0.0;
  const Image exemplar = load_exemplar(o.exemplar, lo);
  const Image psd = exemplar_psd(exemplar, k_grid, &mean, &sd);
  int dropped = 0;
  GaborModel m = gabor_model_from_psd(psd, 2.0 * std::sqrt(k_gabor_pi) / k_grid, STEX_GABOR_MAX_COMPONENTS, 0.0, &dropped);
  m.mean = mean;
  m.stddev = sd;
  save_container(to_container(m), o.output);
  const PsdComparison check = gabor_check_against_exemplar(m, exemplar);
  if (o.json) {
    nlohmann::ordered_json j;
    j["method"] = "gabor";
    j["model"] = o.output;
    j["bandwidth"] = m.bandwidth;
    j["components"] = m.components.size();
    j["dropped"] = dropped;
    nlohmann::ordered_json spectrum;
    spectrum["reference"] = "exemplar Welch PSD";
    spectrum.update(psd_comparison_json(check));
    j["psd"] = spectrum;
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  if (global.quiet) return;
  std::printf("gabor model: %s (power spectrum of %s on a %d^2 grid)\n", o.output.c_str(), o.exemplar.c_str(), k_grid);
  std::printf("  bandwidth       a = %.6g /pixel, %zu components (%d bins dropped), mean %.6g, std %.6g\n",
              m.bandwidth, m.components.size(), dropped, m.mean, m.stddev);
  std::printf("  spectrum        expected radial PSD / exemplar's Welch PSD (channel mean), 24 bins: %s\n",
              psd_comparison_summary(check).c_str());
}

// S4 §5.1: cyclostationary spot noise by example. The periods are the user's (--periods, used as given) or
// estimated (S4 §6: autocorrelation peaks refined on d, analysis/cs_lattice.h); d and a confidence are
// reported either way.
// The periods of a CS method: the user's (--periods, used as given; d and confidence computed) or estimated.
PeriodEstimate resolve_periods(const AnalyzeOptions& o, const Image& ex) {
  if (o.periods.empty()) return o.have_auto_periods ? o.auto_periods : estimate_periods(ex);
  // Both: the user's rough periods refined (S4 §6).
  if (o.estimate_periods) return refine_periods(ex, parse_lattice(o.periods));
  return given_periods(ex, parse_lattice(o.periods));
}

nlohmann::ordered_json periods_json(const PeriodEstimate& est, bool estimated) {
  nlohmann::ordered_json j;
  const Lattice& t = est.periods;
  j["periods"] = {{t.t0x, t.t0y}, {t.t1x, t.t1y}};
  j["estimated"] = estimated;
  j["d"] = est.d;
  j["confidence"] = est.confidence;
  j["d_random_pairs"] = est.d_stationary;
  if (estimated) {
    j["initial"] = {{est.initial.t0x, est.initial.t0y}, {est.initial.t1x, est.initial.t1y}};
    j["d_initial"] = est.d_initial;
    j["autocorrelation_peaks"] = {est.peak0, est.peak1};
    j["evaluations"] = est.evaluations;
  }
  j["warnings"] = est.warnings;
  return j;
}

// Tiling and blending (Heitz & Neyret; S4 §5.2 for cs-tb), analysis/tb_model.h.
void run_analyze_tb(const AnalyzeOptions& o, const GlobalOptions& global) {
  const bool cs = o.method == "cs-tb";
  if (!cs && (!o.periods.empty() || o.estimate_periods))
    throw Error(ErrorKind::Usage, "--method tb is stationary: --periods and --estimate-periods need --method cs-tb or cs-spot");
  if (!o.periods.empty()) parse_lattice(o.periods);  // usage errors before any file work
  int hist_mode = 1, delta = 1;
  resolve_histogram(o, &hist_mode, &delta);
  LoadOptions lo;
  lo.linear = o.linear;
  lo.pixel_budget = o.pixel_budget;
  std::vector<std::string> warnings;
  const Image ex = load_exemplar(o.exemplar, lo, &warnings);
  for (const auto& w : warnings) warn(w);
  PeriodEstimate est;
  if (cs) {
    est = resolve_periods(o, ex);
    for (const auto& w : est.warnings) warn(w);
  }
  TbParams tp;
  tp.tile = o.tile;
  tp.histogram = hist_mode;
  tp.delta = delta;
  const TbModel m = tb_from_exemplar(ex, tp, cs ? &est.periods : nullptr);
  ModelContainer c = to_container(m);
  c.metadata["linear"] = o.linear;
  if (cs) {
    c.metadata["d"] = est.d;
    c.metadata["confidence"] = est.confidence;
  }
  save_container(c, o.output);
  if (o.json) {
    nlohmann::ordered_json j;
    j["method"] = o.method;
    j["model"] = o.output;
    if (cs) {
      const nlohmann::ordered_json pj = periods_json(est, o.periods.empty());
      for (auto it = pj.begin(); it != pj.end(); ++it) j[it.key()] = *it;
    }
    j["tile"] = m.tile;
    j["histogram"] = cs_hist_mode_name(hist_mode);
    if (m.hist.enabled()) {
      j["delta"] = m.hist.delta;
      j["histogram_bins"] = {m.hist.m0, m.hist.m1};
      j["histogram_quantiles"] = m.hist.q;
    }
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  if (global.quiet) return;
  std::printf("%s model: %s (tile %.2f px, %d channel%s, LUT %d)\n", o.method.c_str(), o.output.c_str(), m.tile,
              m.channels, m.channels == 1 ? "" : "s", m.lut_size);
  if (cs)
    std::printf("  periods         t0 = (%.4f, %.4f), t1 = (%.4f, %.4f) (%s), d %.6g, confidence %.3f\n", m.t0x, m.t0y,
                m.t1x, m.t1y, o.periods.empty() ? "estimated" : o.estimate_periods ? "refined" : "given", est.d, est.confidence);
  if (m.hist.enabled())
    std::printf("  histogram       cs, delta %d: %dx%d polyphase bins x %d quantiles\n", m.hist.delta, m.hist.m0, m.hist.m1,
                m.hist.q);
  else
    std::printf("  histogram       stationary (LUT %d)\n", m.lut_size);
}

// S4 §5.1: cyclostationary spot noise by example. The periods are the user's (--periods, used as given) or
// estimated (S4 §6: autocorrelation peaks refined on d, analysis/cs_lattice.h); d and a confidence are
// reported either way.
void run_analyze_cs_spot(const AnalyzeOptions& o, const GlobalOptions& global) {
  if (!o.periods.empty()) parse_lattice(o.periods);  // usage errors before any file work
  int hist_mode = 0, delta = 1;
  resolve_histogram(o, &hist_mode, &delta);
  LoadOptions lo;
  lo.linear = o.linear;
  lo.pixel_budget = o.pixel_budget;
  std::vector<std::string> warnings;
  const Image ex = load_exemplar(o.exemplar, lo, &warnings);
  const bool estimated = o.periods.empty() || o.estimate_periods;
  const PeriodEstimate est = resolve_periods(o, ex);
  for (const auto& w : warnings) warn(w);
  for (const auto& w : est.warnings) warn(w);
  CsSpotParams sp;
  sp.border = o.border;
  sp.histogram = hist_mode;
  sp.delta = delta;
  CsSpotReport rep;
  const CsSpotModel m = cs_spot_from_exemplar(ex, est.periods, sp, &rep);
  CsModelInfo info;
  info.exemplar_name = o.exemplar.substr(o.exemplar.find_last_of('/') == std::string::npos ? 0 : o.exemplar.find_last_of('/') + 1);
  info.linear = o.linear;
  info.estimated = estimated;
  info.d = est.d;
  info.confidence = est.confidence;
  info.border = rep.border;
  ModelContainer c = to_container(m, info);
  save_container(c, o.output);
  const Lattice& t = est.periods;
  if (o.json) {
    nlohmann::ordered_json j;
    j["method"] = "cs-spot";
    j["model"] = o.output;
    const nlohmann::ordered_json pj = periods_json(est, estimated);
    for (auto it = pj.begin(); it != pj.end(); ++it) j[it.key()] = *it;
    j["border"] = rep.border;
    j["mean_grid"] = {m.n0, m.n1};
    j["amplitude"] = m.amplitude;
    j["histogram"] = cs_hist_mode_name(hist_mode);
    if (m.hist.enabled()) {
      j["delta"] = m.hist.delta;
      j["histogram_bins"] = {m.hist.m0, m.hist.m1};
      j["histogram_quantiles"] = m.hist.q;
    }
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  if (global.quiet) return;
  std::printf("cs-spot model: %s\n", o.output.c_str());
  std::printf("  periods         t0 = (%.4f, %.4f), t1 = (%.4f, %.4f) pixels (%s), |Ω⁻| = %.3f px^2\n", t.t0x, t.t0y,
              t.t1x, t.t1y, estimated ? "estimated" : "given", lattice_area(t));
  if (estimated)
    std::printf("  estimate        autocorrelation (%.4f, %.4f), (%.4f, %.4f), peaks %.3f %.3f; refined in %d evaluations of d\n",
                est.initial.t0x, est.initial.t0y, est.initial.t1x, est.initial.t1y, est.peak0, est.peak1, est.evaluations);
  std::printf("  d               %.6g (random pairs %.6g), confidence %.3f\n", est.d, est.d_stationary, est.confidence);
  std::printf("  spot            %dx%d, %d channel%s, border %d texels, amplitude %.6g; M on a %dx%d phase grid (>= %d samples each)\n",
              m.width, m.height, m.channels, m.channels == 1 ? "" : "s", rep.border, m.amplitude, m.n0, m.n1, rep.mean_samples);
  if (m.hist.enabled())
    std::printf("  histogram       %s, delta %d: %dx%d polyphase bins x %d quantiles\n", cs_hist_mode_name(m.hist.mode),
                m.hist.delta, m.hist.m0, m.hist.m1, m.hist.q);
}

void run_export(const std::string& model_path, const std::string& output, const GlobalOptions& global) {
  const TextonModel m = load_model(model_path);
  const int s = m.support, ch = m.channels;
  Image img;
  img.width = s;
  img.height = s;
  img.channels = ch;
  img.pixels.resize(std::size_t(s) * s * ch);
  for (int c = 0; c < ch; ++c) {
    for (int y = 0; y < s; ++y) {
      for (int x = 0; x < s; ++x) img.at(x, y, c) = m.alpha_at(c, y, x);
    }
  }
  std::string ext;
  auto dot = output.find_last_of('.');
  if (dot != std::string::npos) ext = output.substr(dot + 1);
  for (auto& ch_ : ext) ch_ = char(std::tolower(static_cast<unsigned char>(ch_)));
  const bool is_float = ext == "exr" || ext == "hdr";
  double peak = 0.0;
  if (!is_float) {
    // Display normalisation: 0.5 + alpha / (2 max|alpha|) over all channels, so that zero is mid-grey and
    // the sign of the coefficients stays visible.
    for (float v : img.pixels) peak = std::max(peak, double(std::fabs(v)));
    const double scale = peak > 0.0 ? 0.5 / peak : 0.0;
    for (float& v : img.pixels) v = float(0.5 + scale * v);
  }
  WriteOptions wo;
  wo.metadata.push_back({"Software", std::string("stex ") + STEX_VERSION_STRING});
  wo.metadata.push_back({"ImageDescription", "texton coefficients of " + m.exemplar_name});
  write_image_atomic(output, img, wo);
  if (global.quiet) return;
  if (is_float) {
    std::printf("texton %dx%d (%d channel%s) written to %s: raw coefficients alpha\n", s, s, ch,
                ch == 1 ? "" : "s", output.c_str());
  } else {
    std::printf(
        "texton %dx%d (%d channel%s) written to %s, normalised for display: 0.5 + alpha / (2 * %.6g); "
        "use .exr for the raw coefficients\n",
        s, s, ch, ch == 1 ? "" : "s", output.c_str(), peak);
  }
}

// The options of the texton and SOT analysis (the default method), and the exemplar and output of every kind.
void add_texton_options(CLI::App* sub, AnalyzeOptions* opts) {
  sub->add_option("exemplar", opts->exemplar,
                  "Exemplar image (png, jpeg, tiff, exr, bmp, targa, hdr, pnm); required except with --psd");
  sub->add_option("-o,--output", opts->output, "Output model file (.stex)")->required();
  sub->add_option("--method", opts->method,
                  "Model kind to analyse into: auto (default: the kind the exemplar suits, and why, on stderr: cs-tb "
                  "or cs-spot when it repeats on a lattice, tb when it is far from Gaussian, texton otherwise; "
                  "among the methods that read the options given, e.g. texton with --support; docs/auto.md), "
                  "texton (S1's texton, or S2's SOT with --order 0), lrp (S3's "
                  "local random-phase noise), gabor (Gabor noise from the exemplar's power spectrum), cs-spot (S4's "
                  "cyclostationary spot noise), tb (Heitz-Neyret tiling and blending), cs-tb (its cyclostationary variant)")
      ->capture_default_str();
  sub->add_option("--support", opts->support,
                  "Texton support s (s x s coefficients; at most the exemplar size)")
      ->capture_default_str()
      ->check(CLI::Range(1, 4096));
  sub->add_option("--iterations", opts->iterations, "Iterations of Algorithm 1")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  sub->add_option("--seed", opts->seed, "Seed of the random initialisation")->capture_default_str();
  sub->add_option("--order", opts->order,
                  "Interpolation order: 1 bilinear (S1), 0 nearest (S2's SOT), 3 cubic or 5 quintic B-spline "
                  "(S1 §10: smooth derivatives, for bump and normal maps)")
      ->capture_default_str()
      ->check(CLI::IsMember({0, 1, 3, 5}));
  sub->add_flag("--linear", opts->linear, "Decode sRGB to linear light before the analysis");
  sub->add_flag("--no-colour-correction", opts->no_colour_correction,
                "Skip the colour covariance correction (the model keeps less variance)");
  sub->add_option("--pixel-budget", opts->pixel_budget, "Largest exemplar accepted, in pixels")
      ->capture_default_str();
  sub->add_option(
      "--mask", opts->mask,
      "SOT support (with --order 0; S2 Algorithm 2): disc:R (radius R, a (2R+1)^2 box), square:S, or a "
      "mask image (non-zero = in the support)");
  sub->add_option(
         "--tolerance", opts->tolerance,
         "SOT (with --order 0): stop when the RME changes by less than this between iterations (default 0: "
         "run the cap)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--max-iterations", opts->max_iterations,
                  "SOT (with --order 0): iteration cap (default: --iterations)")
      ->check(CLI::Range(1, 100000));
}

// The options of --method lrp (S3).
void add_lrp_options(CLI::App* sub, AnalyzeOptions* opts) {
  sub->add_option("--cosines", opts->lrp.cosines, "lrp: cosine budget J per lattice point (S3 §6.3)")
      ->capture_default_str()
      ->check(CLI::Range(1, 4096));
  sub->add_option("--strata", opts->lrp.strata, "lrp: number L of equal-energy strata (S3 §4.2)")
      ->capture_default_str()
      ->check(CLI::Range(1, STEX_LRP_MAX_STRATA));
  sub->add_option("--structure", opts->lrp.ratio,
                  "lrp: energy ratio r of the fixed-phase region R (S3 §5; 0 = noise by example, 1 = the exemplar)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--turbulence", opts->lrp.sigma, "lrp: turbulence scale sigma in exemplar pixels (S3 §5.2; needs r > 0)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  sub->add_flag("--placement", opts->lrp.placement, "lrp: random placement by half-period blocks (S3 §5.2; needs r > 0)");
  sub->add_option("--psd", opts->psd,
                  "lrp continuous-spectrum mode (S3 Fig. 3, 10), no exemplar: ring:F,W | bilobe:F,ANGLE,W | "
                  "gauss:FX,FY,W[;FX,FY,W...] (frequencies in cycles/pixel)");
  sub->add_option("--psd-size", opts->psd_size, "lrp: grid T of an analytic PSD (power of two)")
      ->capture_default_str()
      ->check(CLI::IsMember({16, 32, 64, 128, 256, 512, 1024}));
  sub->add_option("--amplitudes", opts->amplitudes,
                  "lrp: the cosines' amplitudes: fit (fitted to the exemplar's spectrum through the model's expected "
                  "spectrum), paper (S3: the uniform A_S of eq. 3 in each stratum, J / L cosines per stratum), psd "
                  "(each sub-stratum carries the PSD's energy over it), psd-energy (psd on sub-strata of about equal "
                  "energy); docs/lrp.md compares them")
      ->capture_default_str();
  sub->add_flag("--psd-image", opts->psd_image,
                "lrp: the image is a PSD (square, power of two, zero frequency at the centre), not an exemplar");
}

// The options of the cyclostationary and tiling kinds (--method cs-spot, tb, cs-tb; S4).
void add_cs_options(CLI::App* sub, AnalyzeOptions* opts) {
  sub->add_option("--periods", opts->periods,
                  "cs-spot, cs-tb: period vectors t0, t1 in exemplar pixels, x0,y0,x1,y1 (any parallelogram, sub-pixel; used "
                  "as given; with --estimate-periods, refined)");
  sub->add_flag("--estimate-periods", opts->estimate_periods,
                "cs-spot, cs-tb: estimate the periods (S4 §6; `stex periods` shows them); the default without --periods. "
                "With --periods: refine those (S4 §6)");
  sub->add_option("--border", opts->border, "cs-spot: width in texels of the spot's smoothed border (default min(w, h) / 8)")
      ->check(CLI::Range(0, 2048));
  sub->add_option("--tile", opts->tile, "tb, cs-tb: side of the triangle grid in pixels (default min(w, h) / 6)")
      ->check(CLI::Range(2.0, 2048.0));
  sub->add_option("--histogram", opts->histogram,
                  "cs-spot, tb, cs-tb: histogram transfer (S4 §5.3): none (cs-spot's default: a Gaussian texture), "
                  "stationary (tb, cs-tb default: one T for the whole exemplar), cs (cs-spot, cs-tb: one T per polyphase "
                  "component, pooled over --delta)");
  sub->add_option("--delta", opts->delta,
                  "cs-spot, cs-tb: neighbourhood of the cyclostationary histogram transfer (S4 §5.3.3; 0: each "
                  "polyphase component alone, 1: 3x3 components, ...; default 1); implies --histogram cs")
      ->check(CLI::Range(0, 64));
  sub->add_flag("--json", opts->json, "cs-spot, tb, cs-tb: print the report as JSON (periods as [[t0x, t0y], [t1x, t1y]], d, confidence); "
                "lrp, gabor: the model's expected PSD against the exemplar's (or the given PSD's), per radial bin and polar sector");
}

void run_lrp_method(AnalyzeOptions& o, const GlobalOptions& global) {
  o.lrp.seed = o.seed;
  run_lrp(o, global);
}

// The analysis methods, one per model kind that can be made from an exemplar (model/kinds.h), in the order
// of `--method`'s help: the kind, whether it needs the exemplar (lrp can start from --psd alone), the analysis,
// and the options that belong to it (every option not listed by some method applies to all: the exemplar,
// -o, --method, --linear, --pixel-budget). One table: the unknown-method message, the check that refuses
// another method's options and the help's option groups all come from it.
struct AnalysisMethod {
  const char* kind;
  bool needs_exemplar;
  void (*run)(AnalyzeOptions&, const GlobalOptions&);
  std::vector<std::string> options;
};
const std::vector<AnalysisMethod>& analysis_methods() {
  static const std::vector<AnalysisMethod> table = {
      {kinds::texton, true, [](AnalyzeOptions& o, const GlobalOptions& g) { run_analyze(o, g); },
       {"--support", "--iterations", "--order", "--no-colour-correction", "--mask", "--tolerance", "--max-iterations",
        "--seed"}},
      {kinds::lrp, false, run_lrp_method,
       {"--seed", "--cosines", "--strata", "--structure", "--turbulence", "--placement", "--psd", "--psd-size",
        "--amplitudes", "--psd-image", "--json"}},
      {kinds::gabor, true, [](AnalyzeOptions& o, const GlobalOptions& g) { run_analyze_gabor(o, g); }, {"--json"}},
      {kinds::cs_spot, true, [](AnalyzeOptions& o, const GlobalOptions& g) { run_analyze_cs_spot(o, g); },
       {"--periods", "--estimate-periods", "--border", "--histogram", "--delta", "--json"}},
      {kinds::tb, true, [](AnalyzeOptions& o, const GlobalOptions& g) { run_analyze_tb(o, g); },
       {"--tile", "--histogram", "--json"}},
      {kinds::cs_tb, true, [](AnalyzeOptions& o, const GlobalOptions& g) { run_analyze_tb(o, g); },
       {"--periods", "--estimate-periods", "--tile", "--histogram", "--delta", "--json"}},
  };
  return table;
}

// The methods that read `option`, in the table's order (empty: an option of every method).
std::vector<std::string> methods_reading(const std::string& option) {
  std::vector<std::string> out;
  for (const AnalysisMethod& m : analysis_methods())
    if (std::find(m.options.begin(), m.options.end(), option) != m.options.end()) out.push_back(m.kind);
  return out;
}

std::string join_methods(const std::vector<std::string>& m) {
  std::string out;
  for (std::size_t i = 0; i < m.size(); ++i) out += (i == 0 ? "" : i + 1 == m.size() ? " or " : ", ") + m[i];
  return out;
}

// Error(Usage) naming the first option given (in the help's order) that `method` does not read.
void check_method_options(const CLI::App& sub, const AnalysisMethod& method) {
  for (const CLI::Option* opt : sub.get_options()) {
    const std::string name = opt->get_name();
    if (opt->count() == 0) continue;
    const std::vector<std::string> readers = methods_reading(name);
    if (readers.empty() || std::find(readers.begin(), readers.end(), method.kind) != readers.end()) continue;
    throw Error(ErrorKind::Usage, name + " does not apply to --method " + method.kind + " (it is an option of --method " +
                                      join_methods(readers) + ")");
  }
}

// --method auto (analysis/kind_choice.h): the kinds that read every method option given (e.g. --support:
// texton only), then among texton, tb, cs-spot and cs-tb the one the exemplar's measures pick; sets o.method
// and says why on stderr.
void pick_method(const CLI::App& sub, AnalyzeOptions& o, const GlobalOptions& global) {
  std::vector<std::string> given;
  for (const CLI::Option* opt : sub.get_options())
    if (opt->count() > 0 && !methods_reading(opt->get_name()).empty()) given.push_back(opt->get_name());
  std::vector<std::string> candidates;
  for (const AnalysisMethod& m : analysis_methods())
    if (std::all_of(given.begin(), given.end(), [&](const std::string& g) {
          return std::find(m.options.begin(), m.options.end(), g) != m.options.end();
        }))
      candidates.push_back(m.kind);
  std::string given_text;
  for (std::size_t i = 0; i < given.size(); ++i) given_text += (i ? ", " : "") + given[i];
  if (candidates.empty())
    throw Error(ErrorKind::Usage, "--method auto: no method reads all of " + given_text + ": give --method");
  const auto say = [&](const std::string& why) {
    if (!global.quiet) std::fprintf(stderr, "stex: --method auto: %s (%s)\n", o.method.c_str(), why.c_str());
  };
  if (candidates.size() == 1) {
    o.method = candidates[0];
    say("the only method that reads " + given_text);
    return;
  }
  std::vector<std::string> pickable;
  for (const std::string& k : candidates)
    if (k == kinds::texton || k == kinds::tb || k == kinds::cs_spot || k == kinds::cs_tb) pickable.push_back(k);
  if (pickable.empty())
    throw Error(ErrorKind::Usage, "--method auto picks texton, tb, cs-spot or cs-tb, and " + given_text +
                                      " belong to " + join_methods(candidates) + ": give --method");
  if (o.exemplar.empty()) throw Error(ErrorKind::Usage, "an exemplar image is required");
  LoadOptions lo;
  lo.linear = o.linear;
  lo.pixel_budget = o.pixel_budget;
  const KindChoice ch = choose_kind(load_exemplar(o.exemplar, lo), pickable);
  o.method = ch.kind;
  if ((ch.kind == kinds::cs_spot || ch.kind == kinds::cs_tb) && ch.lattice) {
    o.have_auto_periods = true;
    o.auto_periods = ch.periods;
  }
  say(ch.why);
}

// Checks that the options given suit --method, then runs that method's analysis.
void dispatch_analyze(const CLI::App& sub, AnalyzeOptions& o, const GlobalOptions& global) {
  o.iterations_given = sub.count("--iterations") > 0;
  if (o.method == "auto") pick_method(sub, o, global);
  const auto& methods = analysis_methods();
  const auto it = std::find_if(methods.begin(), methods.end(), [&](const AnalysisMethod& m) { return o.method == m.kind; });
  if (it == methods.end()) {
    std::vector<std::string> names;
    for (const AnalysisMethod& m : methods) names.push_back(m.kind);
    throw Error(ErrorKind::Usage, "unknown --method '" + o.method + "' (expected auto, " + join_methods(names) + ")");
  }
  check_method_options(sub, *it);
  if (it->needs_exemplar && o.exemplar.empty()) throw Error(ErrorKind::Usage, "an exemplar image is required");
  it->run(o, global);
}

// `stex export-texton MODEL -o IMAGE`.
void add_export_texton(CLI::App& app, GlobalOptions& global) {
  auto model = std::make_shared<std::string>();
  auto output = std::make_shared<std::string>();
  auto* exp =
      app.add_subcommand("export-texton",
                         "Write a model's texton coefficients as an image: .exr keeps the raw values; "
                         "png/tif/others are normalised to [0,1] for display (0.5 = zero).");
  exp->add_option("model", *model, "Model file (.stex)")->required();
  exp->add_option("-o,--output", *output, "Output image")->required();
  exp->callback([model, output, &global] { run_export(*model, *output, global); });
}

}  // namespace

void add_analyze(CLI::App& app, GlobalOptions& global) {
  auto opts = std::make_shared<AnalyzeOptions>();
  auto* sub = app.add_subcommand(
      "analyze",
      "Analyse an exemplar into a noise model of the kind --method names: auto (default: the kind the exemplar "
      "suits, docs/auto.md), texton (S1 Algorithm 1, colour phase projection and colour covariance correction; "
      "S2's SOT with --order 0), lrp (S3), gabor, cs-spot (S4), tb or cs-tb. Alpha channels are dropped with a warning. By default the file's encoded values are modelled "
      "as they are; --linear decodes sRGB first (renders are encoded back). Options of other methods than the "
      "one chosen are refused (exit 2).");
  add_texton_options(sub, opts.get());
  add_lrp_options(sub, opts.get());
  add_cs_options(sub, opts.get());
  // Every option the method table names exists (get_option throws otherwise: a misspelt name would make an
  // option of some methods one of every method), and --help groups them by the methods that read them.
  for (const AnalysisMethod& m : analysis_methods())
    for (const std::string& name : m.options) sub->get_option(name);
  for (CLI::Option* opt : sub->get_options()) {
    const std::vector<std::string> readers = methods_reading(opt->get_name());
    if (!readers.empty()) opt->group("Options of --method " + join_methods(readers));
  }
  sub->callback([opts, sub, &global] { dispatch_analyze(*sub, *opts, global); });
  add_export_texton(app, global);
}

}  // namespace stex::cli
