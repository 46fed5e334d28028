// `stex cs-rpn -o MODEL.stex --periods x0,y0,x1,y1 --spectra FILE.json [--variant random-phase|gabor|phasor|fourier]
// ...`: makes a cyclostationary random-phase noise model from user spectra (S4 §4.2, Fig. 1 left and 4; kind
// "cs-rpn", runtime/cs_rpn.h, analysis/cs_rpn_model.h documents the spectra file). Render it with `stex
// render MODEL` (tiles, farm and service like every kind). Thin client.
#include <cstdio>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "analysis/cs_lattice.h"
#include "analysis/cs_rpn_model.h"
#include "analysis/expected_psd.h"
#include "cli/commands.h"
#include "core/error.h"

namespace stex::cli {
namespace {

struct CsRpnOptions {
  std::string output, periods, spectra, variant = "gabor";
  double mean = 0.5, bandwidth = 0.05, spacing = 16.0;
  int cosines = 16;
  bool bandwidth_given = false, spacing_given = false, cosines_given = false;
};

void run_cs_rpn(const CsRpnOptions& o, const GlobalOptions& global) {
  CsRpnModel m;
  m.variant = parse_cs_rpn_variant(o.variant);
  // The variant's own options; another variant's exit 2 naming the option (they would be ignored).
  const bool impulses = m.variant == CsRpnVariant::Gabor || m.variant == CsRpnVariant::Phasor;
  const bool lattice = m.variant == CsRpnVariant::RandomPhase;
  for (const auto& [given, name, ok, whose] :
       {std::tuple<bool, const char*, bool, const char*>{o.bandwidth_given, "--bandwidth", impulses, "gabor and phasor"},
        {o.spacing_given, "--spacing", lattice, "random-phase"},
        {o.cosines_given, "--cosines", lattice, "random-phase"}})
    if (given && !ok)
      throw Error(ErrorKind::Usage, std::string(name) + " does not apply to --variant " + o.variant +
                                        " (it is an option of " + whose + ")");
  const Lattice t = parse_lattice(o.periods);  // Error(Usage) naming the problem
  m.t0x = t.t0x;
  m.t0y = t.t0y;
  m.t1x = t.t1x;
  m.t1y = t.t1y;
  m.mean = o.mean;
  m.bandwidth = o.bandwidth;
  m.spacing = o.spacing;
  m.cosines = o.cosines;
  cs_rpn_load_spectra_file(m, o.spectra);
  try {
    validate_cs_rpn_model(m);
  } catch (const Error& e) {
    throw Error(ErrorKind::Usage, e.what());
  }
  save_container(to_container(m), o.output);
  if (global.quiet) return;
  std::size_t bins = 0;
  for (const CsRpnSpectrum& s : m.spectra) bins += s.bins.size() / 3;
  std::printf("cs-rpn model: %s (%s)\n", o.output.c_str(), cs_rpn_variant_name(m.variant).c_str());
  std::printf("  periods         t0 = (%.4f, %.4f), t1 = (%.4f, %.4f) pixels\n", m.t0x, m.t0y, m.t1x, m.t1y);
  std::printf("  spectra         %dx%d grid, %zu bins in all, bin width %.6g cycles/pixel\n", m.k0, m.k1, bins, m.bin);
  if (m.variant == CsRpnVariant::RandomPhase)
    std::printf("  lattice         spacing %.4g pixels, %d cosines per point\n", m.spacing, m.cosines);
  else
    std::printf("  bandwidth       a = %.6g /pixel\n", m.bandwidth);
  std::printf("  mean            %.6g\n", m.mean);
  // each spectrum's expected Welch PSD, rendered alone, against the spectrum itself (analysis/expected_psd.h)
  const std::vector<PsdComparison> checks = cs_rpn_check_spectra(m);
  std::printf("  spectrum        expected radial PSD of each spectrum rendered alone / the spectrum, 24 bins, T = %d:\n",
              cs_rpn_spectrum_period(m));
  std::size_t worst = 0;
  for (std::size_t g = 0; g < checks.size(); ++g) {
    if (checks[g].period == 0) continue;
    if (checks.size() <= 8)
      std::printf("    %-13zu %s\n", g, psd_comparison_summary(checks[g]).c_str());
    if (checks[g].displaced > checks[worst].displaced || checks[worst].period == 0) worst = g;
  }
  if (checks.size() > 8)
    std::printf("    worst         spectrum %zu: %s\n", worst, psd_comparison_summary(checks[worst]).c_str());
}

}  // namespace

void add_cs_rpn(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<CsRpnOptions>();
  auto* sub = app.add_subcommand(
      "cs-rpn",
      "Make a cyclostationary random-phase noise model from user spectra (S4 §4.2; kind 'cs-rpn'): a K0 x K1 grid "
      "of spectra laid over the parallelogram (t0, t1), interpolated bilinearly into the local PSD, rendered as "
      "local random-phase, Gabor or phasor noise, or as S4 Fig. 4's Fourier series. Render it with `stex render`.");
  sub->add_option("-o,--output", o->output, "Output model file (.stex)")->required();
  sub->add_option("--periods", o->periods, "Period vectors t0, t1 in pixels: x0,y0,x1,y1")->required();
  sub->add_option("--spectra", o->spectra,
                  "Spectra file (JSON): {\"grid\": [K0, K1], \"size\": T, \"spectra\": [\"bilobe:F,ANGLE,W\" | "
                  "{\"psd\": SPEC, \"variance\": V} | {\"image\": PATH, \"variance\": V}, ...]} (docs/cyclostationary.md)")
      ->required();
  sub->add_option("--variant", o->variant, "random-phase | gabor | phasor | fourier (S4 Fig. 4: a Fourier series, repeats every T pixels)")->capture_default_str();
  sub->add_option("--mean", o->mean, "Output mean")->capture_default_str();
  sub->add_option("--bandwidth", o->bandwidth, "gabor, phasor: envelope bandwidth a, 1/pixel [1/1024, 1]")->capture_default_str();
  sub->add_option("--spacing", o->spacing, "random-phase: lattice spacing Delta, pixels [1, 4096]")->capture_default_str();
  sub->add_option("--cosines", o->cosines, "random-phase: cosines J per lattice point (1..256)")->capture_default_str();
  sub->callback([o, sub, &global] {
    o->bandwidth_given = sub->count("--bandwidth") > 0;
    o->spacing_given = sub->count("--spacing") > 0;
    o->cosines_given = sub->count("--cosines") > 0;
    run_cs_rpn(*o, global);
  });
}

}  // namespace stex::cli
