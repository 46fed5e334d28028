// Contrast field and spectrum-of-variance renormalisation (S5 Fig. 6, 9, 10, 13-17). See contrast.h.
#include "analysis/contrast.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "analysis/device_fft.h"
#include "analysis/fft.h"
#include "core/error.h"
#include "core/math.h"
#include "runtime/gabor_params.h"

namespace stex {

namespace {

constexpr std::uint64_t k_max_pixels = std::uint64_t(1) << 26;

[[noreturn]] void usage(const std::string& m) { throw Error(ErrorKind::Usage, m); }

// One FFT interface for both backends (analysis/fft.h convention: forward unnormalised, inverse 1/(w h)).
class Fft2 {
 public:
  Fft2(const std::string& which, Context* ctx) {
    if (which == "device") {
      if (!ctx) usage("--fft device needs an OpenCL device");
      dev_ = std::make_unique<DeviceFft>(*ctx);
    } else if (which != "host") {
      usage("--fft must be device or host, got '" + which + "'");
    }
  }
  void run(int w, int h, std::vector<Complex>& d, bool inverse) {
    if (!dev_) {
      inverse ? fft2d_inverse(w, h, d) : fft2d_forward(w, h, d);
      backend = "fftw (host)";
      return;
    }
    std::vector<ComplexF> f(d.size());
    for (std::size_t i = 0; i < d.size(); ++i) f[i] = ComplexF(float(d[i].real()), float(d[i].imag()));
    backend = dev_->transform(w, h, f, inverse) == DeviceFft::Backend::ClFft ? "clfft" : "fftw";
    for (std::size_t i = 0; i < d.size(); ++i) d[i] = Complex(f[i].real(), f[i].imag());
  }
  std::string backend;

