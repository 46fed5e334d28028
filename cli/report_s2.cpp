// `stex s2-report --out DIR [--exemplar PATH] [--crop N] [--inits N] [--iterations N] [--radius R]
//  [--radii LIST] [--fig5-iterations N] [--threads N] [--seed N] [--sample N] [--mni M]`: reproduces S2's
// Fig. 2 (mean and standard deviation of RME_n, the RME after n iterations of Algorithm 2, over random
// initialisations on a grey exemplar, n = 1..N) and Fig. 5 (SOTs with disc supports of radius 5, 15, 25:
// textons, samples, RMEs), and the comparison of S2 §4 / Fig. 4 (SOT vs the cropped luminance texton of DMR
// vs the cropped random-phase texton, same support) on the grey exemplar and two synthesised colour Gaussian
// textures with known spectra. Writes into DIR: fig2.svg (plot drawn by this file), fig2.csv, fig5_*.png,
// baseline_*.png, s2-report.md (tables), report.json (every number and parameter). docs/s2.md explains the
// committed run. A client of analysis/sot.h, luminance_texton.h, gaussian_synthesis.h.
//
// Samples: every ADSN sample (of t_u and of each SOT, on Z^2) uses the same seed, hence the same white noise:
// the pictures differ only by their kernels. The SOTs are shown without the colour correction (S2 applies it
// in Fig. 3 only), so their sample variance is the model's (variance kept < 1).
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/gaussian_synthesis.h"
#include "analysis/image_io.h"
#include "analysis/luminance_texton.h"
#include "analysis/sot.h"
#include "analysis/support_mask.h"
#include "cli/commands.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace stex::cli {
namespace {

struct S2ReportOptions {
  std::string out, exemplar, radii = "5,15,25";  // exemplar "": the source tree's data/gravel.png
  int crop = 128, inits = 100, iterations = 1000, radius = 15, fig5_iterations = 1000, threads = 1,
      sample = 256;
  std::uint64_t seed = 0;
  double mni = 30.0;
};

using Json = nlohmann::ordered_json;

void write_text(const std::string& path, const std::string& text) {
  write_file_atomic(path, text.data(), text.size());
}

std::vector<int> parse_int_list(const std::string& s, const char* what) {
  std::vector<int> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      std::size_t used = 0;
      const int v = std::stoi(item, &used);
      if (used != item.size() || v < 0) throw std::invalid_argument(item);
      out.push_back(v);
    } catch (const std::exception&) {
      throw Error(ErrorKind::Usage, std::string(what) + ": '" + item + "' is not a non-negative integer");
    }
  }
  if (out.empty()) throw Error(ErrorKind::Usage, std::string(what) + " needs at least one value");
  return out;
}

// Grey version (DMR luminance weights 1/3, 1/2, 1/6 for RGB; the mean for other counts) and a top-left crop.
Image grey_crop(const Image& u, int crop) {
  const std::vector<double> wt = luminance_weights(u.channels);
  const int w = crop > 0 ? std::min(crop, u.width) : u.width,
            h = crop > 0 ? std::min(crop, u.height) : u.height;
  Image g;
  g.width = w;
  g.height = h;
  g.channels = 1;
  g.pixels.resize(std::size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double v = 0.0;
      for (int c = 0; c < u.channels; ++c) v += wt[std::size_t(c)] * u.at(x, y, c);
      g.pixels[std::size_t(y) * w + x] = float(v);
    }
  return g;
}

// Texton coefficients for display: 0.5 + alpha / (2 max |alpha|) (as `stex export-texton`).
Image texton_picture(const std::vector<double>& alpha, int channels, int s) {
  double peak = 0.0;
  for (double v : alpha) peak = std::max(peak, std::fabs(v));
  const double scale = peak > 0.0 ? 0.5 / peak : 0.0;
  Image img;
  img.width = img.height = s;
  img.channels = channels;
  img.pixels.resize(std::size_t(s) * s * channels);
  for (int c = 0; c < channels; ++c)
    for (int y = 0; y < s; ++y)
      for (int x = 0; x < s; ++x)
        img.at(x, y, c) = float(0.5 + scale * alpha[(std::size_t(c) * s + y) * s + x]);
  return img;
}

