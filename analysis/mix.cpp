// Noise mixing analysis (S1 §7): OT barycentres, textons from a shared initial noise, the "mix" codec and
// mixing maps from images. See mix.h.
#include "analysis/mix.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "analysis/fft.h"
#include "analysis/ot_distance.h"
#include "core/error.h"

namespace stex {
namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

void check_kernel(const NormalisedKernel& k) {
  if (k.width <= 0 || k.height <= 0 || k.channels < 1 || k.channels > 4 ||
      k.t.size() != std::size_t(k.width) * k.height * k.channels)
    throw Error(ErrorKind::Usage, "mix_barycentre: malformed kernel");
}

}  // namespace

MixBarycentre mix_barycentre(const NormalisedKernel& tu, const NormalisedKernel& tv) {
  check_kernel(tu);
  check_kernel(tv);
  if (tu.width != tv.width || tu.height != tv.height || tu.channels != tv.channels)
    throw Error(ErrorKind::Usage, "mix_barycentre: the kernels live on different grids or channel counts (" +
                                      std::to_string(tu.width) + "x" + std::to_string(tu.height) + "x" +
                                      std::to_string(tu.channels) + " and " + std::to_string(tv.width) + "x" +
                                      std::to_string(tv.height) + "x" + std::to_string(tv.channels) + ")");
  const int w = tu.width, h = tu.height, ch = tu.channels;
  const std::size_t n = std::size_t(w) * h;
  const std::vector<Complex> u_hat = kernel_spectrum(tu), v_hat = kernel_spectrum(tv);
  // tau_0^ = (t_u^* t_v / |t_u^* t_v|) t_u^, per frequency, z/|z| := 1 where z = 0.
  std::vector<Complex> tau0_hat(n * ch);
  for (std::size_t k = 0; k < n; ++k) {
    Complex z(0.0);
    for (int c = 0; c < ch; ++c) z += std::conj(u_hat[n * c + k]) * v_hat[n * c + k];
    const double mag = std::abs(z);
    const Complex phase = mag > 0.0 ? z / mag : Complex(1.0);
    for (int c = 0; c < ch; ++c) tau0_hat[n * c + k] = phase * u_hat[n * c + k];
  }
  MixBarycentre b;
  b.tau1 = tv;  // tau_1 = t_v
  b.tau0.width = w;
  b.tau0.height = h;
  b.tau0.channels = ch;
  b.tau0.mean = tu.mean;
  b.tau0.t.resize(n * ch);
  for (int c = 0; c < ch; ++c) {
    fft2d_inverse(w, h, tau0_hat.data() + n * c);
    // The spectrum is conjugate-symmetric (z(-xi) = conj z(xi)): tau_0 is real up to rounding.
    for (std::size_t k = 0; k < n; ++k) b.tau0.t[n * c + k] = tau0_hat[n * c + k].real();
  }
  return b;
}

NormalisedKernel MixBarycentre::at(double rho) const {
  if (!(rho >= 0.0 && rho <= 1.0)) throw Error(ErrorKind::Usage, "mixing parameter rho must be in [0, 1]");
  // tau_rho = (1 - rho) tau_0 + rho tau_1 (S1 §7): linear in space as in frequency.
  NormalisedKernel k = tau0;
  for (std::size_t i = 0; i < k.t.size(); ++i) k.t[i] = (1.0 - rho) * tau0.t[i] + rho * tau1.t[i];
  for (int c = 0; c < 4; ++c) k.mean[c] = (1.0 - rho) * tau0.mean[c] + rho * tau1.mean[c];
  return k;
}

