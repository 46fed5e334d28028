// `stex gabor -o MODEL.stex ...`: makes a Gabor noise model (kind "gabor", runtime/gabor_params.h) from
// parameters (anisotropic, isotropic, multi-lobe, explicit components), from a PSD image, or from an
// exemplar's power spectrum (analysis/gabor_model.h). Render it with `stex render MODEL`. Thin client.
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/expected_psd.h"
#include "analysis/gabor_model.h"
#include "analysis/image_io.h"
#include "cli/commands.h"
#include "core/error.h"

namespace stex::cli {
namespace {

constexpr double k_deg = k_gabor_pi / 180.0;

struct GaborOptions {
  std::string output, psd, exemplar;
  double frequency = 0.08, orientation = 0.0, spread = 0.0, bandwidth = 0.05, mean = 0.5, stddev = 0.15;
  bool isotropic = false;
  int lobes = 2, grid = 64, max_components = STEX_GABOR_MAX_COMPONENTS;
  std::vector<std::string> components;
  std::uint64_t pixel_budget = std::uint64_t(1) << 26;
};

GaborComponent parse_component(const std::string& text) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      std::size_t used = 0;
      v.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw Error(ErrorKind::Usage, "--component '" + text + "': '" + item + "' is not a number");
    }
  }
  if (v.size() < 2 || v.size() > 4)
    throw Error(ErrorKind::Usage, "--component '" + text + "' must be F,ORIENTATION[,SPREAD[,WEIGHT]] (degrees)");
  GaborComponent c;
  c.frequency = v[0];
  c.orientation = v[1] * k_deg;
  c.spread = v.size() > 2 ? v[2] * k_deg : 0.0;
  c.weight = v.size() > 3 ? v[3] : 1.0;
  return c;
}

void run_gabor(const GaborOptions& o, const GlobalOptions& global) {
  GaborModel m;
  m.bandwidth = o.bandwidth;
  m.mean = o.mean;
  m.stddev = o.stddev;
  std::string how;
  int dropped = 0;
  Image reference;  // the exemplar or the PSD image, for the spectrum check
  bool from_exemplar = false;
  if (!o.psd.empty() || !o.exemplar.empty()) {
    if (!o.psd.empty() && !o.exemplar.empty()) throw Error(ErrorKind::Usage, "give --psd or --exemplar, not both");
    if (!o.components.empty()) throw Error(ErrorKind::Usage, "--component does not combine with --psd/--exemplar");
    LoadOptions lo;
    lo.pixel_budget = o.pixel_budget;
    Image psd;
    if (!o.psd.empty()) {
      LoadOptions plo = lo;
      plo.what = "PSD image";
      psd = load_exemplar(o.psd, plo);
      reference = psd;
      how = "PSD image " + o.psd;
    } else {
      double mean = 0.0, sd = 0.0;
      reference = load_exemplar(o.exemplar, lo);
      from_exemplar = true;
      psd = exemplar_psd(reference, o.grid, &mean, &sd);
      m.mean = mean;
      m.stddev = sd;
      how = "power spectrum of " + o.exemplar + " on a " + std::to_string(o.grid) + "^2 grid";
    }
    GaborModel from = gabor_model_from_psd(psd, o.bandwidth, o.max_components, 0.0, &dropped);
    m.components = from.components;
  } else if (!o.components.empty()) {
    m.components.clear();
    for (const std::string& c : o.components) m.components.push_back(parse_component(c));
    how = std::to_string(m.components.size()) + " explicit components";
  } else {
    if (o.lobes < 2 || o.lobes % 2 != 0 || o.lobes > 64)
      throw Error(ErrorKind::Usage, "--lobes must be even, 2..64 (a component makes the 2 lobes +-f), got " +
                                        std::to_string(o.lobes));
    m.components.clear();
    const int n = o.isotropic ? 1 : o.lobes / 2;
    for (int k = 0; k < n; ++k) {
      GaborComponent c;
      c.frequency = o.frequency;
      c.orientation = o.orientation * k_deg + k * k_gabor_pi / n;
      c.spread = o.isotropic ? 2.0 * k_gabor_pi : o.spread * k_deg;
      m.components.push_back(c);
    }
    how = o.isotropic ? "isotropic" : (std::to_string(o.lobes) + "-lobe" + (o.spread > 0 ? " (spread)" : ""));
  }
  // The file stores float32 components: report and save what the file gives back.
  try {
    validate_gabor_model(m);
  } catch (const Error& e) {
    throw Error(ErrorKind::Usage, e.what());
  }
  save_container(to_container(m), o.output);
  if (global.quiet) return;
  std::printf("gabor model: %s (%s)\n", o.output.c_str(), how.c_str());
  std::printf("  bandwidth       a = %.6g /pixel: kernel radius %.2f pixels, lobe std %.4g cycles/pixel\n",
              m.bandwidth, gabor_radius(m.bandwidth), m.bandwidth / (2.0 * std::sqrt(k_gabor_pi)));
  std::printf("  components      %zu%s\n", m.components.size(),
              dropped ? (" (" + std::to_string(dropped) + " PSD bins dropped: beyond 0.5 cycles/pixel or over "
                                                           "--max-components)")
                            .c_str()
                      : "");
  std::printf("  mean, std       %.6g, %.6g\n", m.mean, m.stddev);
  // the model's expected spectrum (analysis/expected_psd.h) against what it was made from
  if (from_exemplar) {
    std::printf("  spectrum        expected radial PSD / exemplar's Welch PSD (channel mean), 24 bins: %s\n",
                psd_comparison_summary(gabor_check_against_exemplar(m, reference)).c_str());
  } else if (!o.psd.empty()) {
    const std::optional<PsdComparison> c = gabor_check_against_psd_image(m, reference);
    if (c)
      std::printf("  spectrum        expected radial PSD / the given PSD, 24 bins: %s\n", psd_comparison_summary(*c).c_str());
    else
      std::printf("  spectrum        not checked (the PSD image is not square with a power-of-two side 16..1024)\n");
  }
}

}  // namespace