NormalisedKernel alpha_kernel(const std::vector<double>& alpha, int channels, int s,
                              const std::array<double, 4>& mean) {
  NormalisedKernel k;
  k.mean = mean;
  k.width = k.height = s;
  k.channels = channels;
  k.t = alpha;
  return k;
}

// The two synthesised colour Gaussian textures (known spectra |k^|^2): CADSN of a 3-channel kernel on a
// 128 x 128 torus (periodic, so its periodic component is itself).
//  A "oriented colour stripes": k_c = a_c g_4(x) cos(2 pi (0.15 dx + 0.05 dy) + 1.2 c), g_4 a Gaussian
//  envelope of
//    standard deviation 4 px on a 25 x 25 box: a band-pass, oriented spectrum whose phase differs per
//    channel;
//  B "multi-scale colour blobs": k_c = sum_j M_cj g_sj(x), s = (1, 3, 6) px, M mixing: isotropic low-pass
//  spectra
//    of different widths per channel.
NormalisedKernel synthetic_kernel(char which) {
  const int ks = 25, r = ks / 2;
  NormalisedKernel k;
  k.width = k.height = ks;
  k.channels = 3;
  k.mean = {0.5, 0.42, 0.33, 0.0};
  k.t.assign(std::size_t(3) * ks * ks, 0.0);
  const double amp[3] = {1.0, 0.8, 0.6};
  const double sig[3] = {1.0, 3.0, 6.0};
  const double mix[3][3] = {{1.0, 0.5, 0.2}, {0.3, 1.0, 0.4}, {0.2, 0.3, 1.0}};
  for (int c = 0; c < 3; ++c) {
    double sum2 = 0.0;
    for (int y = 0; y < ks; ++y)
      for (int x = 0; x < ks; ++x) {
        const double dx = x - r, dy = y - r, d2 = dx * dx + dy * dy;
        double v = 0.0;
        if (which == 'A') {
          v = amp[c] * std::exp(-d2 / (2.0 * 16.0)) *
              std::cos(2.0 * M_PI * (0.15 * dx + 0.05 * dy) + 1.2 * c);
        } else {
          for (int j = 0; j < 3; ++j)
            v += mix[c][j] * std::exp(-d2 / (2.0 * sig[j] * sig[j])) / (sig[j] * sig[j]);
        }
        k.t[(std::size_t(c) * ks + y) * ks + x] = v;
        sum2 += v * v;
      }
    // Pixel standard deviation 0.08 per channel (sum k^2 = variance of k (.) W).
    const double norm = 0.08 / std::sqrt(sum2);
    for (int i = 0; i < ks * ks; ++i) k.t[std::size_t(c) * ks * ks + i] *= norm;
  }
  return k;
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// A two-panel SVG plot (mean and standard deviation of RME_n against n, log-scaled n axis).
std::string fig2_svg(const SotConvergence& conv, const std::string& title) {
  const int pw = 440, ph = 330, ml = 76, mr = 20, mt = 62, mb = 48;
  const int n = conv.iterations;
  const double lx1 = std::log10(double(std::max(n, 10)));
  std::ostringstream os;
  os.precision(6);
  os << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << 2 * pw << "\" height=\"" << ph
     << "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" "
        "fill=\"white\"/>\n";
  os << "<text x=\"" << pw << "\" y=\"20\" text-anchor=\"middle\" font-size=\"14\">" << title << "</text>\n";
  for (int panel = 0; panel < 2; ++panel) {
    const std::vector<double>& v = panel == 0 ? conv.mean : conv.stddev;
    double lo = *std::min_element(v.begin(), v.end()), hi = *std::max_element(v.begin(), v.end());
    const double pad = 0.05 * std::max(hi - lo, 1e-6);
    lo -= pad;
    hi += pad;
    const int x0 = panel * pw + ml, x1 = (panel + 1) * pw - mr, y0 = ph - mb, y1 = mt;
    auto px = [&](double it) { return x0 + (x1 - x0) * std::log10(it) / lx1; };
    auto py = [&](double val) { return y0 - (y0 - y1) * (val - lo) / (hi - lo); };
    os << "<rect x=\"" << x0 << "\" y=\"" << y1 << "\" width=\"" << x1 - x0 << "\" height=\"" << y0 - y1
       << "\" fill=\"none\" stroke=\"black\"/>\n";
    for (double t = 1; t <= std::pow(10.0, lx1) + 0.5; t *= 10) {
      os << "<line x1=\"" << px(t) << "\" y1=\"" << y0 << "\" x2=\"" << px(t) << "\" y2=\"" << y0 + 5
         << "\" stroke=\"black\"/><text x=\"" << px(t) << "\" y=\"" << y0 + 18 << "\" text-anchor=\"middle\">"
         << t << "</text>\n";
    }
    for (int k = 0; k <= 4; ++k) {
      const double val = lo + (hi - lo) * k / 4.0;
      os << "<line x1=\"" << x0 - 5 << "\" y1=\"" << py(val) << "\" x2=\"" << x0 << "\" y2=\"" << py(val)
         << "\" stroke=\"black\"/><text x=\"" << x0 - 8 << "\" y=\"" << py(val) + 4
         << "\" text-anchor=\"end\">" << fmt("%.4g", val) << "</text>\n";
    }
    os << "<polyline fill=\"none\" stroke=\"" << (panel == 0 ? "#1f5fbf" : "#bf3f1f")
       << "\" stroke-width=\"1.5\" points=\"";
    for (int i = 0; i < n; ++i) os << px(i + 1) << "," << py(v[std::size_t(i)]) << " ";
    os << "\"/>\n";
    os << "<text x=\"" << (x0 + x1) / 2 << "\" y=\"" << ph - 12
       << "\" text-anchor=\"middle\">iterations n</text>\n";
    os << "<text x=\"" << (x0 + x1) / 2 << "\" y=\"" << y1 - 8 << "\" text-anchor=\"middle\">"
       << (panel == 0 ? "mean of RME_n" : "standard deviation of RME_n") << "</text>\n";
  }
  os << "</svg>\n";
  return os.str();
}

struct Baseline {
  double sot = 0.0, lum = 0.0, rpn = 0.0;
  int iterations = 0;
  double variance_kept = 0.0;
  std::vector<double> alpha;
};

Baseline baseline_rmes(const SotSolver& solver, int iterations, std::uint64_t seed) {
  Baseline b;
  const SotRun run = solver.run(seed, iterations);
  b.sot = run.rme_history.back();
  b.iterations = run.iterations;
  b.alpha = run.alpha;
  b.lum = solver.rme(cropped_luminance_texton(solver.kernel(), solver.kernel_spectrum(), solver.mask()));
  b.rpn =
      solver.rme(cropped_random_phase_texton(solver.kernel(), solver.kernel_spectrum(), solver.mask(), seed));
  const int ch = solver.channels(), s = solver.mask().size;
  const std::vector<double> a = model_colour_covariance(run.alpha, ch, s, 0);
  const std::vector<double> e = exemplar_colour_covariance(solver.kernel());
  double ta = 0.0, te = 0.0;
  for (int c = 0; c < ch; ++c) {
    ta += a[std::size_t(c) * ch + c];
    te += e[std::size_t(c) * ch + c];
  }
  b.variance_kept = te > 0.0 ? ta / te : 1.0;
  return b;
}

// What every phase of the report shares: the options, the output directory, the grey exemplar and the JSON.
struct S2Run {
  const S2ReportOptions& o;
  const GlobalOptions& global;
  std::vector<int> radii;
  std::string dir, ex_name;
  Image grey;
  Json report;

  void log(const std::string& m) const {
    if (!global.quiet) std::printf("%s\n", m.c_str());
    std::fflush(stdout);
  }
};

// Fig. 2's results, for report.json and the Markdown tables.
struct Fig2Result {
  SupportMask mask;
  SotConvergence conv;
  std::vector<int> marks;  // the n listed in the tables
};

// Checks the options, creates the output directory, loads the exemplar and writes its grey crop.
void prepare_run(S2Run& run) {
  const S2ReportOptions& o = run.o;
  if (o.inits < 2)
    throw Error(ErrorKind::Usage, "--inits must be at least 2 (a standard deviation needs two)");
  if (o.iterations < 1 || o.fig5_iterations < 1)
    throw Error(ErrorKind::Usage, "iterations must be at least 1");
  if (o.threads < 1 || o.threads > 256) throw Error(ErrorKind::Usage, "--threads must be 1..256");
  if (o.sample < 8 || o.sample > 4096) throw Error(ErrorKind::Usage, "--sample must be 8..4096");
  run.radii = parse_int_list(o.radii, "--radii");
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (!fs::is_directory(o.out, ec))
    throw Error(ErrorKind::Output, "cannot create the output directory '" + o.out + "'");
  run.dir = o.out + "/";

  // The default exemplar is the source tree's, by absolute path: the report does not depend on the working
  // directory (an installed stex without the source tree asks for --exemplar).
  std::string exemplar = o.exemplar;
  if (exemplar.empty()) {
    exemplar = std::string(STEX_SOURCE_DATA_DIR) + "/gravel.png";
    struct stat st {};
    if (::stat(exemplar.c_str(), &st) != 0)
      throw Error(ErrorKind::Usage, "the default exemplar " + exemplar +
                                        " (the source tree's data/gravel.png) is not there: pass --exemplar PATH");
  }
  const Image full = load_exemplar(exemplar);
  run.grey = grey_crop(full, o.crop);
  const Image& grey = run.grey;
  const auto slash = exemplar.find_last_of('/');
  run.ex_name = slash == std::string::npos ? exemplar : exemplar.substr(slash + 1);
  for (int r : run.radii)
    if (2 * r + 1 > std::min(grey.width, grey.height))
      throw Error(ErrorKind::Usage, "--radii: a disc of radius " + std::to_string(r) + " does not fit the " +
                                        std::to_string(grey.width) + "x" + std::to_string(grey.height) +
                                        " exemplar");
  if (2 * o.radius + 1 > std::min(grey.width, grey.height))
    throw Error(ErrorKind::Usage, "--radius " + std::to_string(o.radius) + " does not fit the exemplar");
  write_image_atomic(run.dir + "fig5_exemplar.png", grey);

  run.report["exemplar"] = run.ex_name;
  run.report["grey_crop"] = {grey.width, grey.height};
  run.report["seed"] = o.seed;
}

// Fig. 2: the convergence of Algorithm 2 over random initialisations; writes fig2.csv and fig2.svg.
Fig2Result run_fig2(S2Run& run) {
  const S2ReportOptions& o = run.o;
  const Image& grey = run.grey;
  Fig2Result f;
  f.mask = disc_mask(o.radius);
  const SotSolver fig2_solver(grey, f.mask);
  run.log("Fig. 2: " + std::to_string(o.inits) + " initialisations x " + std::to_string(o.iterations) +
          " iterations, " + f.mask.description + " on " + run.ex_name + " " + std::to_string(grey.width) +
          "x" + std::to_string(grey.height) + ", " + std::to_string(o.threads) + " thread(s)...");
  f.conv = sot_convergence(fig2_solver, o.inits, o.iterations, o.seed, o.threads);
  const SotConvergence& conv = f.conv;
  run.log("  done in " + fmt("%.1f", conv.ms_total / 1000.0) + " s");
  {
    std::ostringstream csv;
    csv.precision(9);
    csv << "n,mean_rme,std_rme\n";
    for (int i = 0; i < conv.iterations; ++i)
      csv << i + 1 << "," << conv.mean[std::size_t(i)] << "," << conv.stddev[std::size_t(i)] << "\n";
    write_text(run.dir + "fig2.csv", csv.str());
    write_text(
        run.dir + "fig2.svg",
        fig2_svg(conv, "S2 Fig. 2: RME after n iterations of Algorithm 2, " + std::to_string(o.inits) +
                           " random initialisations (" + run.ex_name + " " + std::to_string(grey.width) +
                           "x" + std::to_string(grey.height) + ", " + f.mask.description + ")"));
  }
  for (int m : {1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000})
    if (m <= conv.iterations) f.marks.push_back(m);
  if (f.marks.back() != conv.iterations) f.marks.push_back(conv.iterations);
  Json fig2;
  fig2["support"] = f.mask.description;
  fig2["support_pixels"] = f.mask.count();
  fig2["inits"] = conv.inits;
  fig2["iterations"] = conv.iterations;
  fig2["seconds"] = conv.ms_total / 1000.0;
  fig2["threads"] = o.threads;
  fig2["at"] = Json::array();
  for (int m : f.marks)
    fig2["at"].push_back(
        {{"n", m}, {"mean", conv.mean[std::size_t(m - 1)]}, {"std", conv.stddev[std::size_t(m - 1)]}});
  fig2["final_min"] = *std::min_element(conv.final_rme.begin(), conv.final_rme.end());
  fig2["final_max"] = *std::max_element(conv.final_rme.begin(), conv.final_rme.end());
  run.report["fig2"] = fig2;
  return f;
}

// Fig. 5: SOTs of radius r, their textons, ADSN and DSN samples (same seed for every sample).
Json run_fig5(S2Run& run) {
  const S2ReportOptions& o = run.o;
  const std::string& dir = run.dir;
  run.log("Fig. 5: SOTs of radius " + o.radii + ", " + std::to_string(o.fig5_iterations) + " iterations...");
  const NormalisedKernel tu = normalised_kernel(run.grey, true);
  write_image_atomic(dir + "fig5_adsn_tu.png", synthesize_adsn_z2(tu, 0, 0, o.sample, o.sample, o.seed));
  Json fig5 = Json::array();
  for (int r : run.radii) {
    const SotSolver solver(run.grey, disc_mask(r));
    const Baseline b = baseline_rmes(solver, o.fig5_iterations, o.seed);
    const int s = solver.mask().size;
    const std::string tag = "r" + std::to_string(r);
    Image pic = texton_picture(b.alpha, 1, s);
    write_image_atomic(dir + "fig5_texton_" + tag + ".png", pic);
    write_image_atomic(
        dir + "fig5_adsn_" + tag + ".png",
        synthesize_adsn_z2(alpha_kernel(b.alpha, 1, s, tu.mean), 0, 0, o.sample, o.sample, o.seed));
    TextonModel m;
    m.channels = 1;
    m.support = s;
    m.order = 0;
    m.alpha.assign(b.alpha.begin(), b.alpha.end());
    m.mean[0] = float(tu.mean[0]);
    write_image_atomic(dir + "fig5_dsn_" + tag + ".png",
                       synthesize_dsn(m, 0, 0, o.sample, o.sample, o.mni, o.seed));
    fig5.push_back({{"radius", r},
                    {"support_pixels", solver.mask().count()},
                    {"iterations", b.iterations},
                    {"rme_sot", b.sot},
                    {"rme_luminance", b.lum},
                    {"rme_random_phase", b.rpn},
                    {"variance_kept", b.variance_kept}});
    run.log("  r = " + std::to_string(r) + ": RME " + fmt("%.4f", b.sot) + " (luminance texton " +
            fmt("%.4f", b.lum) + ", random phase " + fmt("%.4f", b.rpn) + ")");
  }
  run.report["fig5"] = fig5;
  run.report["fig5_samples"] = {{"size", o.sample}, {"seed", o.seed}, {"dsn_mni", o.mni}};
  return fig5;
}

// S2 §4: SOT vs cropped luminance texton vs cropped random-phase texton on three exemplars.
Json run_baselines(S2Run& run) {
  const S2ReportOptions& o = run.o;
  run.log("Baselines: SOT vs luminance texton vs random phase on three exemplars...");
  struct Ex {
    std::string name, description;
    Image img;
  };
  std::vector<Ex> exemplars;
  exemplars.push_back({run.ex_name + " (grey crop)", "the Fig. 2 exemplar", run.grey});
  for (char which : {'A', 'B'}) {
    Image img = synthesize_cadsn(synthetic_kernel(which), 0, 0, 128, 128, 1000 + std::uint64_t(which));
    const std::string file = std::string("baseline_colour_") + char(which - 'A' + 'a') + ".png";
    write_image_atomic(run.dir + file, img);
    exemplars.push_back({std::string("synthetic colour ") + which,
                         which == 'A' ? "oriented colour stripes (band-pass, channel phases differ), " + file
                                      : "multi-scale colour blobs (low-pass, channel widths differ), " + file,
                         img});
  }
  Json baselines = Json::array();
  for (const Ex& e : exemplars) {
    for (int r : run.radii) {
      const SotSolver solver(e.img, disc_mask(r));
      const Baseline b = baseline_rmes(solver, o.fig5_iterations, o.seed);
      baselines.push_back({{"exemplar", e.name},
                           {"description", e.description},
                           {"channels", e.img.channels},
                           {"radius", r},
                           {"rme_sot", b.sot},
                           {"rme_luminance", b.lum},
                           {"rme_random_phase", b.rpn}});
      run.log("  " + e.name + ", r = " + std::to_string(r) + ": SOT " + fmt("%.4f", b.sot) + ", luminance " +
              fmt("%.4f", b.lum) + ", random phase " + fmt("%.4f", b.rpn));
    }
  }
  return baselines;
}

// The Markdown tables of s2-report.md.
std::string markdown_tables(const S2Run& run, const Fig2Result& f, const Json& fig5, const Json& baselines) {
  const S2ReportOptions& o = run.o;
  const SotConvergence& conv = f.conv;
  std::ostringstream md;
  md << "# S2 reproduction (generated by `stex s2-report`)\n\n";
  md << "Exemplar: " << run.ex_name << ", grey, top-left " << run.grey.width << "x" << run.grey.height
     << " crop. Seed " << o.seed << ".\n\n";
  md << "## Fig. 2: RME after n iterations (" << conv.inits << " initialisations, " << f.mask.description
     << ", " << f.mask.count() << " pixels)\n\n| n | mean RME | std RME |\n| ---: | ---: | ---: |\n";
  for (int m : f.marks)
    md << "| " << m << " | " << fmt("%.5f", conv.mean[std::size_t(m - 1)]) << " | "
       << fmt("%.5f", conv.stddev[std::size_t(m - 1)]) << " |\n";
  md << "\nFinal RMEs range over ["
     << fmt("%.5f", *std::min_element(conv.final_rme.begin(), conv.final_rme.end())) << ", "
     << fmt("%.5f", *std::max_element(conv.final_rme.begin(), conv.final_rme.end())) << "]; "
     << fmt("%.1f", conv.ms_total / 1000.0) << " s with " << o.threads << " thread(s).\n\n";
  md << "## Fig. 5: SOT with a disc support (" << o.fig5_iterations
     << " iterations)\n\n| radius | pixels in S | RME SOT | RME luminance texton | RME random phase | "
        "variance kept |\n"
        "| ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const auto& e : fig5)
    md << "| " << e["radius"].get<int>() << " | " << e["support_pixels"].get<std::size_t>() << " | "
       << fmt("%.4f", e["rme_sot"].get<double>()) << " | " << fmt("%.4f", e["rme_luminance"].get<double>())
       << " | " << fmt("%.4f", e["rme_random_phase"].get<double>()) << " | "
       << fmt("%.3f", e["variance_kept"].get<double>()) << " |\n";
  md << "\n## SOT vs baselines (S2 §4), same disc support\n\n| exemplar | radius | RME SOT | RME luminance "
        "texton | "
        "RME random phase |\n| --- | ---: | ---: | ---: | ---: |\n";
  for (const auto& b : baselines)
    md << "| " << b["exemplar"].get<std::string>() << " | " << b["radius"].get<int>() << " | "
       << fmt("%.4f", b["rme_sot"].get<double>()) << " | " << fmt("%.4f", b["rme_luminance"].get<double>())
       << " | " << fmt("%.4f", b["rme_random_phase"].get<double>()) << " |\n";
  return md.str();
}

void run_report(const S2ReportOptions& o, const GlobalOptions& global) {
  const auto t_start = std::chrono::steady_clock::now();
  S2Run run{o, global, {}, {}, {}, {}, {}};
  prepare_run(run);
  const Fig2Result fig2 = run_fig2(run);
  const Json fig5 = run_fig5(run);
  const Json baselines = run_baselines(run);
  run.report["baselines"] = baselines;
  run.report["seconds_total"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  write_text(run.dir + "report.json", run.report.dump(2) + "\n");
  write_text(run.dir + "s2-report.md", markdown_tables(run, fig2, fig5, baselines));
  run.log("wrote " + run.dir +
          "{fig2.svg, fig2.csv, fig5_*.png, baseline_*.png, s2-report.md, report.json} in " +
          fmt("%.1f", run.report["seconds_total"].get<double>()) + " s");
}

}  // namespace

void add_s2_report(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<S2ReportOptions>();
  auto* sub = app.add_subcommand(
      "s2-report",
      "Reproduce S2 Fig. 2 (mean/std of the RME after n iterations of Algorithm 2 over random "
      "initialisations), "
      "Fig. 5 (SOTs with disc supports) and the SOT vs luminance texton vs random-phase comparison of S2 §4; "
      "writes an SVG plot, PNGs, Markdown tables and JSON (docs/s2.md).");
  sub->add_option("--out", o->out, "Output directory (created)")->required();
  sub->add_option("--exemplar", o->exemplar,
                  "Exemplar (made grey with weights 1/3, 1/2, 1/6); default: the source tree's data/gravel.png, "
                  STEX_SOURCE_DATA_DIR "/gravel.png");
  sub->add_option("--crop", o->crop, "Top-left crop size (0: the whole exemplar)")
      ->capture_default_str()
      ->check(CLI::Range(0, 8192));
  sub->add_option("--inits", o->inits, "Fig. 2: random initialisations")
      ->capture_default_str()
      ->check(CLI::Range(2, 100000));
  sub->add_option("--iterations", o->iterations, "Fig. 2: iterations n (1..N)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  sub->add_option("--radius", o->radius, "Fig. 2: disc radius of the support")
      ->capture_default_str()
      ->check(CLI::Range(0, 2047));
  sub->add_option("--radii", o->radii, "Fig. 5 and baselines: disc radii")->capture_default_str();
  sub->add_option("--fig5-iterations", o->fig5_iterations, "Fig. 5 and baselines: iterations")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  sub->add_option("--threads", o->threads, "Worker threads for Fig. 2 (results do not depend on it)")
      ->capture_default_str();
  sub->add_option("--seed", o->seed, "First seed (Fig. 2 uses seed .. seed + inits - 1)")
      ->capture_default_str();
  sub->add_option("--sample", o->sample, "Size of the Fig. 5 samples")->capture_default_str();
  sub->add_option("--mni", o->mni, "Mean number of impacts per pixel of the DSN samples (lambda = MNI / s^2)")
      ->capture_default_str();
  sub->callback([o, &global] { run_report(*o, global); });
}

}  // namespace stex::cli
