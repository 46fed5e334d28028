// Cyclostationary spot noise by example and the "cs-spot" codec. See cs_spot_model.h.
#include "analysis/cs_spot_model.h"

#include <cmath>

#include "core/error.h"
#include "core/math.h"

namespace stex {

namespace {

using json = nlohmann::json;

// The 1-D window: a sin^2 ramp over `b` texels at each end, 1 inside.
std::vector<double> taper(int n, int b) {
  std::vector<double> w(n, 1.0);
  for (int i = 0; i < b && i < n; ++i) {
    const double s = std::sin(0.5 * k_pi * (i + 0.5) / b);
    w[i] = std::min(w[i], s * s);
    w[n - 1 - i] = std::min(w[n - 1 - i], s * s);
  }
  return w;
}

}  // namespace

CsSpotModel cs_spot_from_exemplar(const Image& exemplar, const Lattice& t, const CsSpotParams& params, CsSpotReport* report) {
  validate_lattice(t, exemplar.width, exemplar.height);
  // With a histogram transfer the noise is made of the Gaussianised exemplar E_G (S4 §5.3.2).
  Image gaussianised;
  CsHistTable hist;
  if (params.histogram != 0) {
    // In the PCA basis of the colours, as tiling and blending: channels transferred independently in the
    // colour basis would recombine into false colours (a binary orange / teal motif gives pink and green).
    std::vector<float> basis;
    Image coords;
    pca_coordinates(exemplar, &basis, &coords);
    hist = build_cs_hist(coords, &t, params.histogram, params.delta, &gaussianised);
    hist.basis = std::move(basis);
  }
  const Image& e = params.histogram != 0 ? gaussianised : exemplar;
  if (e.channels < 1 || e.channels > STEX_CS_MAX_CHANNELS)
    throw Error(ErrorKind::Input, "cs-spot needs an exemplar of 1..4 channels, got " + std::to_string(e.channels));
  if (e.width > k_cs_max_spot || e.height > k_cs_max_spot)
    throw Error(ErrorKind::Limit, "cs-spot exemplars are at most 4096 pixels on each side (the spot is the exemplar)");
  const int b = params.border < 0 ? std::min(e.width, e.height) / 8 : params.border;
  if (b > std::min(e.width, e.height) / 2)
    throw Error(ErrorKind::Usage, "--border must be at most half the exemplar's smaller side (" +
                                      std::to_string(std::min(e.width, e.height) / 2) + "), got " + std::to_string(b));
  const CyclicMean m = cyclic_mean(e, t);
  CsSpotModel s;
  s.t0x = t.t0x;
  s.t0y = t.t0y;
  s.t1x = t.t1x;
  s.t1y = t.t1y;
  s.width = e.width;
  s.height = e.height;
  s.channels = e.channels;
  s.n0 = m.n0;
  s.n1 = m.n1;
  s.mean = m.values;
  s.spot.resize(e.pixels.size());
  const std::vector<double> wx = taper(e.width, b), wy = taper(e.height, b);
  double ex = 0.0, ey = 0.0;
  for (double v : wx) ex += v * v;
  for (double v : wy) ey += v * v;
  for (int j = 0; j < e.height; ++j)
    for (int i = 0; i < e.width; ++i) {
      double u, v;
      lattice_phase(t, i + 0.5, j + 0.5, &u, &v);
      for (int c = 0; c < e.channels; ++c)
        s.spot[(std::size_t(j) * e.width + i) * e.channels + c] = float(wx[i] * wy[j] * (e.at(i, j, c) - m.at(u, v, c)));
    }
  s.amplitude = std::sqrt(lattice_area(t) / (ex * ey));
  s.hist = std::move(hist);
  validate_cs_spot_model(s);
  if (report) {
    report->periods = t;
    report->border = b;
    report->window_energy = ex * ey;
    report->mean_samples = m.min_samples;
  }
  return s;
}

}  // namespace stex
