// Cyclostationary random-phase noise from user spectra: spectrum tables, spectra files, the "cs-rpn" codec.
// See cs_rpn_model.h.
#include "analysis/cs_rpn_model.h"

#include <cmath>
#include <fstream>

#include "analysis/image_io.h"
#include "core/error.h"

namespace stex {

namespace {

using json = nlohmann::json;

[[noreturn]] void usage(const std::string& msg) { throw Error(ErrorKind::Usage, msg); }

}  // namespace

CsRpnSpectrum cs_rpn_spectrum(const LrpSpectrum& s, double variance, const std::string& source) {
  const int T = s.period;
  auto freq = [T](int k) { return double(k < T / 2 ? k : k - T) / T; };
  // Principal direction: leading eigenvector of sum P f f^T.
  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  for (int ky = 0; ky < T; ++ky)
    for (int kx = 0; kx < T; ++kx) {
      const double p = s.psd[std::size_t(ky) * T + kx];
      const double fx = freq(kx), fy = freq(ky);
      sxx += p * fx * fx;
      sxy += p * fx * fy;
      syy += p * fy * fy;
    }
  const double angle = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
  double dx = std::cos(angle), dy = std::sin(angle);
  if (dx < 0.0 || (dx == 0.0 && dy < 0.0)) {
    dx = -dx;
    dy = -dy;
  }
  CsRpnSpectrum out;
  out.energy = variance;
  out.source = source;
  for (int ky = 0; ky < T; ++ky)
    for (int kx = 0; kx < T; ++kx) {
      const double fx = freq(kx), fy = freq(ky);
      const double dot = fx * dx + fy * dy;
      if (dot < 0.0 || (dot == 0.0 && dx * fy - dy * fx <= 0.0)) continue;  // the other half (and f = 0)
      if (std::hypot(fx, fy) > 0.5) continue;
      const int mx = (T - kx) % T, my = (T - ky) % T;
      const double w = s.psd[std::size_t(ky) * T + kx] + s.psd[std::size_t(my) * T + mx];
      if (!(w > 0.0)) continue;
      out.bins.push_back(float(fx));
      out.bins.push_back(float(fy));
      out.bins.push_back(float(w));
    }
  if (out.bins.empty()) usage("spectrum '" + source + "' has no power below 0.5 cycles per pixel");
  if (out.bins.size() / 3 > std::size_t(k_cs_rpn_max_bins))
    usage("spectrum '" + source + "' has more than 65536 non-zero bins: use a smaller size");
  return out;
}

void cs_rpn_load_spectra(CsRpnModel& m, const json& j, const std::string& base_dir) {
  if (!j.is_object()) usage("the spectra file must be a JSON object with 'grid' and 'spectra'");
  const auto grid = j.find("grid");
  if (grid == j.end() || !grid->is_array() || grid->size() != 2 || !(*grid)[0].is_number_integer() ||
      !(*grid)[1].is_number_integer())
    usage("spectra file: 'grid' must be [K0, K1] (integers)");
  const long k0 = (*grid)[0].get<long>(), k1 = (*grid)[1].get<long>();
  if (k0 < 1 || k1 < 1 || k0 > STEX_CSR_MAX_GRID || k1 > STEX_CSR_MAX_GRID)
    usage("spectra file: 'grid' must be 1..16 on each side, got " + std::to_string(k0) + "x" + std::to_string(k1));
  int T = 64;
  if (j.contains("size")) {
    if (!j["size"].is_number_integer()) usage("spectra file: 'size' must be an integer");
    const long t = j["size"].get<long>();
    if (t < 16 || t > 1024 || (t & (t - 1)) != 0) usage("spectra file: 'size' must be a power of two in 16..1024, got " + std::to_string(t));
    T = int(t);
  }
  const auto list = j.find("spectra");
  if (list == j.end() || !list->is_array()) usage("spectra file: 'spectra' must be an array");
  if (list->size() != std::size_t(k0 * k1))
    usage("spectra file: the grid " + std::to_string(k0) + "x" + std::to_string(k1) + " needs " + std::to_string(k0 * k1) +
          " spectra, got " + std::to_string(list->size()));
  std::vector<CsRpnSpectrum> spectra;
  for (std::size_t i = 0; i < list->size(); ++i) {
    const json& e = (*list)[i];
    const std::string at = "spectra file: entry " + std::to_string(i) + ": ";
    std::string spec, image;
    double variance = 0.0225;
    if (e.is_string()) {
      spec = e.get<std::string>();
    } else if (e.is_object()) {
      if (e.contains("psd")) {
        if (!e["psd"].is_string()) usage(at + "'psd' must be a string");
        spec = e["psd"].get<std::string>();
      }
      if (e.contains("image")) {
        if (!e["image"].is_string()) usage(at + "'image' must be a string");
        image = e["image"].get<std::string>();
      }
      if (spec.empty() == image.empty()) usage(at + "give exactly one of 'psd' and 'image'");
      if (e.contains("variance")) {
        if (!e["variance"].is_number() || !std::isfinite(e["variance"].get<double>()) || e["variance"].get<double>() < 0.0 ||
            e["variance"].get<double>() > 1e6)
          usage(at + "'variance' must be a number in [0, 1e6]");
        variance = e["variance"].get<double>();
      }
    } else {
      usage(at + "must be a spec string or an object {\"psd\"|\"image\": ..., \"variance\": V}");
    }
    // lrp_analytic_psd normalises to a positive variance; the energy is set afterwards (0 allowed).
    if (!spec.empty()) {
      LrpSpectrum s;
      try {
        s = lrp_analytic_psd(spec, T, 1.0);
      } catch (const Error& err) {
        usage(at + err.what());
      }
      spectra.push_back(cs_rpn_spectrum(s, variance, spec));
    } else {
      const std::string path = !image.empty() && image[0] == '/' ? image : base_dir + "/" + image;
      LoadOptions lo;
      lo.what = "PSD image";
      const Image img = load_exemplar(path, lo);
      if (img.width != T || img.height != T)
        usage(at + "the PSD image " + image + " is " + std::to_string(img.width) + "x" + std::to_string(img.height) +
              ", but 'size' is " + std::to_string(T));
      spectra.push_back(cs_rpn_spectrum(lrp_psd_from_image(img, 1.0), variance, image));
    }
  }
  m.k0 = int(k0);
  m.k1 = int(k1);
  m.spectra = std::move(spectra);
  m.bin = 1.0 / T;
}

void cs_rpn_load_spectra_file(CsRpnModel& m, const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(ErrorKind::Input, "cannot read the spectra file '" + path + "'");
  json j;
  try {
    in >> j;
  } catch (const std::exception& e) {
    throw Error(ErrorKind::Input, "the spectra file '" + path + "' is not JSON: " + e.what());
  }
  const std::size_t slash = path.find_last_of('/');
  cs_rpn_load_spectra(m, j, slash == std::string::npos ? "." : path.substr(0, slash));
}

}  // namespace stex