 private:
  std::unique_ptr<DeviceFft> dev_;
};

double freq(int k, int n) { return double(k >= (n + 1) / 2 ? k - n : k) / n; }

void check_image(const Image& im, const char* what) {
  if (im.width < 2 || im.height < 2 || im.channels < 1 || im.channels > 4)
    usage(std::string(what) + " must be at least 2x2 with 1..4 channels");
  if (std::uint64_t(im.width) * std::uint64_t(im.height) > k_max_pixels)
    throw Error(ErrorKind::Limit, std::string(what) + " has more than 2^26 pixels");
  if (im.pixels.size() != std::size_t(im.width) * im.height * im.channels)
    throw Error(ErrorKind::Internal, std::string(what) + ": pixel count does not match its size");
}

void check_options(const ContrastOptions& o) {
  if (!std::isfinite(o.L) || o.L < 1.0 || o.L > 1e5) usage("--L (stationarity scale) must be in [1, 1e5] pixels");
}

// Planes of an image (double) and their means.
struct Planes {
  int w = 0, h = 0, nc = 0;
  std::vector<std::vector<double>> p;
  std::vector<double> mean;
};

Planes planes_of(const Image& im) {
  Planes s;
  s.w = im.width;
  s.h = im.height;
  s.nc = im.channels;
  s.p.assign(s.nc, std::vector<double>(std::size_t(s.w) * s.h));
  s.mean.assign(s.nc, 0.0);
  for (std::size_t i = 0; i < std::size_t(s.w) * s.h; ++i)
    for (int c = 0; c < s.nc; ++c) {
      s.p[c][i] = im.pixels[i * s.nc + c];
      s.mean[c] += s.p[c][i];
    }
  for (double& m : s.mean) m /= double(std::size_t(s.w) * s.h);
  return s;
}

Image image_of(const Planes& s) {
  Image im;
  im.width = s.w;
  im.height = s.h;
  im.channels = s.nc;
  im.pixels.resize(std::size_t(s.w) * s.h * s.nc);
  for (std::size_t i = 0; i < std::size_t(s.w) * s.h; ++i)
    for (int c = 0; c < s.nc; ++c) im.pixels[i * s.nc + c] = float(s.p[c][i]);
  return im;
}

// The transfer function that selects the variance-spectrum features (Fig. 10 LF_filter, Fig. 14 red).
std::vector<double> selection_filter(int w, int h, double L, LobeSelection sel,
                                     const std::vector<std::array<double, 2>>& lobes) {
  std::vector<std::array<double, 2>> centres{{0.0, 0.0}};
  for (std::size_t i = 0; i < lobes.size() && sel != LobeSelection::LowFrequency; ++i) {
    for (std::size_t j = 0; j < lobes.size(); ++j) {
      const double sx = lobes[i][0] + lobes[j][0], sy = lobes[i][1] + lobes[j][1];
      const bool same = std::hypot(lobes[i][0] - lobes[j][0], lobes[i][1] - lobes[j][1]) < 1e-9;
      const bool opposite = std::hypot(sx, sy) < 1e-9;
      if (opposite) continue;  // the LF lobe, already in
      if ((sel == LobeSelection::LfPureLobes) == same) centres.push_back({sx, sy});
    }
  }
  const double sigma = L / 2.0, k = 2.0 * k_pi * k_pi * sigma * sigma;
  std::vector<double> f(std::size_t(w) * h, 0.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double u = freq(x, w), v = freq(y, h);
      double best = 0.0;
      for (const auto& c : centres) {
        double du = u - c[0], dv = v - c[1];
        du -= std::round(du);
        dv -= std::round(dv);
        best = std::max(best, std::exp(-k * (du * du + dv * dv)));
      }
      f[std::size_t(y) * w + x] = best;
    }
  return f;
}

// E = LF * (mean over channels of (x_c - m_c)^2); also the variance spectrum |FFT(sq)| if asked.
std::vector<double> second_moment(const Planes& s, const std::vector<double>& means, const std::vector<double>& filter,
                                  Fft2& fft, std::vector<double>* spectrum) {
  const std::size_t n = std::size_t(s.w) * s.h;
  std::vector<Complex> f(n);
  for (std::size_t i = 0; i < n; ++i) {
    double sq = 0.0;
    for (int c = 0; c < s.nc; ++c) sq += (s.p[c][i] - means[c]) * (s.p[c][i] - means[c]);
    f[i] = Complex(sq / s.nc, 0.0);
  }
  fft.run(s.w, s.h, f, false);
  if (spectrum) {
    spectrum->assign(n, 0.0);
    for (int y = 0; y < s.h; ++y)
      for (int x = 0; x < s.w; ++x)
        (*spectrum)[std::size_t((y + s.h / 2) % s.h) * s.w + (x + s.w / 2) % s.w] = std::abs(f[std::size_t(y) * s.w + x]);
  }
  for (std::size_t i = 0; i < n; ++i) f[i] *= filter[i];
  fft.run(s.w, s.h, f, true);
  std::vector<double> e(n);
  for (std::size_t i = 0; i < n; ++i) e[i] = f[i].real();
  return e;
}

std::vector<double> sqrt_abs(const std::vector<double>& e) {
  std::vector<double> c(e.size());
  for (std::size_t i = 0; i < e.size(); ++i) c[i] = std::sqrt(std::fabs(e[i]));
  return c;
}

// Initial footprint (Fig. 10 imf_footprint) on the FFT grid: weights in [0, 1] that multiply the spectrum.
std::vector<double> footprint_of(const Planes& s, const RenormOptions& o, Fft2& fft) {
  const std::size_t n = std::size_t(s.w) * s.h;
  std::vector<double> psd(n, 0.0);
  if (o.footprint_psd) {
    for (int y = 0; y < s.h; ++y)
      for (int x = 0; x < s.w; ++x) psd[std::size_t(y) * s.w + x] = o.footprint_psd(freq(x, s.w), freq(y, s.h));
  } else {
    // Periodogram smoothed in frequency: FFT of the autocorrelation times a Gaussian window of std L / 2
    // (frequency smoothing of std 1 / (pi L)), which keeps the lobes and removes the periodogram's noise.
    for (int c = 0; c < s.nc; ++c) {
      std::vector<Complex> f(n);
      for (std::size_t i = 0; i < n; ++i) f[i] = Complex(s.p[c][i] - s.mean[c], 0.0);
      fft.run(s.w, s.h, f, false);
      for (auto& v : f) v = Complex(std::norm(v), 0.0);
      fft.run(s.w, s.h, f, true);  // autocorrelation
      const double sw = o.L / 2.0;
      for (int y = 0; y < s.h; ++y)
        for (int x = 0; x < s.w; ++x) {
          const double dx = freq(x, s.w) * s.w, dy = freq(y, s.h) * s.h;
          f[std::size_t(y) * s.w + x] *= std::exp(-(dx * dx + dy * dy) / (2.0 * sw * sw));
        }
      fft.run(s.w, s.h, f, false);
      for (std::size_t i = 0; i < n; ++i) psd[i] += std::max(0.0, f[i].real());
    }
  }
  const double peak = *std::max_element(psd.begin(), psd.end());
  std::vector<double> m(n, 0.0);
  if (!(peak > 0.0)) return m;
  for (std::size_t i = 0; i < n; ++i)
    m[i] = o.smooth_footprint ? std::sqrt(psd[i] / peak) : (psd[i] >= o.footprint_threshold * peak ? 1.0 : 0.0);
  return m;
}

double total_variance(const Planes& s, const std::vector<double>& means) {
  double v = 0.0;
  for (int c = 0; c < s.nc; ++c)
    for (double x : s.p[c]) v += (x - means[c]) * (x - means[c]);
  return v / double(std::size_t(s.w) * s.h);
}

}  // namespace

LobeSelection parse_lobe_selection(const std::string& name) {
  if (name == "lf") return LobeSelection::LowFrequency;
  if (name == "lf+interferences") return LobeSelection::LfInterferences;
  if (name == "lf+pure") return LobeSelection::LfPureLobes;
  usage("--select must be lf, lf+interferences or lf+pure, got '" + name + "'");
}

ContrastStats contrast_stats(const std::vector<double>& c, int w, int h, double L) {
  ContrastStats s;
  const int m = (w > 4 * L && h > 4 * L) ? int(std::ceil(L)) : 0;
  s.margin = m;
  double sum = 0.0, sq = 0.0;
  s.min = std::numeric_limits<double>::infinity();
  s.max = -s.min;
  std::size_t n = 0;
  for (int y = m; y < h - m; ++y)
    for (int x = m; x < w - m; ++x) {
      const double v = c[std::size_t(y) * w + x];
      sum += v;
      sq += v * v;
      s.min = std::min(s.min, v);
      s.max = std::max(s.max, v);
      ++n;
    }
  s.mean = sum / double(n);
  s.stddev = std::sqrt(std::max(0.0, sq / double(n) - s.mean * s.mean));
  s.cov = s.mean > 0.0 ? s.stddev / s.mean : 0.0;
  return s;
}

ContrastField contrast_field(const Image& image, const ContrastOptions& o, Context* ctx) {
  check_image(image, "the image");
  check_options(o);
  Fft2 fft(o.fft, ctx);
  const Planes s = planes_of(image);
  ContrastField out;
  out.width = s.w;
  out.height = s.h;
  out.mean = std::accumulate(s.mean.begin(), s.mean.end(), 0.0) / s.nc;
  out.second_moment =
      second_moment(s, s.mean, selection_filter(s.w, s.h, o.L, LobeSelection::LowFrequency, {}), fft, &out.variance_spectrum);
  out.contrast = sqrt_abs(out.second_moment);
  out.stats = contrast_stats(out.contrast, s.w, s.h, o.L);
  return out;
}

Image renormalize(const Image& image, const RenormOptions& o, Context* ctx, RenormReport* report) {
  check_image(image, "the image");
  check_options(o);
  if (!(o.min_contrast > 0.0) || o.min_contrast > 10.0) usage("--min-contrast must be in (0, 10]");
  if (o.iterations < 1 || o.iterations > 1000) usage("--iterations must be 1..1000");
  if (!(o.footprint_threshold > 0.0) || o.footprint_threshold >= 1.0) usage("--footprint-threshold must be in (0, 1)");
  for (const auto& l : o.lobes)
    if (!std::isfinite(l[0]) || !std::isfinite(l[1]) || std::fabs(l[0]) > 0.5 || std::fabs(l[1]) > 0.5)
      usage("a lobe centre must be within [-0.5, 0.5] cycles per pixel");
  if (o.selection != LobeSelection::LowFrequency && o.lobes.empty())
    usage("--select " + std::string(o.selection == LobeSelection::LfPureLobes ? "lf+pure" : "lf+interferences") +
          " needs the spectrum's lobes (--lobe or --model)");
  if (!std::isnan(o.reference_contrast) && !(o.reference_contrast > 0.0 && std::isfinite(o.reference_contrast)))
    usage("the reference contrast must be positive");
  Fft2 fft(o.fft, ctx);
  Planes s = planes_of(image);
  const std::vector<double> mean0 = s.mean;
  std::vector<double> means = s.mean;
  if (!std::isnan(o.mean)) means.assign(s.nc, o.mean);
  const double var0 = total_variance(s, mean0);
  const std::size_t n = std::size_t(s.w) * s.h;
  const std::vector<double> filter = selection_filter(s.w, s.h, o.L, o.selection, o.lobes);
  const std::vector<double> lf = selection_filter(s.w, s.h, o.L, LobeSelection::LowFrequency, {});
  std::vector<double> footprint;
  if (o.quality) footprint = footprint_of(s, o, fft);
  RenormReport rep;
  const int passes = o.quality ? o.iterations : 1;
  for (int it = 0; it < passes; ++it) {
    // Renormalisation (both modes).
    std::vector<double> c = sqrt_abs(second_moment(s, means, filter, fft, nullptr));
    rep.passes.push_back(contrast_stats(o.selection == LobeSelection::LowFrequency
                                            ? c
                                            : sqrt_abs(second_moment(s, means, lf, fft, nullptr)),
                                        s.w, s.h, o.L));
    const double cref = std::isnan(o.reference_contrast) ? *std::max_element(c.begin(), c.end()) : o.reference_contrast;
    for (std::size_t i = 0; i < n; ++i) {
      const double k = (o.min_contrast + 1.0) / (o.min_contrast + c[i] / cref);
      for (int ch = 0; ch < s.nc; ++ch) s.p[ch][i] = means[ch] + (s.p[ch][i] - means[ch]) * k;
    }
    // Spectrum reprofiling (quality mode): clamp the spectrum to its initial footprint.
    if (o.quality) {
      for (int ch = 0; ch < s.nc; ++ch) {
        std::vector<Complex> f(n);
        for (std::size_t i = 0; i < n; ++i) f[i] = Complex(s.p[ch][i] - means[ch], 0.0);
        fft.run(s.w, s.h, f, false);
        for (std::size_t i = 0; i < n; ++i) f[i] *= footprint[i];
        f[0] = Complex(0.0, 0.0);
        fft.run(s.w, s.h, f, true);
        for (std::size_t i = 0; i < n; ++i) s.p[ch][i] = means[ch] + f[i].real();
      }
    }
  }
  if (o.keep_std) {
    std::vector<double> m(s.nc, 0.0);
    for (int ch = 0; ch < s.nc; ++ch) m[ch] = std::accumulate(s.p[ch].begin(), s.p[ch].end(), 0.0) / double(n);
    const double var = total_variance(s, m);
    const double g = var > 0.0 ? std::sqrt(var0 / var) : 1.0;
    for (int ch = 0; ch < s.nc; ++ch)
      for (double& v : s.p[ch]) v = mean0[ch] + (v - m[ch]) * g;
    means = mean0;
  }
  rep.passes.push_back(contrast_stats(sqrt_abs(second_moment(s, means, lf, fft, nullptr)), s.w, s.h, o.L));
  rep.fft_backend = fft.backend;
  if (report) *report = rep;
  return image_of(s);
}

Image apply_contrast_map(const Image& r, const Image& map, double mean) {
  check_image(r, "the image");
  check_image(map, "the contrast map");
  if (map.width != r.width || map.height != r.height) usage("the contrast map must have the image's size");
  Image out = r;
  for (std::size_t i = 0; i < std::size_t(r.width) * r.height; ++i) {
    double m = 0.0;
    for (int c = 0; c < map.channels; ++c) m += map.pixels[i * map.channels + c];
    m /= map.channels;
    for (int c = 0; c < r.channels; ++c) {
      float& v = out.pixels[i * r.channels + c];
      v = float(mean + (v - mean) * m);
    }
  }
  return out;
}

Image dominance_blend(const Image& a, const Image& b, const Image& map, const RenormOptions& o, Context* ctx) {
  check_image(a, "the first noise");
  check_image(b, "the second noise");
  check_image(map, "the dominance map");
  if (b.width != a.width || b.height != a.height || b.channels != a.channels || map.width != a.width ||
      map.height != a.height)
    usage("the dominance noise and map must have the image's size and channels");
  const Image na = renormalize(a, o, ctx), nb = renormalize(b, o, ctx);
  Image mix = na;
  for (std::size_t i = 0; i < std::size_t(a.width) * a.height; ++i) {
    double m = 0.0;
    for (int c = 0; c < map.channels; ++c) m += map.pixels[i * map.channels + c];
    m /= map.channels;
    for (int c = 0; c < a.channels; ++c) {
      const std::size_t k = i * a.channels + c;
      mix.pixels[k] = float((1.0 - m) * na.pixels[k] + m * nb.pixels[k]);
    }
  }
  return renormalize(mix, o, ctx);
}

Image renormalize_layers(const std::vector<Image>& layers, const RenormOptions& o, Context* ctx) {
  if (layers.empty()) usage("no layers");
  Image sum = layers[0];
  for (std::size_t l = 1; l < layers.size(); ++l) {
    if (layers[l].width != sum.width || layers[l].height != sum.height || layers[l].channels != sum.channels)
      usage("every layer must have the first one's size and channels");
    for (std::size_t i = 0; i < sum.pixels.size(); ++i) sum.pixels[i] += layers[l].pixels[i];
  }
  Image acc = renormalize(layers[0], o, ctx);
  for (std::size_t l = 1; l < layers.size(); ++l) {
    const Image r = renormalize(layers[l], o, ctx);
    for (std::size_t i = 0; i < acc.pixels.size(); ++i) acc.pixels[i] += r.pixels[i];
  }
  // Rescale to the plain sum's mean and standard deviation (per channel).
  const Planes ps = planes_of(sum);
  Planes pa = planes_of(acc);
  for (int c = 0; c < pa.nc; ++c) {
    double va = 0.0, vs = 0.0;
    for (std::size_t i = 0; i < pa.p[c].size(); ++i) {
      va += (pa.p[c][i] - pa.mean[c]) * (pa.p[c][i] - pa.mean[c]);
      vs += (ps.p[c][i] - ps.mean[c]) * (ps.p[c][i] - ps.mean[c]);
    }
    const double g = va > 0.0 ? std::sqrt(vs / va) : 1.0;
    for (double& v : pa.p[c]) v = ps.mean[c] + (v - pa.mean[c]) * g;
  }
  return image_of(pa);
}

Image content_constraint(const Image& noise, const Image& drawing, double w, const RenormOptions& o, Context* ctx) {
  check_image(noise, "the noise");
  check_image(drawing, "the drawing");
  if (drawing.width != noise.width || drawing.height != noise.height) usage("the drawing must have the noise's size");
  if (!(w >= 0.0 && w <= 1.0)) usage("--weight must be in [0, 1]");
  const Planes pn = planes_of(noise);
  std::vector<double> d(std::size_t(noise.width) * noise.height, 0.0);
  for (std::size_t i = 0; i < d.size(); ++i) {
    for (int c = 0; c < drawing.channels; ++c) d[i] += drawing.pixels[i * drawing.channels + c];
    d[i] /= drawing.channels;
  }
  const double md = std::accumulate(d.begin(), d.end(), 0.0) / double(d.size());
  double vd = 0.0;
  for (double v : d) vd += (v - md) * (v - md);
  vd /= double(d.size());
  Image mix = noise;
  for (int c = 0; c < noise.channels; ++c) {
    double vn = 0.0;
    for (double v : pn.p[c]) vn += (v - pn.mean[c]) * (v - pn.mean[c]);
    vn /= double(d.size());
    const double g = vd > 0.0 ? std::sqrt(vn / vd) : 0.0;
    for (std::size_t i = 0; i < d.size(); ++i) {
      const double dv = pn.mean[c] + (d[i] - md) * g;
      mix.pixels[i * noise.channels + c] = float((1.0 - w) * dv + w * pn.p[c][i]);
    }
  }
  return renormalize(mix, o, ctx);
}

Image apply_lut(const Image& image, const Image& lut) {
  check_image(image, "the image");
  if (lut.width < 2 || lut.height < 1 || lut.channels < 1) usage("the LUT must be at least 2 pixels wide");
  const std::size_t n = std::size_t(image.width) * image.height;
  std::vector<double> v(n, 0.0);
  double mean = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < image.channels; ++c) v[i] += image.pixels[i * image.channels + c];
    v[i] /= image.channels;
    mean += v[i];
  }
  mean /= double(n);
  double peak = 0.0;
  for (double x : v) peak = std::max(peak, std::fabs(x - mean));
  Image out;
  out.width = image.width;
  out.height = image.height;
  out.channels = std::min(lut.channels, 3);
  out.pixels.resize(n * out.channels);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = peak > 0.0 ? 0.5 + (v[i] - mean) / (2.0 * peak) : 0.5;
    const double pos = std::clamp(t, 0.0, 1.0) * (lut.width - 1);
    const int x0 = std::min(int(pos), lut.width - 2);
    const double f = pos - x0;
    for (int c = 0; c < out.channels; ++c)
      out.pixels[i * out.channels + c] = float((1.0 - f) * lut.at(x0, 0, c) + f * lut.at(x0 + 1, 0, c));
  }
  return out;
}