void match_exemplars(Image& u, Image& v, std::vector<std::string>* warnings) {
  for (const Image* im : {&u, &v})
    if (im->width <= 0 || im->height <= 0 || im->channels < 1 || im->channels > 4 ||
        im->pixels.size() != std::size_t(im->width) * im->height * im->channels)
      throw Error(ErrorKind::Input, "exemplar image is empty or malformed");
  auto note = [&](const std::string& s) {
    if (warnings) warnings->push_back(s);
  };
  if (u.channels != v.channels) {
    if (u.channels != 1 && v.channels != 1)
      throw Error(ErrorKind::Input, "the exemplars have " + std::to_string(u.channels) + " and " +
                                        std::to_string(v.channels) + " channels: mixing needs the same channels "
                                        "(or one grey exemplar, which is replicated)");
    Image& grey = u.channels == 1 ? u : v;
    const int to = u.channels == 1 ? v.channels : u.channels;
    Image out{grey.width, grey.height, to, {}};
    out.pixels.resize(std::size_t(grey.width) * grey.height * to);
    for (std::size_t i = 0; i < std::size_t(grey.width) * grey.height; ++i)
      for (int c = 0; c < to; ++c) out.pixels[i * to + c] = grey.pixels[i];
    note(std::string("exemplar ") + (u.channels == 1 ? "A" : "B") + " is grey: replicated to " + std::to_string(to) +
         " channels");
    grey = std::move(out);
  }
  const int w = std::min(u.width, v.width), h = std::min(u.height, v.height);
  for (Image* im : {&u, &v}) {
    if (im->width == w && im->height == h) continue;
    note(std::string("exemplar ") + (im == &u ? "A" : "B") + " (" + std::to_string(im->width) + "x" +
         std::to_string(im->height) + ") cropped to the common grid " + std::to_string(w) + "x" + std::to_string(h) +
         " (top-left)");
    Image out{w, h, im->channels, {}};
    out.pixels.resize(std::size_t(w) * h * im->channels);
    for (int y = 0; y < h; ++y)
      std::copy(im->pixels.begin() + std::ptrdiff_t(std::size_t(y) * im->width * im->channels),
                im->pixels.begin() + std::ptrdiff_t((std::size_t(y) * im->width + w) * im->channels),
                out.pixels.begin() + std::ptrdiff_t(std::size_t(y) * w * im->channels));
    *im = std::move(out);
  }
}

MixModel analyse_mix(const Image& u_in, const Image& v_in, const MixParams& params, MixReport* report) {
  const auto t_start = Clock::now();
  MixReport local;
  MixReport& rep = report ? *report : local;
  rep = MixReport{};
  if (params.levels < 2 || params.levels > STEX_MIX_MAX_LEVELS)
    throw Error(ErrorKind::Usage, "--levels must be in [2, " + std::to_string(STEX_MIX_MAX_LEVELS) + "], got " +
                                      std::to_string(params.levels));
  validate_mix_map(params.map, "invalid mixing map: ");
  Image u = u_in, v = v_in;
  match_exemplars(u, v, &rep.warnings);
  if (u.width < params.support || u.height < params.support)
    throw Error(ErrorKind::Input, "the exemplars' common grid is " + std::to_string(u.width) + "x" +
                                      std::to_string(u.height) + ", smaller than the texton support " +
                                      std::to_string(params.support) + " (use a smaller --support)");

  const NormalisedKernel tu = normalised_kernel(u, true), tv = normalised_kernel(v, true);
  const MixBarycentre bary = mix_barycentre(tu, tv);
  const int w = u.width, h = u.height, ch = u.channels;
  rep.ot_distance = ot_distance(gaussian_spectrum(bary.tau0, w, h), gaussian_spectrum(bary.tau1, w, h)).distance();

  // One shared initial noise for every level (S1 §7).
  const std::vector<double> alpha0 = texton_initial_noise(w, h, ch, params.seed);
  TextonParams tp;
  tp.support = params.support;
  tp.iterations = params.iterations;
  tp.seed = params.seed;
  tp.order = params.order;
  tp.colour_correction = params.colour_correction;
  tp.linear = params.linear;
  tp.alpha0 = &alpha0;

  MixModel m;
  m.channels = ch;
  m.support = params.support;
  m.order = params.order;
  m.levels = params.levels;
  m.linear = params.linear;
  m.map = params.map;
  m.exemplar_width = w;
  m.exemplar_height = h;
  m.iterations = params.iterations;
  m.analysis_seed = params.seed;
  m.colour_correction = params.colour_correction;
  m.ot_distance = rep.ot_distance;
  m.stex_version = STEX_VERSION_STRING;
  for (int c = 0; c < ch; ++c) {
    m.mean0[c] = float(tu.mean[c]);
    m.mean1[c] = float(tv.mean[c]);
  }
  rep.levels.resize(std::size_t(params.levels));
  for (int k = 0; k < params.levels; ++k) {
    const NormalisedKernel tau = bary.at(m.level_rho(k));
    const TextonModel level = analyse_texton_kernel(tau, tp, &rep.levels[std::size_t(k)]);
    m.alpha.insert(m.alpha.end(), level.alpha.begin(), level.alpha.end());
    m.rme.push_back(rep.levels[std::size_t(k)].rme);
  }
  for (const TextonReport& r : rep.levels)
    for (const std::string& wmsg : r.warnings)
      if (std::find(rep.warnings.begin(), rep.warnings.end(), wmsg) == rep.warnings.end()) rep.warnings.push_back(wmsg);
  rep.ms_total = std::chrono::duration<double, std::milli>(Clock::now() - t_start).count();
  return m;
}