void add_gabor(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<GaborOptions>();
  auto* sub = app.add_subcommand(
      "gabor",
      "Make a Gabor noise model (sparse Gabor convolution, Lagae et al. 2009; kind 'gabor'): anisotropic "
      "(default: 2 lobes), multi-lobe (--lobes), isotropic, explicit components, from a PSD image or from an "
      "exemplar's power spectrum. Render it with `stex render`.");
  sub->add_option("-o,--output", o->output, "Output model file (.stex)")->required();
  sub->add_option("--frequency", o->frequency, "Frequency F, cycles per pixel [0, 0.5]")->capture_default_str();
  sub->add_option("--orientation", o->orientation, "Orientation of the first component, degrees")
      ->capture_default_str();
  sub->add_option("--spread", o->spread, "Orientation spread of each component, degrees [0, 360]")
      ->capture_default_str();
  sub->add_flag("--isotropic", o->isotropic, "Isotropic noise (one component, spread 360 degrees)");
  sub->add_option("--lobes", o->lobes,
                  "Number of spectral lobes (even): lobes/2 components at orientations 180/(lobes/2) apart")
      ->capture_default_str();
  sub->add_option("--bandwidth", o->bandwidth, "Gaussian bandwidth a, 1/pixel [1/1024, 1] (radius ~1.63/a)")
      ->capture_default_str();
  sub->add_option("--mean", o->mean, "Output mean")->capture_default_str();
  sub->add_option("--std", o->stddev, "Output standard deviation")->capture_default_str();
  sub->add_option("--component", o->components,
                  "Explicit component F,ORIENTATION[,SPREAD[,WEIGHT]] (cycles/pixel, degrees); repeatable");
  sub->add_option("--psd", o->psd,
                  "PSD image: pixel (i, j) is the power at ((i - w/2)/w, (j - h/2)/h) cycles/pixel (channel 0)");
  sub->add_option("--exemplar", o->exemplar, "Exemplar whose power spectrum (and mean, std) the model takes");
  sub->add_option("--grid", o->grid, "Frequency bins per axis for --exemplar")->capture_default_str();
  sub->add_option("--max-components", o->max_components, "Strongest PSD bins kept as components (1..4096)")
      ->capture_default_str();
  sub->add_option("--pixel-budget", o->pixel_budget, "Largest image accepted, in pixels")->capture_default_str();
  sub->callback([o, &global] { run_gabor(*o, global); });
}

}  // namespace stex::cli