std::vector<std::array<double, 2>> gabor_lobes(const GaborModel& m) {
  std::vector<std::array<double, 2>> l;
  for (const GaborComponent& c : m.components) {
    if (c.spread != 0.0 || c.weight <= 0.0 || c.frequency == 0.0) continue;
    const double fx = c.frequency * std::cos(c.orientation), fy = c.frequency * std::sin(c.orientation);
    l.push_back({fx, fy});
    l.push_back({-fx, -fy});
  }
  return l;
}

RenormalizedNoise::RenormalizedNoise(Context& ctx, std::unique_ptr<NoiseRenderer> inner, RenormOptions options,
                                     double overlap)
    : ctx_(ctx), inner_(std::move(inner)), options_(std::move(options)) {
  if (std::isnan(options_.mean) || std::isnan(options_.reference_contrast))
    usage("tiled renormalisation needs a fixed mean and reference contrast (the model's)");
  if (!(overlap >= 0.0 && overlap <= 64.0)) usage("--overlap must be in [0, 64] (in units of L)");
  check_options(options_);
  options_.keep_std = false;  // the input's std depends on the tile
  // The sharp footprint's spatial kernel is long-ranged (a thresholded PSD): tiles padded by 3 L then
  // differ by ~0.3 std; the smooth footprint's is about the Gabor kernel's size (docs/contrast.md).
  options_.smooth_footprint = true;
  pad_ = int(std::ceil(overlap * options_.L));
}

NoiseRenderStats RenormalizedNoise::render(const RenderParams& params, std::int64_t x, std::int64_t y, int width,
                                           int height, float* out) {
  const int pw = width + 2 * pad_, ph = height + 2 * pad_;
  if (std::uint64_t(pw) * std::uint64_t(ph) > k_max_pixels)
    throw Error(ErrorKind::Limit, "a renormalised tile with its overlap exceeds 2^26 pixels: use smaller tiles");
  Image padded;
  padded.width = pw;
  padded.height = ph;
  padded.channels = inner_->channels();
  padded.pixels.resize(std::size_t(pw) * ph * padded.channels);
  NoiseRenderStats stats = inner_->render(params, x - pad_, y - pad_, pw, ph, padded.pixels.data());
  const Image r = renormalize(padded, options_, &ctx_);
  const int nc = padded.channels;
  for (int j = 0; j < height; ++j)
    std::copy(r.pixels.begin() + (std::ptrdiff_t(j + pad_) * pw + pad_) * nc,
              r.pixels.begin() + (std::ptrdiff_t(j + pad_) * pw + pad_ + width) * nc,
              out + std::size_t(j) * width * nc);
  stats.strategy += "+renormalize";
  return stats;
}

}  // namespace stex