MixModel analyse_mix_files(const std::string& path_u, const std::string& path_v, const LoadOptions& opts,
                           MixParams params, MixReport* report) {
  std::vector<std::string> load_warnings;
  const Image u = load_exemplar(path_u, opts, &load_warnings);
  const Image v = load_exemplar(path_v, opts, &load_warnings);
  params.linear = opts.linear;
  MixReport local;
  MixReport& rep = report ? *report : local;
  MixModel m = analyse_mix(u, v, params, &rep);
  rep.warnings.insert(rep.warnings.begin(), load_warnings.begin(), load_warnings.end());
  const std::string* paths[2] = {&path_u, &path_v};
  for (int i = 0; i < 2; ++i) {
    const auto slash = paths[i]->find_last_of('/');
    m.exemplar_name[i] = slash == std::string::npos ? *paths[i] : paths[i]->substr(slash + 1);
    m.exemplar_hash[i] = sha256_file_hex(*paths[i]);
  }
  return m;
}

MixMap mix_map_from_image(const std::string& path, double scale, std::int64_t origin_x, std::int64_t origin_y,
                          bool clamp) {
  LoadOptions lo;
  lo.pixel_budget = std::uint64_t(k_mix_max_map_side) * std::uint64_t(k_mix_max_map_side);
  lo.what = "mixing map image";
  std::vector<std::string> warnings;
  const Image img = load_exemplar(path, lo, &warnings);
  MixMap m;
  m.type = MixMap::Type::Image;
  m.map_width = img.width;
  m.map_height = img.height;
  m.scale = scale;
  m.origin_x = origin_x;
  m.origin_y = origin_y;
  m.clamp = clamp;
  const auto slash = path.find_last_of('/');
  m.name = slash == std::string::npos ? path : path.substr(slash + 1);
  m.grey.resize(std::size_t(img.width) * img.height);
  for (std::size_t i = 0; i < m.grey.size(); ++i) {
    double s = 0.0;
    for (int c = 0; c < img.channels; ++c) s += img.pixels[i * img.channels + c];
    m.grey[i] = std::clamp(float(s / img.channels), 0.0f, 1.0f);  // float exemplars may leave [0, 1]
  }
  validate_mix_map(m, "--mix-map '" + path + "': ");
  return m;
}

MixMap parse_mix_map(const std::string& spec, double scale, const std::string& origin, const std::string& wrap,
                     bool image_options_given) {
  MixMap m;
  if (parse_analytic_mix_map(spec, &m)) {
    if (image_options_given)
      throw Error(ErrorKind::Usage, "--mix-scale, --mix-origin and --mix-wrap apply to image maps, not to '" + spec + "'");
    return m;
  }
  if (wrap != "repeat" && wrap != "clamp")
    throw Error(ErrorKind::Usage, "--mix-wrap must be repeat or clamp, got '" + wrap + "'");
  std::int64_t ox = 0, oy = 0;
  {
    const auto comma = origin.find(',');
    auto parse = [](const std::string& s, std::int64_t* v) {
      if (s.empty()) return false;
      errno = 0;
      char* end = nullptr;
      const long long r = std::strtoll(s.c_str(), &end, 10);
      if (errno != 0 || end != s.c_str() + s.size()) return false;
      *v = r;
      return true;
    };
    if (comma == std::string::npos || !parse(origin.substr(0, comma), &ox) || !parse(origin.substr(comma + 1), &oy))
      throw Error(ErrorKind::Usage, "--mix-origin must be X,Y (integers, output pixels), got '" + origin + "'");
  }
  // Parameters before the file: a bad scale or origin is a usage error whatever the file.
  MixMap probe;
  probe.type = MixMap::Type::Image;
  probe.map_width = probe.map_height = 1;
  probe.grey = {0.0f};
  probe.scale = scale;
  probe.origin_x = ox;
  probe.origin_y = oy;
  validate_mix_map(probe, "--mix-map '" + spec + "': ");
  return mix_map_from_image(spec, scale, ox, oy, wrap == "clamp");
}

}  // namespace stex
