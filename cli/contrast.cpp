// `stex contrast IMAGE`: the contrast field of an image (S5 Fig. 9e: windowed second moment at stationarity
// scale L) and its variance spectrum (Fig. 6, 9f), with statistics; `stex renormalize`: S5's contrast
// renormalisation (Fig. 10: simple and quality modes) with the options of Fig. 14-17 and the applications of
// Fig. 1, 11-13 (colour LUT, content constraint), on an image or, deterministically, on a region of a model
// (tiles). Thin clients of analysis/contrast.h.
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/contrast.h"
#include "analysis/gabor_model.h"
#include "analysis/image_io.h"
#include "model/codecs.h"
#include "model/kinds.h"
#include "model/kinds.h"
#include "cli/commands.h"
#include "core/error.h"
#include "runtime/selftest.h"

namespace stex::cli {
namespace {

[[noreturn]] void usage(const std::string& m) { throw Error(ErrorKind::Usage, m); }

std::string lower_ext(const std::string& path) {
  const auto dot = path.find_last_of('.');
  std::string e = dot == std::string::npos ? "" : path.substr(dot + 1);
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}
bool is_float_ext(const std::string& p) {
  const std::string e = lower_ext(p);
  return e == "exr" || e == "hdr" || e == "tif" || e == "tiff";
}

void write(const std::string& path, const Image& img, const std::string& what) {
  WriteOptions wo;
  wo.metadata.push_back({"Software", std::string("stex ") + STEX_VERSION_STRING});
  wo.metadata.push_back({"ImageDescription", what});
  write_image_atomic(path, img, wo);
}

Image grey(int w, int h, const std::vector<double>& v, double scale) {
  Image im;
  im.width = w;
  im.height = h;
  im.channels = 1;
  im.pixels.resize(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) im.pixels[i] = float(v[i] * scale);
  return im;
}

struct ContrastCli {
  std::string image, field, spectrum, fft = "host";
  double L = 32.0;
  bool json = false;
  std::uint64_t pixel_budget = std::uint64_t(1) << 26;
};

void run_contrast(const ContrastCli& o, const GlobalOptions& global) {
  LoadOptions lo;
  lo.pixel_budget = o.pixel_budget;
  lo.what = "image";
  const Image im = load_exemplar(o.image, lo);
  ContrastOptions co;
  co.L = o.L;
  co.fft = o.fft;
  std::unique_ptr<Context> ctx;
  if (o.fft == "device") ctx = Context::create(global.device);
  const ContrastField f = contrast_field(im, co, ctx.get());
  if (!o.field.empty()) {
    // png: C / max C; float formats: C itself.
    const double scale = is_float_ext(o.field) ? 1.0 : (f.stats.max > 0 ? 1.0 / *std::max_element(f.contrast.begin(), f.contrast.end()) : 1.0);
    write(o.field, grey(f.width, f.height, f.contrast, scale), "stex contrast field (L = " + std::to_string(o.L) + ")");
  }
  if (!o.spectrum.empty()) {
    // Centred variance spectrum; png: log(1 + 1e4 V / max V) / log(1 + 1e4) for display.
    std::vector<double> v = f.variance_spectrum;
    if (!is_float_ext(o.spectrum)) {
      const double peak = *std::max_element(v.begin(), v.end());
      for (double& x : v) x = peak > 0 ? std::log1p(1e4 * x / peak) / std::log1p(1e4) : 0.0;
    }
    write(o.spectrum, grey(f.width, f.height, v, 1.0), "stex variance spectrum (centred)");
  }
  const ContrastStats& s = f.stats;
  if (o.json) {
    std::printf(
        "{\"width\": %d, \"height\": %d, \"L\": %.17g, \"mean\": %.17g, \"contrast\": {\"mean\": %.17g, \"std\": %.17g, "
        "\"cov\": %.17g, \"min\": %.17g, \"max\": %.17g, \"margin\": %d}}\n",
        f.width, f.height, o.L, f.mean, s.mean, s.stddev, s.cov, s.min, s.max, s.margin);
    return;
  }
  if (global.quiet) return;
  std::printf("contrast field of %s (%dx%d, L = %g: window std %g pixels)\n", o.image.c_str(), f.width, f.height, o.L,
              o.L / 2);
  std::printf("  image mean        %.6g\n", f.mean);
  std::printf("  contrast          mean %.6g, std %.6g, min %.6g, max %.6g (interior: margin %d)\n", s.mean, s.stddev,
              s.min, s.max, s.margin);
  std::printf("  coefficient of variation  %.4f\n", s.cov);
}

struct RenormCli {
  std::string image, output, mode = "simple", select = "lf", model, size, origin = "0,0", fft = "host";
  std::string contrast_map, dominance, dominance_map, drawing, lut, raw_output;
  std::vector<std::string> lobes, layers;
  double L = 32.0, min_contrast = 1e-2, footprint_threshold = 1e-2, weight = 0.5, overlap = 3.0;
  int iterations = 4;
  bool smooth_footprint = false, json = false;
  RenderParams params;
  std::uint64_t pixel_budget = std::uint64_t(1) << 26;
};

std::array<double, 2> parse_pair(const std::string& s, const char* what) {
  std::stringstream ss(s);
  std::string a, b;
  if (!std::getline(ss, a, ',') || !std::getline(ss, b, ',')) usage(std::string(what) + " must be X,Y, got '" + s + "'");
  try {
    std::size_t ua = 0, ub = 0;
    const double x = std::stod(a, &ua), y = std::stod(b, &ub);
    if (ua != a.size() || ub != b.size()) throw std::invalid_argument(s);
    return {x, y};
  } catch (const std::exception&) {
    usage(std::string(what) + " must be X,Y, got '" + s + "'");
  }
}

void run_renormalize(const RenormCli& o, const GlobalOptions& global) {
  if (o.mode != "simple" && o.mode != "quality" && o.mode != "none")
    usage("--mode must be simple, quality or none, got '" + o.mode + "'");
  RenormOptions ro;
  ro.L = o.L;
  ro.fft = o.fft;
  ro.quality = o.mode == "quality";
  ro.iterations = o.iterations;
  ro.min_contrast = o.min_contrast;
  ro.selection = parse_lobe_selection(o.select);
  ro.footprint_threshold = o.footprint_threshold;
  ro.smooth_footprint = o.smooth_footprint;
  for (const std::string& l : o.lobes) {
    const auto p = parse_pair(l, "--lobe");
    ro.lobes.push_back(p);
    ro.lobes.push_back({-p[0], -p[1]});
  }
  LoadOptions lo;
  lo.pixel_budget = o.pixel_budget;
  lo.what = "image";
  std::unique_ptr<Context> ctx;
  auto context = [&]() -> Context* {
    if (!ctx) ctx = Context::create(global.device);
    return ctx.get();
  };
  std::unique_ptr<ModelContainer> container;
  GaborModel gm;
  if (!o.model.empty()) {
    container = std::make_unique<ModelContainer>(load_container(o.model));
    if (container->kind == "gabor") {
      gm = gabor_from_container(*container, o.model);
      const std::vector<std::array<double, 2>> l = gabor_lobes(gm);
      if (ro.lobes.empty()) ro.lobes = l;
      ro.footprint_psd = [gm](double u, double v) { return gabor_psd(gm, u, v); };
    }
  }
  Image result;
  RenormReport rep;
  std::string what;
  if (!o.size.empty()) {
    // A region of a model, deterministic: mean and Cref are the model's mean and std.
    if (!container) usage("--size renders a region of --model: give --model");
    if (!o.image.empty()) usage("give an IMAGE or --model with --size, not both");
    if (container->kind != "gabor") usage("tiled renormalisation needs a gabor model (its mean, std and PSD)");
    int w = 0, h = 0;
    if (std::sscanf(o.size.c_str(), "%dx%d", &w, &h) != 2 || w < 1 || h < 1) usage("--size must be WIDTHxHEIGHT");
    if (std::uint64_t(w) * std::uint64_t(h) > o.pixel_budget) throw Error(ErrorKind::Limit, "--size exceeds --pixel-budget");
    const auto org = parse_pair(o.origin, "--origin");
    ro.mean = gm.mean;
    ro.reference_contrast = gm.stddev;
    ensure_selftest(*context(), selftest_rows_for(*container, o.params, {}, context()->info(), o.model));
    RenormalizedNoise rn(*context(), make_noise_renderer(*context(), *container, {}, o.model), ro, o.overlap);
    result.width = w;
    result.height = h;
    result.channels = rn.channels();
    result.pixels.resize(std::size_t(w) * h * result.channels);
    rn.render(o.params, std::int64_t(org[0]), std::int64_t(org[1]), w, h, result.pixels.data());
    what = "stex renormalize (" + o.mode + ", L = " + std::to_string(o.L) + ") of " + o.model;
  } else {
    if (o.image.empty()) usage("give an IMAGE (or --model with --size)");
    const Image im = load_exemplar(o.image, lo);
    Context* c = o.fft == "device" ? context() : nullptr;
    if (!o.layers.empty()) {
      std::vector<Image> layers{im};
      for (const std::string& l : o.layers) layers.push_back(load_exemplar(l, lo));
      result = renormalize_layers(layers, ro, c);
    } else if (!o.dominance.empty()) {
      if (o.dominance_map.empty()) usage("--dominance needs --dominance-map");
      result = dominance_blend(im, load_exemplar(o.dominance, lo), load_exemplar(o.dominance_map, lo), ro, c);
    } else if (!o.drawing.empty()) {
      result = content_constraint(im, load_exemplar(o.drawing, lo), o.weight, ro, c);
    } else if (o.mode == "none") {
      result = im;  // no renormalisation: the LUT or contrast map alone (the "raw" pictures)
    } else {
      result = renormalize(im, ro, c, &rep);
    }
    if (!o.contrast_map.empty()) {
      double mean = 0.0;
      for (float v : result.pixels) mean += v;
      mean /= double(result.pixels.size());
      result = apply_contrast_map(result, load_exemplar(o.contrast_map, lo), mean);
    }
    what = "stex renormalize (" + o.mode + ", L = " + std::to_string(o.L) + ") of " + o.image;
  }
  if (!o.raw_output.empty()) write(o.raw_output, result, what);
  if (!o.lut.empty()) result = apply_lut(result, load_exemplar(o.lut, lo));
  write(o.output, result, what + (o.lut.empty() ? "" : " with LUT " + o.lut));
  if (!global.quiet && !o.size.empty()) {
    // A region of a model: tiles renormalised with the model's own mean, std and PSD (no passes to report).
    std::printf("renormalised %dx%d pixels at (%s) of %s -> %s (%s mode, L = %g, %d channel%s)\n", result.width,
                result.height, o.origin.c_str(), o.model.c_str(), o.output.c_str(), o.mode.c_str(), o.L,
                result.channels, result.channels == 1 ? "" : "s");
    return;
  }
  if (global.quiet || rep.passes.empty()) return;
  if (o.json) {
    std::printf("{\"mode\": \"%s\", \"L\": %.17g, \"fft\": \"%s\", \"cov\": [", o.mode.c_str(), o.L, rep.fft_backend.c_str());
    for (std::size_t i = 0; i < rep.passes.size(); ++i) std::printf("%s%.17g", i ? ", " : "", rep.passes[i].cov);
    std::printf("]}\n");
    return;
  }
  std::printf("renormalised %s -> %s (%s mode, L = %g, %s FFT)\n", o.image.c_str(), o.output.c_str(), o.mode.c_str(),
              o.L, rep.fft_backend.c_str());
  std::printf("  contrast CoV      %.4f before, %.4f after (factor %.2f)\n", rep.passes.front().cov,
              rep.passes.back().cov, rep.passes.back().cov > 0 ? rep.passes.front().cov / rep.passes.back().cov : 0.0);
}

}  // namespace

void add_contrast(CLI::App& app, GlobalOptions& global) {
  auto c = std::make_shared<ContrastCli>();
  auto* sub = app.add_subcommand(
      "contrast",
      "Contrast field of an image (S5: windowed second moment at stationarity scale L) and its variance "
      "spectrum; prints the field's statistics (mean, std, coefficient of variation).");
  sub->add_option("image", c->image, "Image (render) to analyse")->required();
  sub->add_option("--L", c->L, "Stationarity scale L in pixels (window: Gaussian of std L/2)")->capture_default_str();
  sub->add_option("--field", c->field, "Write the contrast field (png: C / max C; exr/tif: C)");
  sub->add_option("--spectrum", c->spectrum, "Write the centred variance spectrum (png: log scale)");
  sub->add_option("--fft", c->fft, "host (FFTW) or device (clFFT where the size allows)")->capture_default_str();
  sub->add_flag("--json", c->json, "Print the statistics as JSON");
  sub->add_option("--pixel-budget", c->pixel_budget, "Largest image accepted, in pixels")->capture_default_str();
  sub->callback([c, &global] { run_contrast(*c, global); });

  auto r = std::make_shared<RenormCli>();
  auto* rs = app.add_subcommand(
      "renormalize",
      "S5 contrast renormalisation of an image (or, with --model and --size, of a region of a gabor model, "
      "deterministically: tiles join), simple or quality mode, with the options of S5 Fig. 13-17 and a colour "
      "LUT.");
  rs->add_option("image", r->image, "Image (render) to renormalise");
  rs->add_option("-o,--output", r->output, "Output image")->required();
  rs->add_option("--mode", r->mode, "simple (one pass), quality (iterated passes + spectrum reprofiling), none (only --lut / --contrast-map)")
      ->capture_default_str();
  rs->add_option("--L", r->L, "Stationarity scale L in pixels")->capture_default_str();
  rs->add_option("--iterations", r->iterations, "Passes of the quality mode")->capture_default_str();
  rs->add_option("--min-contrast", r->min_contrast, "minC of S5 Fig. 10")->capture_default_str();
  rs->add_option("--select", r->select,
                 "Variance-spectrum features collected (S5 Fig. 14): lf, lf+interferences, lf+pure")
      ->capture_default_str();
  rs->add_option("--lobe", r->lobes, "A spectrum lobe centre FX,FY in cycles/pixel (its mirror is added); repeatable");
  rs->add_option("--model", r->model, "gabor model: its lobes, its PSD as footprint, and (with --size) the noise");
  rs->add_option("--footprint-threshold", r->footprint_threshold, "Footprint: PSD >= threshold x peak")
      ->capture_default_str();
  rs->add_flag("--smooth-footprint", r->smooth_footprint, "Smooth footprint variant (sqrt of the normalised PSD)");
  rs->add_option("--contrast-map", r->contrast_map, "S5 Fig. 16a: multiply the result by this contrast map");
  rs->add_option("--dominance", r->dominance, "S5 Fig. 16b: second noise, lerped by --dominance-map");
  rs->add_option("--dominance-map", r->dominance_map, "Dominance map (0: IMAGE, 1: --dominance)");
  rs->add_option("--layer", r->layers, "S5 Fig. 17: more layers, each normalised separately, then summed");
  rs->add_option("--drawing", r->drawing, "S5 Fig. 13: content constraint from this drawing");
  rs->add_option("--weight", r->weight, "Weight of the noise in lerp(drawing, noise, w)")->capture_default_str();
  rs->add_option("--lut", r->lut, "Colour LUT image (row 0, left = low) applied after renormalisation");
  rs->add_option("--raw-output", r->raw_output, "Also write the renormalised image before the LUT");
  rs->add_option("--size", r->size, "With --model: render and renormalise this region WIDTHxHEIGHT");
  rs->add_option("--origin", r->origin, "With --size: top-left pixel X,Y")->capture_default_str();
  rs->add_option("--overlap", r->overlap, "With --size: overlap around the region, in units of L")->capture_default_str();
  rs->add_option("--seed", r->params.seed, "With --size: seed of the noise");
  rs->add_option("--mni", r->params.mni, "With --size: impulses per kernel")->capture_default_str();
  rs->add_option("--fft", r->fft, "host (FFTW) or device (clFFT where the size allows)")->capture_default_str();
  rs->add_flag("--json", r->json, "Print the contrast statistics as JSON");
  rs->add_option("--pixel-budget", r->pixel_budget, "Largest image accepted, in pixels")->capture_default_str();
  rs->callback([r, &global] { run_renormalize(*r, global); });
}

}  // namespace stex::cli
