// Reports of a `stex bench` run: terminal, Table 1, goals, JSON, CSV, Markdown, SVG. See bench_report.h.
#include "benchmarks/lib/bench_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <vector>

namespace stex::bench {
namespace {

std::string printf_str(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string num(double v, int sig = 3) {
  std::ostringstream os;
  os.precision(sig);
  os << v;
  return os.str();
}

double fps_of(const Measurement& m) { return m.ms > 0 ? 1000.0 / m.ms : 0.0; }
double mpix_of(const BenchPoint& p, const Measurement& m) {
  return m.ms > 0 ? frame_pixels(p, m) / (m.ms * 1000.0) : 0.0;
}
double floor_ms(const BenchReport& r, const BenchPoint& p) {
  return r.peak.gflops_fma > 0 ? p.flops / (r.peak.gflops_fma * 1e6) : 0.0;
}
// The texton floor applies to the texton strategies only (ADSN and DSN compute something else).
bool floor_applies(Strategy s) {
  return s == Strategy::Default || s == Strategy::Splat || s == Strategy::Gather || s == Strategy::S1 ||
         s == Strategy::Omp;
}
double floor_fraction(const BenchReport& r, const BenchPoint& p, const Measurement& m) {
  return (m.ms > 0 && floor_applies(m.strategy)) ? floor_ms(r, p) / m.ms : -1.0;
}
// Paired with the default's runs when measured so, per pixel for a smaller frame (bench_suite.h).
double relative(const BenchPoint& p, const Measurement& m) { return time_vs_default(p, m); }

std::string pad(const std::string& s, std::size_t w, bool right = false) {
  if (s.size() >= w) return s;
  return right ? std::string(w - s.size(), ' ') + s : s + std::string(w - s.size(), ' ');
}

std::string machine_line(const BenchReport& r) {
  return "CPU: " + r.machine.cpu + " (" + std::to_string(r.machine.host_threads) + " hardware threads)\n" +
         "OpenCL device: " + r.machine.device + " [" + r.machine.device_type + ", " +
         std::to_string(r.machine.compute_units) + " compute units], platform " + r.machine.platform +
         ", driver " + r.machine.driver + "\n" + "Worker threads: " + describe(r.machine.workers) + "\n" +
         "Peak (measured, kernels/bench_fma_peak.cl): " +
         num(r.peak.gflops_fma, 4) + " GFLOP/s FMA, " + num(r.peak.gflops_muladd, 4) +
         " GFLOP/s separate mul+add\n" + "Exemplar: " + r.exemplar_desc + "; stex default strategy: " +
         r.default_strategy + "\n";
}

const std::vector<std::pair<int, const char*>>& support_colours() {
  static const std::vector<std::pair<int, const char*>> v{
      {32, "#1b9e77"}, {64, "#d95f02"}, {128, "#7570b3"}, {256, "#e7298a"}};
  return v;
}
const char* colour_of(int support, int index) {
  for (const auto& kv : support_colours())
    if (kv.first == support) return kv.second;
  static const char* extra[] = {"#66a61e", "#e6ab02", "#a6761d", "#666666"};
  return extra[index % 4];
}

}  // namespace

std::string format_table1(const BenchReport& r) {
  std::ostringstream os;
  bool any = false;
  os << "S1 Table 1 layout on " << r.machine.device << " (stex default, MNI 30, device time; fps / ms):\n";
  os << pad("Output size", 21) << pad("Texton 64x64", 22) << pad("Texton 256x256", 22) << "\n";
  for (const OutputSize& size : all_sizes()) {
    os << pad(size_label(size) + " (" + std::to_string(size.width) + "x" + std::to_string(size.height) + ")", 21);
    for (int s : {64, 256}) {
      std::string cell = "-";
      for (const BenchPoint& p : r.points)
        if (p.size.width == size.width && p.size.height == size.height && p.support == s &&
            std::fabs(p.mni - 30) < 1e-9 && !p.results.empty() && p.results[0].ok) {
          cell = printf_str("%.1f fps", fps_of(p.results[0])) + " / " + printf_str("%.1f ms", p.results[0].ms);
          any = true;
        }
      os << pad(cell, 22);
    }
    os << "\n";
  }
  return any ? os.str() : "";
}

std::string format_goals(const BenchReport& r) {
  std::ostringstream os;
  os << "Goals (issue #5; issue #8 for tiling and blending):\n";
  for (const Goal& g : r.goals) {
    std::string verdict = !g.applicable ? "n/a " : g.met ? "MET " : "NOT MET";
    std::string value;
    if (g.name.find("floor") != std::string::npos)
      value = printf_str("%.1f %%", 100 * g.value);
    else
      value = printf_str("%.2fx", g.value);
    os << "  [" << pad(verdict, 7) << "] " << g.name << ": target " << g.target << "; worst " << value << "\n";
    if (!g.detail.empty()) os << "            " << g.detail << "\n";
  }
  return os.str();
}

std::string format_terminal(const BenchReport& r) {
  std::ostringstream os;
  os << machine_line(r);
  os << "Times: device ms (profiling events) for OpenCL strategies, wall ms for host ones; 'x stex' = time / "
        "stex default's (per pixel when a row's note names a smaller frame); floor = FLOP / FMA peak, FLOP/pixel = MNI (8C + 6) + 3C.\n\n";
  os << pad("size", 8) << pad("supp", 5, true) << pad("MNI", 6, true) << "  " << pad("strategy", 30)
     << pad("ms", 10, true) << pad("wall ms", 10, true) << pad("fps", 9, true) << pad("Mpix/s", 9, true)
     << pad("x stex", 9, true) << pad("floor", 8, true) << pad("spec.err", 10, true) << pad("ex.kurt", 9, true)
     << "  note\n";
  for (const BenchPoint& p : r.points) {
    for (const Measurement& m : p.results) {
      os << pad(size_label(p.size), 8) << pad(std::to_string(p.support), 5, true) << pad(num(p.mni), 6, true) << "  "
         << pad(m.strategy == Strategy::Default ? m.label : strategy_label(m.strategy), 30);
      if (!m.ok) {
        os << "  not measured: " << m.note << "\n";
        continue;
      }
      const double ff = floor_fraction(r, p, m);
      os << pad(printf_str("%.2f", m.ms), 10, true) << pad(printf_str("%.1f", m.wall_ms), 10, true)
         << pad(printf_str("%.1f", fps_of(m)), 9, true) << pad(printf_str("%.1f", mpix_of(p, m)), 9, true)
         << pad(printf_str("%.2f", relative(p, m)), 9, true)
         << pad(ff >= 0 ? printf_str("%.1f%%", 100 * ff) : "-", 8, true)
         << pad(m.has_quality ? printf_str("%.4f", m.spectrum_error) : "-", 10, true)
         << pad(m.has_quality ? printf_str("%.3f", m.kurtosis) : "-", 9, true) << "  " << m.note << "\n";
    }
  }
  os << "\n" << format_table1(r) << "\n" << format_goals(r);
  for (const std::string& n : r.notes) os << "note: " << n << "\n";
  os << printf_str("total %.1f s\n", r.total_seconds);
  return os.str();
}

std::string to_json(const BenchReport& r) {
  using nlohmann::ordered_json;
  ordered_json j;
  j["machine"] = {{"cpu", r.machine.cpu},
                  {"host_threads", r.machine.host_threads},
                  {"device", r.machine.device},
                  {"device_type", r.machine.device_type},
                  {"platform", r.machine.platform},
                  {"driver", r.machine.driver},
                  {"compute_units", r.machine.compute_units},
                  {"worker_affinity",
                   {{"pocl_affinity", r.machine.workers.setting.empty() ? ordered_json(nullptr)
                                                                        : ordered_json(r.machine.workers.setting)},
                    {"source", r.machine.workers.source},
                    {"note", r.machine.workers.note},
                    {"pinned_threads", r.machine.workers.pinned_threads},
                    {"openmp_pinned", r.machine.workers.openmp_pinned}}}};
  j["peak"] = {{"gflops_fma", r.peak.gflops_fma},
               {"gflops_muladd", r.peak.gflops_muladd},
               {"ms_fma", r.peak.ms_fma},
               {"ms_muladd", r.peak.ms_muladd},
               {"work_items", r.peak.work_items},
               {"iterations_fma", r.peak.iterations_fma},
               {"iterations_muladd", r.peak.iterations_muladd},
               {"method", "kernels/bench_fma_peak.cl: 12 float16 FMA chains per work-item, best of 3 launches"}};
  ordered_json cfg;
  cfg["mni"] = r.config.mni;
  cfg["supports"] = r.config.supports;
  ordered_json sizes = ordered_json::array();
  for (const OutputSize& s : r.config.sizes) sizes.push_back({s.width, s.height});
  cfg["sizes"] = sizes;
  cfg["exemplar"] = r.config.exemplar;
  cfg["repeat"] = r.config.repeat;
  cfg["warm_pairs"] = r.config.warm_pairs;
  cfg["budget_ms"] = r.config.budget_ms;
  ordered_json cmp = ordered_json::array();
  for (Strategy s : r.config.compare) cmp.push_back(strategy_key(s));
  cfg["compare"] = cmp;
  cfg["compare_mni"] = r.config.compare_mni;
  cfg["table1"] = r.config.table1;
  cfg["seed"] = r.config.seed;
  cfg["analysis_iterations"] = r.config.analysis_iterations;
  j["config"] = cfg;
  j["default_strategy"] = r.default_strategy;
  j["channels"] = r.channels;
  j["exemplar"] = r.exemplar_desc;
  j["flops_per_pixel"] = "MNI * (8 * channels + 6) + 3 * channels";
  ordered_json tex = ordered_json::array();
  for (const TextonInfo& t : r.textons)
    tex.push_back({{"support", t.support}, {"analysis_ms", t.analysis_ms}, {"rme", t.rme},
                   {"variance_kept", t.variance_kept}});
  j["textons"] = tex;
  ordered_json pts = ordered_json::array();
  for (const BenchPoint& p : r.points) {
    ordered_json pj;
    pj["width"] = p.size.width;
    pj["height"] = p.size.height;
    pj["support"] = p.support;
    pj["mni"] = p.mni;
    pj["table1_only"] = p.table1_only;
    pj["flops"] = p.flops;
    pj["floor_ms"] = floor_ms(r, p);
    ordered_json res = ordered_json::array();
    for (const Measurement& m : p.results) {
      ordered_json mj;
      mj["strategy"] = strategy_key(m.strategy);
      mj["label"] = m.label;
      mj["ok"] = m.ok;
      if (m.ok) {
        mj["ms"] = m.ms;
        mj["device_ms"] = m.device_ms >= 0 ? ordered_json(m.device_ms) : ordered_json(nullptr);
        mj["wall_ms"] = m.wall_ms;
        mj["runs"] = m.runs;
        mj["fps"] = fps_of(m);
        mj["mpixel_per_s"] = mpix_of(p, m);
        mj["time_vs_default"] = relative(p, m);
        mj["default_ms_paired"] = m.ref_ms > 0 ? ordered_json(m.ref_ms) : ordered_json(nullptr);
        // Minima of the same runs (Measurement::ms_min): the ratio of minima is the interference-free estimate.
        mj["ms_min"] = m.ms_min > 0 ? ordered_json(m.ms_min) : ordered_json(nullptr);
        mj["default_ms_paired_min"] = m.ref_min_ms > 0 ? ordered_json(m.ref_min_ms) : ordered_json(nullptr);
        // The frame measured (the point's unless smaller, e.g. cs-spot): fps and Mpixel/s are of this frame.
        mj["frame_width"] = m.frame_width > 0 ? m.frame_width : p.size.width;
        mj["frame_height"] = m.frame_height > 0 ? m.frame_height : p.size.height;
        const double ff = floor_fraction(r, p, m);
        mj["floor_fraction"] = ff >= 0 ? ordered_json(ff) : ordered_json(nullptr);
        mj["spectrum_error"] = m.has_quality ? ordered_json(m.spectrum_error) : ordered_json(nullptr);
        mj["excess_kurtosis"] = m.has_quality ? ordered_json(m.kurtosis) : ordered_json(nullptr);
      }
      mj["note"] = m.note;
      res.push_back(mj);
    }
    pj["results"] = res;
    pts.push_back(pj);
  }
  j["points"] = pts;
  ordered_json goals = ordered_json::array();
  for (const Goal& g : r.goals)
    goals.push_back({{"name", g.name}, {"target", g.target}, {"applicable", g.applicable}, {"met", g.met},
                     {"value", g.value}, {"detail", g.detail}});
  j["goals"] = goals;
  j["notes"] = r.notes;
  j["total_seconds"] = r.total_seconds;
  return j.dump(2) + "\n";
}

std::string to_csv(const BenchReport& r) {
  std::ostringstream os;
  os << "width,height,support,mni,strategy,ok,ms,device_ms,wall_ms,runs,fps,mpixel_per_s,time_vs_default,"
        "floor_fraction,spectrum_error,excess_kurtosis,table1_only,note,frame_width,frame_height\n";
  auto quote = [](const std::string& s) {
    std::string q = "\"";
    for (char c : s) q += (c == '"') ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
  };
  for (const BenchPoint& p : r.points)
    for (const Measurement& m : p.results) {
      os << p.size.width << "," << p.size.height << "," << p.support << "," << p.mni << "," << strategy_key(m.strategy)
         << "," << (m.ok ? 1 : 0) << ",";
      if (m.ok) {
        const double ff = floor_fraction(r, p, m);
        os << printf_str("%.4f", m.ms) << "," << (m.device_ms >= 0 ? printf_str("%.4f", m.device_ms) : "") << ","
           << printf_str("%.4f", m.wall_ms) << "," << m.runs << "," << printf_str("%.3f", fps_of(m)) << ","
           << printf_str("%.3f", mpix_of(p, m)) << "," << printf_str("%.4f", relative(p, m)) << ","
           << (ff >= 0 ? printf_str("%.4f", ff) : "") << ","
           << (m.has_quality ? printf_str("%.5f", m.spectrum_error) : "") << ","
           << (m.has_quality ? printf_str("%.5f", m.kurtosis) : "");
      } else {
        os << ",,,,,,,,,";
      }
      os << "," << (p.table1_only ? 1 : 0) << "," << quote(m.note) << ","
         << (m.frame_width > 0 ? m.frame_width : p.size.width) << ","
         << (m.frame_height > 0 ? m.frame_height : p.size.height) << "\n";
    }
  return os.str();
}

std::string to_markdown(const BenchReport& r) {
  std::ostringstream os;
  os << "Measured by `stex bench` on:\n\n";
  os << "- CPU: " << r.machine.cpu << " (" << r.machine.host_threads << " hardware threads)\n";
  os << "- OpenCL device: " << r.machine.device << " (" << r.machine.device_type << ", "
     << r.machine.compute_units << " compute units; " << r.machine.platform << ", driver " << r.machine.driver
     << ")\n";
  os << "- Worker threads: " << describe(r.machine.workers) << "\n";
  os << "- Measured peak: " << num(r.peak.gflops_fma, 4) << " GFLOP/s with FMA, " << num(r.peak.gflops_muladd, 4)
     << " GFLOP/s with separate mul + add\n";
  os << "- Exemplar: " << r.exemplar_desc << "; stex default strategy: " << r.default_strategy << "\n\n";

  // Grid points by size: the MNI / support trade-off.
  std::vector<OutputSize> sizes;
  for (const BenchPoint& p : r.points)
    if (!p.table1_only &&
        std::none_of(sizes.begin(), sizes.end(), [&](const OutputSize& s) {
          return s.width == p.size.width && s.height == p.size.height;
        }))
      sizes.push_back(p.size);
  for (const OutputSize& size : sizes) {
    os << "#### stex default, " << size.width << "x" << size.height << "\n\n";
    os << "| support | MNI | device ms | fps | Mpixel/s | floor | spectrum error | excess kurtosis |\n";
    os << "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
    for (const BenchPoint& p : r.points) {
      if (p.table1_only || p.size.width != size.width || p.size.height != size.height || p.results.empty()) continue;
      const Measurement& m = p.results[0];
      if (!m.ok) continue;
      os << "| " << p.support << " | " << num(p.mni) << " | " << printf_str("%.2f", m.ms) << " | "
         << printf_str("%.1f", fps_of(m)) << " | " << printf_str("%.1f", mpix_of(p, m)) << " | "
         << printf_str("%.0f %%", 100 * floor_fraction(r, p, m)) << " | "
         << (m.has_quality ? printf_str("%.3f", m.spectrum_error) : "-") << " | "
         << (m.has_quality ? printf_str("%.3f", m.kurtosis) : "-") << " |\n";
    }
    os << "\n";
  }

  // Comparison points.
  bool header = false;
  for (const BenchPoint& p : r.points) {
    if (p.results.size() < 2) continue;
    if (!header) {
      os << "#### Side by side (time relative to the stex default; floor = fraction of the compute floor)\n\n";
      os << "| size | support | MNI | strategy | ms | fps | x stex | floor | spectrum error | excess kurtosis | note |\n";
      os << "| --- | ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n";
      header = true;
    }
    for (const Measurement& m : p.results) {
      os << "| " << size_label(p.size) << " | " << p.support << " | " << num(p.mni) << " | "
         << (m.strategy == Strategy::Default ? m.label : strategy_label(m.strategy)) << " | ";
      if (!m.ok) {
        os << "- | - | - | - | - | - | " << m.note << " |\n";
        continue;
      }
      const double ff = floor_fraction(r, p, m);
      os << printf_str("%.2f", m.ms) << " | " << printf_str("%.1f", fps_of(m)) << " | "
         << printf_str("%.2f", relative(p, m)) << " | " << (ff >= 0 ? printf_str("%.0f %%", 100 * ff) : "-") << " | "
         << (m.has_quality ? printf_str("%.3f", m.spectrum_error) : "-") << " | "
         << (m.has_quality ? printf_str("%.3f", m.kurtosis) : "-") << " | " << m.note << " |\n";
    }
  }
  if (header) os << "\n";

  const std::string t1 = format_table1(r);
  if (!t1.empty()) {
    os << "#### S1 Table 1 layout (stex default, MNI 30, device time)\n\n";
    os << "| output size | texton 64x64 | texton 256x256 |\n| --- | ---: | ---: |\n";
    for (const OutputSize& size : all_sizes()) {
      os << "| " << size_label(size) << " (" << size.width << "x" << size.height << ") |";
      for (int s : {64, 256}) {
        std::string cell = " - |";
        for (const BenchPoint& p : r.points)
          if (p.size.width == size.width && p.size.height == size.height && p.support == s &&
              std::fabs(p.mni - 30) < 1e-9 && !p.results.empty() && p.results[0].ok)
            cell = " " + printf_str("%.1f fps", fps_of(p.results[0])) + " / " +
                   printf_str("%.1f ms", p.results[0].ms) + " |";
        os << cell;
      }
      os << "\n";
    }
    os << "\n";
  }

  os << "#### Goals\n\n| goal | target | measured (worst) | verdict | per point |\n| --- | --- | ---: | --- | --- |\n";
  for (const Goal& g : r.goals) {
    const std::string value = g.name.find("floor") != std::string::npos ? printf_str("%.1f %%", 100 * g.value)
                                                                          : printf_str("%.2fx", g.value);
    os << "| " << g.name << " | " << g.target << " | " << value << " | "
       << (!g.applicable ? "n/a" : g.met ? "met" : "**not met**") << " | " << g.detail << " |\n";
  }
  os << "\n";
  for (const std::string& n : r.notes) os << "Note: " << n << "\n\n";
  return os.str();
}

namespace {

// The SVG's layout in pixels: the page, each panel's size and top edge, and the panels' left edges.
constexpr double k_svg_width = 1000, k_svg_height = 470, k_panel_width = 400, k_panel_height = 330,
                 k_panel_top = 60;
constexpr double k_panel_left[2] = {80, 580};

// One point of an SVG curve: the default's speed and its distances to the Gaussian model at one MNI.
struct SvgPoint {
  double mni, fps, kurt, spec;
};

// What the SVG plots: one curve per texton support at the first configured size, and the ADSN (FFTW) point.
struct SvgData {
  OutputSize size;
  std::map<int, std::vector<SvgPoint>> curves;
  double adsn_fps = -1, adsn_spec = -1;
};

// A panel's axes: its left edge and the log10 ranges of its x and y axes.
struct SvgAxes {
  double px, x0, x1, y0, y1;
  double X(double v) const { return px + k_panel_width * (std::log10(v) - x0) / (x1 - x0); }
  double Y(double v) const {
    return k_panel_top + k_panel_height - k_panel_height * (std::log10(v) - y0) / (y1 - y0);
  }
};

// The curves (sorted by MNI) and the ADSN point of the report's first size, from its quality measurements.
SvgData collect_svg_data(const BenchReport& r) {
  SvgData d;
  d.size = r.config.sizes[0];
  for (const BenchPoint& p : r.points) {
    if (p.table1_only || p.size.width != d.size.width || p.size.height != d.size.height || p.results.empty())
      continue;
    const Measurement& m = p.results[0];
    if (m.ok && m.has_quality)
      d.curves[p.support].push_back({p.mni, fps_of(m), m.kurtosis, m.spectrum_error});
    for (const Measurement& b : p.results)
      if (b.strategy == Strategy::AdsnFftw && b.ok && b.has_quality) {
        d.adsn_fps = fps_of(b);
        d.adsn_spec = b.spectrum_error;
      }
  }
  for (auto& kv : d.curves)
    std::sort(kv.second.begin(), kv.second.end(),
              [](const SvgPoint& a, const SvgPoint& b) { return a.mni < b.mni; });
  return d;
}

// The log10 range of [lo, hi], padded on both sides.
void log_range(double lo, double hi, double* l0, double* l1) {
  *l0 = std::log10(lo);
  *l1 = std::log10(hi);
  const double padv = std::max(0.08 * (*l1 - *l0), 0.05);
  *l0 -= padv;
  *l1 += padv;
}

// The 1, 2, 5 x 10^e ticks within the log10 range [l0, l1].
std::vector<double> log_ticks(double l0, double l1) {
  std::vector<double> t;
  for (int e = int(std::floor(l0)) - 1; e <= int(std::ceil(l1)) + 1; ++e)
    for (double m : {1.0, 2.0, 5.0}) {
      const double v = m * std::pow(10.0, e);
      if (std::log10(v) >= l0 && std::log10(v) <= l1) t.push_back(v);
    }
  return t;
}

// A tick's label: %g from 1 up, three significant digits below.
std::string tick_label(double v) {
  char buf[32];
  if (v >= 1)
    std::snprintf(buf, sizeof buf, "%g", v);
  else
    std::snprintf(buf, sizeof buf, "%.3g", v);
  return std::string(buf);
}

// The SVG's opening tag, background and the two title lines.
void write_svg_header(std::ostringstream& os, const BenchReport& r, const OutputSize& size) {
  const double W = k_svg_width, H = k_svg_height;
  os << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
     << "\" viewBox=\"0 0 " << W << " " << H << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  os << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  os << "<text x=\"" << W / 2 << "\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">stex texton noise, "
     << size.width << "x" << size.height << ": frames per second against distance to the Gaussian model"
     << "</text>\n";
  os << "<text x=\"" << W / 2 << "\" y=\"40\" text-anchor=\"middle\" fill=\"#555\">" << r.machine.device
     << " (stex default: " << r.default_strategy
     << "); point labels: MNI; one curve per texton support</text>\n";
}

// The smallest and largest fps of the curves and of the ADSN point (1e300 and -1e300 when there is none).
void fps_range(const SvgData& d, double* ymin, double* ymax) {
  *ymin = 1e300;
  *ymax = -1e300;
  for (auto& kv : d.curves)
    for (const SvgPoint& p : kv.second) {
      *ymin = std::min(*ymin, p.fps);
      *ymax = std::max(*ymax, p.fps);
    }
  if (d.adsn_fps > 0) {
    *ymin = std::min(*ymin, d.adsn_fps);
    *ymax = std::max(*ymax, d.adsn_fps);
  }
}

// A panel's frame, grid lines, tick labels and axis titles (panel 0: kurtosis, 1: spectrum error).
void write_svg_axes(std::ostringstream& os, const SvgAxes& a, int panel) {
  const double px = a.px, pw = k_panel_width, ph = k_panel_height, top = k_panel_top;
  os << "<rect x=\"" << px << "\" y=\"" << top << "\" width=\"" << pw << "\" height=\"" << ph
     << "\" fill=\"none\" stroke=\"#333\"/>\n";
  for (double t : log_ticks(a.x0, a.x1)) {
    os << "<line x1=\"" << a.X(t) << "\" y1=\"" << top << "\" x2=\"" << a.X(t) << "\" y2=\"" << top + ph
       << "\" stroke=\"#eee\"/>\n";
    os << "<text x=\"" << a.X(t) << "\" y=\"" << top + ph + 15 << "\" text-anchor=\"middle\">"
       << tick_label(t) << "</text>\n";
  }
  for (double t : log_ticks(a.y0, a.y1)) {
    os << "<line x1=\"" << px << "\" y1=\"" << a.Y(t) << "\" x2=\"" << px + pw << "\" y2=\"" << a.Y(t)
       << "\" stroke=\"#eee\"/>\n";
    os << "<text x=\"" << px - 6 << "\" y=\"" << a.Y(t) + 4 << "\" text-anchor=\"end\">" << tick_label(t)
       << "</text>\n";
  }
  os << "<text x=\"" << px + pw / 2 << "\" y=\"" << top + ph + 34 << "\" text-anchor=\"middle\">"
     << (panel == 0 ? "excess kurtosis of the marginal (0 = Gaussian), log"
                    : "spectrum error vs ADSN (median relative ring error), log")
     << "</text>\n";
  os << "<text transform=\"translate(" << px - 48 << "," << top + ph / 2
     << ") rotate(-90)\" text-anchor=\"middle\">frames per second (device time), log</text>\n";
}

// A panel's curves, one per support, with their points labelled by MNI (points with x <= 0 are left out).
void write_svg_curves(std::ostringstream& os, const SvgData& d, const SvgAxes& a, int panel) {
  int index = 0;
  for (auto& kv : d.curves) {
    const char* colour = colour_of(kv.first, index++);
    std::ostringstream path;
    int n = 0;
    for (const SvgPoint& p : kv.second) {
      const double x = panel == 0 ? p.kurt : p.spec;
      if (x <= 0) continue;
      path << (n++ ? " L " : "M ") << a.X(x) << " " << a.Y(p.fps);
    }
    if (n > 1)
      os << "<path d=\"" << path.str() << "\" fill=\"none\" stroke=\"" << colour
         << "\" stroke-width=\"2\"/>\n";
    for (const SvgPoint& p : kv.second) {
      const double x = panel == 0 ? p.kurt : p.spec;
      if (x <= 0) continue;
      os << "<circle cx=\"" << a.X(x) << "\" cy=\"" << a.Y(p.fps) << "\" r=\"3.5\" fill=\"" << colour
         << "\"/>\n";
      os << "<text x=\"" << a.X(x) + 5 << "\" y=\"" << a.Y(p.fps) - 5 << "\" font-size=\"10\" fill=\""
         << colour << "\">" << num(p.mni) << "</text>\n";
    }
  }
}

// One panel (0: fps against kurtosis, 1: against spectrum error, with the ADSN point); none without x data.
void write_svg_panel(std::ostringstream& os, const SvgData& d, int panel, double y0, double y1) {
  double xmin = 1e300, xmax = -1e300;
  for (auto& kv : d.curves)
    for (const SvgPoint& p : kv.second) {
      const double x = panel == 0 ? p.kurt : p.spec;
      if (x > 0) {
        xmin = std::min(xmin, x);
        xmax = std::max(xmax, x);
      }
    }
  if (panel == 1 && d.adsn_spec > 0) {
    xmin = std::min(xmin, d.adsn_spec);
    xmax = std::max(xmax, d.adsn_spec);
  }
  if (!(xmin < 1e300)) return;
  SvgAxes a{k_panel_left[panel], 0, 0, y0, y1};
  log_range(xmin, xmax, &a.x0, &a.x1);
  write_svg_axes(os, a, panel);
  write_svg_curves(os, d, a, panel);
  if (panel == 1 && d.adsn_spec > 0 && d.adsn_fps > 0) {
    const double cx = a.X(d.adsn_spec), cy = a.Y(d.adsn_fps);
    os << "<path d=\"M " << cx << " " << cy - 6 << " L " << cx + 6 << " " << cy << " L " << cx << " "
       << cy + 6 << " L " << cx - 6 << " " << cy << " Z\" fill=\"black\"/>\n";
    os << "<text x=\"" << cx + 8 << "\" y=\"" << cy + 4
       << "\" font-size=\"10\">ADSN (FFTW): the metric's floor</text>\n";
  }
}

// The legend: one colour swatch per texton support, in the left panel's top-left corner.
void write_svg_legend(std::ostringstream& os, const SvgData& d) {
  int index = 0;
  double lx = k_panel_left[0] + 10, ly = k_panel_top + 14;
  for (auto& kv : d.curves) {
    const char* colour = colour_of(kv.first, index++);
    os << "<rect x=\"" << lx << "\" y=\"" << ly - 9 << "\" width=\"14\" height=\"4\" fill=\"" << colour
       << "\"/>\n";
    os << "<text x=\"" << lx + 20 << "\" y=\"" << ly - 3 << "\">texton " << kv.first << "x" << kv.first
       << "</text>\n";
    ly += 16;
  }
}

}  // namespace

std::string to_svg(const BenchReport& r) {
  if (r.config.sizes.empty()) return "";
  const SvgData d = collect_svg_data(r);
  std::ostringstream os;
  write_svg_header(os, r, d.size);
  // y range (fps), shared by both panels.
  double ymin, ymax;
  fps_range(d, &ymin, &ymax);
  if (!(ymin < 1e300) || ymin <= 0) {
    os << "<text x=\"" << k_svg_width / 2 << "\" y=\"" << k_svg_height / 2
       << "\" text-anchor=\"middle\">no quality measurements</text>\n</svg>\n";
    return os.str();
  }
  double y0, y1;
  log_range(ymin, ymax, &y0, &y1);
  for (int panel = 0; panel < 2; ++panel) write_svg_panel(os, d, panel, y0, y1);
  write_svg_legend(os, d);
  os << "</svg>\n";
  return os.str();
}

}  // namespace stex::bench
