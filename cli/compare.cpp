// `stex compare A B [--json] [--linear] [--pixel-budget N]`: compares two Gaussian texture models (S2 §2.3,
// §3.2) given as exemplars, renders (any image) or model files (.stex), printing each one's mean and colour
// covariance and their L2 optimal-transport distance (S2 eq. 1) and RMEs. A thin client of
// analysis/ot_distance.h.
//
// Inputs: an image u stands for its estimated Gaussian model, mean + CADSN(t_u) with t_u the normalised
// periodic component (S2 eq. 3); a model for mean + texton noise covariance, h^ = sqrt(b^) alpha^ (b^ = 1 for
// order 0). Domain Theta: the larger, per dimension, of the inputs' natural domains (an image's own size; a
// model's exemplar size as recorded in the model, or (2 (s + order) - 1)^2 if none is recorded: the support
// of its covariance, so that no lag wraps around). Kernels smaller than Theta are zero-padded at the origin
// (S2 §2.4). Comparing a model with its own exemplar therefore uses the exemplar's grid, where the analysis
// measured its RME.
//
// Errors (README "Exit codes"): 2 bad options; 3 a missing/unreadable/corrupt input, or inputs with different
// channel counts; 5 an input or Theta above --pixel-budget.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/image_io.h"
#include "model/codecs.h"
#include "analysis/ot_distance.h"
#include "cli/commands.h"
#include "core/error.h"

