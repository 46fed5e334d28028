// `stex analyze-mix A B -o MIX.stex [--levels K] [--support S] [--iterations N] [--seed N] [--order 0|1|3|5]
//  [--linear] [--no-colour-correction] [--mix-map SPEC [--mix-scale S] [--mix-origin X,Y] [--mix-wrap W]]`:
// noise mixing (S1 §7, analysis/mix.h): the OT barycentres tau_rho between the Gaussian models of A (rho = 0)
// and B (rho = 1), K textons alpha_{rho_k} by S1 Algorithm 1 from one shared initial noise, stored with both
// means and a default mixing map as a model of kind "mix" (docs/mixing.md), rendered by `stex render`. A thin
// client of analysis/mix; errors are stex::Error, mapped to exit codes by main.cpp.
#include <cstdio>
#include <memory>
#include <string>

#include "analysis/mix.h"
#include "model/codecs.h"
#include "cli/commands.h"
#include "core/error.h"

namespace stex::cli {
namespace {

struct AnalyzeMixOptions {
  std::string a, b, output;
  MixParams params;
  bool linear = false, no_colour_correction = false;
  std::string map = "ramp:0:1024", map_origin = "0,0", map_wrap = "repeat";
  double map_scale = 1.0;
  std::uint64_t pixel_budget = std::uint64_t(1) << 26;
};

void run_analyze_mix(const AnalyzeMixOptions& o, bool map_image_options, const GlobalOptions& global) {
  MixParams p = o.params;
  p.colour_correction = !o.no_colour_correction;
  // Parameters first (the map image is small and read here; the exemplars after).
  if (p.levels < 2 || p.levels > STEX_MIX_MAX_LEVELS)
    throw Error(ErrorKind::Usage, "--levels must be in [2, " + std::to_string(STEX_MIX_MAX_LEVELS) + "], got " +
                                      std::to_string(p.levels));
  p.map = parse_mix_map(o.map, o.map_scale, o.map_origin, o.map_wrap, map_image_options);
  LoadOptions lo;
  lo.linear = o.linear;
  lo.pixel_budget = o.pixel_budget;
  MixReport rep;
  const MixModel m = analyse_mix_files(o.a, o.b, lo, p, &rep);
  for (const std::string& w : rep.warnings) std::fprintf(stderr, "stex: warning: %s\n", w.c_str());
  save_container(to_container(m), o.output);
  if (global.quiet) return;
  std::printf("mix model: %s\n", o.output.c_str());
  std::printf("  exemplars       %s (rho = 0), %s (rho = 1); grid %dx%d, %d channel%s%s\n", m.exemplar_name[0].c_str(),
              m.exemplar_name[1].c_str(), m.exemplar_width, m.exemplar_height, m.channels, m.channels == 1 ? "" : "s",
              m.linear ? ", linear light" : "");
  std::printf("  levels          %d (rho = k/%d), support %dx%d, order %d, %d iterations, seed %llu\n", m.levels,
              m.levels - 1, m.support, m.support, m.order, m.iterations,
              static_cast<unsigned long long>(m.analysis_seed));
  std::printf("  OT distance     d_OT(tau_0, tau_1) = %.6g\n", m.ot_distance);
  std::printf("  RME per level  ");
  for (double r : m.rme) std::printf(" %.3f", r);
  std::printf("\n  mixing map      %s\n", mix_map_spec(m.map).c_str());
  std::printf("  time            %.1f ms\n", rep.ms_total);
}

}  // namespace

void add_analyze_mix(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<AnalyzeMixOptions>();
  auto* sub = app.add_subcommand(
      "analyze-mix",
      "Noise mixing (S1 §7, docs/mixing.md): analyse two exemplars A (rho = 0) and B (rho = 1) into one model of "
      "kind mix: K textons of the optimal-transport barycentres tau_rho, rho = k/(K-1), computed by Algorithm 1 "
      "from one shared initial noise, both means, and a default mixing map. `stex render` renders it (the map "
      "can be replaced there with --mix-map). Exemplars of different sizes are cropped to the common size; a "
      "grey exemplar mixed with a colour one is replicated to colour.");
  sub->add_option("a", o->a, "Exemplar A (rho = 0)")->required();
  sub->add_option("b", o->b, "Exemplar B (rho = 1)")->required();
  sub->add_option("-o,--output", o->output, "Output model file (.stex)")->required();
  sub->add_option("--levels", o->params.levels,
                  "K, the number of barycentres (textons) on the regular grid rho = k/(K-1) in [0, 1]; S1 Fig. 5 "
                  "uses 21")
      ->capture_default_str();
  sub->add_option("--support", o->params.support, "Texton support s (s x s coefficients per level)")
      ->capture_default_str()
      ->check(CLI::Range(1, 4096));
  sub->add_option("--iterations", o->params.iterations, "Iterations of Algorithm 1 per level")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  sub->add_option("--seed", o->params.seed, "Seed of the shared random initialisation")->capture_default_str();
  sub->add_option("--order", o->params.order, "Interpolation order: 1 bilinear (S1), 0 nearest, 3 cubic, 5 quintic")
      ->capture_default_str()
      ->check(CLI::IsMember({0, 1, 3, 5}));
  sub->add_flag("--linear", o->linear, "Decode sRGB to linear light before the analysis");
  sub->add_flag("--no-colour-correction", o->no_colour_correction, "Skip the colour covariance correction");
  sub->add_option("--pixel-budget", o->pixel_budget, "Largest exemplar accepted, in pixels")->capture_default_str();
  sub->add_option("--mix-map", o->map,
                  "Default mixing map stored in the model, in output pixels: const:RHO, ramp:X0:X1 (rho from 0 at "
                  "x = X0 to 1 at x = X1: S1 Fig. 5's strips), strips:PERIOD[:WIDTH] (rho 0 then 1 each half "
                  "period, edges ramped over WIDTH), or a grey image file (0 = A, 1 = B)")
      ->capture_default_str();
  sub->add_option("--mix-scale", o->map_scale, "Image maps: output pixels per map pixel (default 1)");
  sub->add_option("--mix-origin", o->map_origin, "Image maps: output pixel X,Y of the map's top-left corner (default 0,0)");
  sub->add_option("--mix-wrap", o->map_wrap, "Image maps: repeat (default) or clamp outside the map");
  sub->callback([o, sub, &global] {
    const bool image_opts = sub->count("--mix-scale") || sub->count("--mix-origin") || sub->count("--mix-wrap");
    run_analyze_mix(*o, image_opts, global);
  });
}

}  // namespace stex::cli