namespace stex::cli {
namespace {

struct CompareOptions {
  std::string a, b;
  bool json = false, linear = false;
  std::uint64_t pixel_budget = std::uint64_t(1) << 26;
};

void warn(const std::string& w) { std::fprintf(stderr, "stex: warning: %s\n", w.c_str()); }

bool is_model_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  if (!in.read(magic, sizeof magic)) return false;
  return std::memcmp(magic, "STEXMDL", 8) == 0;  // "STEXMDL\0" (docs/model-format.md)
}

struct Input {
  std::string path, kind;  // kind: "image" or "model"
  int width = 0, height = 0, channels = 0;
  int natural_width = 0, natural_height = 0;
  bool linear = false;
  Image image;
  TextonModel model;
};

Input load_input(const std::string& path, const CompareOptions& o) {
  Input in;
  in.path = path;
  if (is_model_file(path)) {
    in.kind = "model";
    in.model = load_model(path);
    const int reach = 2 * (in.model.support + in.model.order) - 1;
    in.width = in.height = in.model.support;
    in.channels = in.model.channels;
    in.linear = in.model.linear;
    const bool recorded =
        in.model.exemplar_width >= in.model.support && in.model.exemplar_height >= in.model.support;
    in.natural_width = recorded ? in.model.exemplar_width : reach;
    in.natural_height = recorded ? in.model.exemplar_height : reach;
    return in;
  }
  LoadOptions lo;
  lo.linear = o.linear;
  lo.pixel_budget = o.pixel_budget;
  std::vector<std::string> warnings;
  in.image = load_exemplar(path, lo, &warnings);
  for (const auto& w : warnings) warn(path + ": " + w);
  in.kind = "image";
  in.width = in.natural_width = in.image.width;
  in.height = in.natural_height = in.image.height;
  in.channels = in.image.channels;
  in.linear = o.linear;
  return in;
}

GaussianSpectrum spectrum_of(const Input& in, int w, int h) {
  return in.kind == "model" ? gaussian_spectrum_of_model(in.model, w, h)
                            : gaussian_spectrum_of_image(in.image, w, h);
}

nlohmann::ordered_json describe(const Input& in, const GaussianSpectrum& g, const std::vector<double>& cov) {
  nlohmann::ordered_json j;
  j["path"] = in.path;
  j["kind"] = in.kind;
  j["channels"] = in.channels;
  if (in.kind == "model") {
    j["order"] = in.model.order;
    j["support"] = in.model.support;
    j["exemplar"] = in.model.exemplar_name;
  } else {
    j["width"] = in.width;
    j["height"] = in.height;
  }
  j["natural_domain"] = {in.natural_width, in.natural_height};
  j["linear"] = in.linear;
  j["mean"] = nlohmann::ordered_json::array();
  for (int c = 0; c < g.channels; ++c) j["mean"].push_back(g.mean[c]);
  j["covariance"] = nlohmann::ordered_json::array();
  double trace = 0.0;
  for (int r = 0; r < g.channels; ++r) {
    nlohmann::ordered_json row = nlohmann::ordered_json::array();
    for (int c = 0; c < g.channels; ++c) row.push_back(cov[std::size_t(r) * g.channels + c]);
    j["covariance"].push_back(row);
    trace += cov[std::size_t(r) * g.channels + r];
  }
  j["variance"] = trace;
  return j;
}

std::string label(const Input& in) {
  char buf[160];
  if (in.kind == "model")
    std::snprintf(buf, sizeof buf, "model, order %d, support %d, %d channel%s", in.model.order,
                  in.model.support, in.channels, in.channels == 1 ? "" : "s");
  else
    std::snprintf(buf, sizeof buf, "image %dx%d, %d channel%s", in.width, in.height, in.channels,
                  in.channels == 1 ? "" : "s");
  return buf;
}

void print_input(const char* name, const Input& in, const GaussianSpectrum& g,
                 const std::vector<double>& cov) {
  std::printf("%s: %s (%s)\n", name, in.path.c_str(), label(in).c_str());
  std::printf("  mean             ");
  for (int c = 0; c < g.channels; ++c) std::printf(" %.6f", g.mean[c]);
  std::printf("\n  colour covariance");
  for (int r = 0; r < g.channels; ++r) {
    if (r > 0) std::printf("\n                   ");
    for (int c = 0; c < g.channels; ++c) std::printf(" %.6e", cov[std::size_t(r) * g.channels + c]);
  }
  std::printf("\n");
}

void run_compare(const CompareOptions& o, const GlobalOptions& global) {
  const Input a = load_input(o.a, o), b = load_input(o.b, o);
  if (a.channels != b.channels)
    throw Error(ErrorKind::Input, "'" + o.a + "' has " + std::to_string(a.channels) + " channel(s) and '" +
                                      o.b + "' has " + std::to_string(b.channels) +
                                      ": compare needs the same channel count");
  if (a.linear != b.linear)
    warn(
        "one input is in linear light and the other is not (--linear decodes images; models record their "
        "own)");
  const int w = std::max(a.natural_width, b.natural_width), h = std::max(a.natural_height, b.natural_height);
  if (std::uint64_t(w) * std::uint64_t(h) > o.pixel_budget)
    throw Error(ErrorKind::Limit, "the comparison domain " + std::to_string(w) + "x" + std::to_string(h) +
                                      " exceeds the pixel budget of " + std::to_string(o.pixel_budget));
  const GaussianSpectrum ga = spectrum_of(a, w, h), gb = spectrum_of(b, w, h);
  const std::vector<double> ca = spectrum_colour_covariance(ga), cb = spectrum_colour_covariance(gb);
  const OtDistance d = ot_distance(ga, gb);
  if (o.json) {
    nlohmann::ordered_json j;
    j["a"] = describe(a, ga, ca);
    j["b"] = describe(b, gb, cb);
    j["domain"] = {w, h};
    j["ot_distance"] = d.distance();
    j["ot_distance_squared"] = d.d2;
    j["mean_distance"] = std::sqrt(d.mean2);
    j["ot_distance_with_mean"] = d.distance_with_mean();
    j["variance_a"] = d.variance0;
    j["variance_b"] = d.variance1;
    j["rme_b_vs_a"] = d.rme_1_vs_0();
    j["rme_a_vs_b"] = d.rme_0_vs_1();
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  if (global.quiet) return;
  print_input("A", a, ga, ca);
  print_input("B", b, gb, cb);
  std::printf("domain Theta        %dx%d (largest natural domain; kernels zero-padded at the origin)\n", w,
              h);
  std::printf("OT distance (eq. 1) %.6e   (squared %.6e; per pixel, xi != 0)\n", d.distance(), d.d2);
  std::printf("  with the means    %.6e   (|mA - mB| = %.6e)\n", d.distance_with_mean(), std::sqrt(d.mean2));
  std::printf("RME of B against A  %.6f   (OT distance / A's marginal standard deviation %.6e)\n",
              d.rme_1_vs_0(), std::sqrt(d.variance0));
  std::printf("RME of A against B  %.6f\n", d.rme_0_vs_1());
}

}  // namespace

void add_compare(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<CompareOptions>();
  auto* sub = app.add_subcommand(
      "compare",
      "Compare two Gaussian texture models (S2 §2.3): exemplars or renders (through their estimated model: "
      "mean + "
      "t_u of the periodic component) or model files (.stex: texton spectrum sqrt(b^) alpha^). Prints the "
      "means, "
      "colour covariances, the L2 optimal-transport distance of S2 eq. 1 (per pixel, xi != 0; with the means "
      "too) and the RMEs (S2 §3.2) on a common domain: the larger of the inputs' natural domains (an image's "
      "size, a model's exemplar size), kernels zero-padded.");
  sub->add_option("a", o->a, "Reference: image or model file")->required();
  sub->add_option("b", o->b, "Compared: image or model file")->required();
  sub->add_flag("--json", o->json, "Print JSON instead of text");
  sub->add_flag("--linear", o->linear, "Decode sRGB images to linear light first");
  sub->add_option("--pixel-budget", o->pixel_budget, "Largest image and comparison domain, in pixels")
      ->capture_default_str();
  sub->footer("Exit codes: 0 ok, 2 usage, 3 bad or mismatched input, 5 pixel budget.");
  sub->callback([o, &global] { run_compare(*o, global); });
}

}  // namespace stex::cli
