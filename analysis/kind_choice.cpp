// `stex analyze --method auto` (analysis/kind_choice.h).
#include "analysis/kind_choice.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "analysis/periodic.h"
#include "core/error.h"
#include "model/kinds.h"

namespace stex {
namespace {

constexpr double k_pi = 3.14159265358979323846;

// One channel as doubles.
std::vector<double> channel(const Image& img, int c) {
  std::vector<double> u(std::size_t(img.width) * img.height);
  for (std::size_t i = 0; i < u.size(); ++i) u[i] = img.pixels[i * img.channels + c];
  return u;
}

void check_size(const Image& img) {
  if (img.width < 2 || img.height < 2 || img.channels < 1)
    throw Error(ErrorKind::Input, "the exemplar (" + std::to_string(img.width) + "x" + std::to_string(img.height) +
                                      ") is too small to choose a kind: at least 2x2 pixels");
}

// The standard normal quantile: Acklam's rational approximation (relative error below 1.2e-9), then one
// Halley step on erfc, for p in (0, 1).
double normal_quantile(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                             1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01,  -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
  const double p_low = 0.02425;
  double x;
  if (p < p_low || p > 1.0 - p_low) {
    const double q = std::sqrt(-2.0 * std::log(p < p_low ? p : 1.0 - p));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
    if (p > 1.0 - p_low) x = -x;
  } else {
    const double q = p - 0.5, r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
  }
  const double e = 0.5 * std::erfc(-x / std::sqrt(2.0)) - p;
  const double u = e * std::sqrt(2.0 * k_pi) * std::exp(0.5 * x * x);
  return x - u / (1.0 + 0.5 * x * u);
}

}  // namespace

Image cyclic_residual(const Image& img, const Lattice& t) {
  const CyclicMean m = cyclic_mean(img, t);
  Image out = img;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < img.channels; ++c)
        out.at(x, y, c) = float(img.at(x, y, c) - m.at_point(x + 0.5, y + 0.5, c));
  return out;
}

double gradient_ratio(const Image& img) {
  check_size(img);
  const int w = img.width, h = img.height;
  double tv = 0.0, expected = 0.0;
  for (int c = 0; c < img.channels; ++c) {
    // The periodic component (Moisan), as the Gaussian analyses use: the wrap-around jumps of a photograph
    // are not part of its texture, and the ADSN's derivatives are the periodic ones.
    const std::vector<double> p = periodic_component(w, h, channel(img, c));
    double abs_x = 0.0, abs_y = 0.0, sq_x = 0.0, sq_y = 0.0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double v = p[std::size_t(y) * w + x];
        const double gx = p[std::size_t(y) * w + (x + 1) % w] - v;
        const double gy = p[std::size_t((y + 1) % h) * w + x] - v;
        abs_x += std::fabs(gx);
        abs_y += std::fabs(gy);
        sq_x += gx * gx;
        sq_y += gy * gy;
      }
    const double n = double(w) * h;
    tv += (abs_x + abs_y) / n;
    expected += std::sqrt(2.0 / k_pi) * (std::sqrt(sq_x / n) + std::sqrt(sq_y / n));
  }
  return expected > 0.0 ? tv / expected : 1.0;  // a constant exemplar: nothing a Gaussian model loses
}

double marginal_distance(const Image& img) {
  check_size(img);
  const std::size_t n = std::size_t(img.width) * img.height;
  // The normal quantiles at (i + 1/2) / n, shared by the channels.
  std::vector<double> q(n);
  for (std::size_t i = 0; i < n; ++i) q[i] = normal_quantile((double(i) + 0.5) / double(n));
  double sum = 0.0;
  int counted = 0;
  for (int c = 0; c < img.channels; ++c) {
    std::vector<double> u = channel(img, c);
    double mean = 0.0, var = 0.0;
    for (double v : u) mean += v;
    mean /= double(n);
    for (double v : u) var += (v - mean) * (v - mean);
    const double sd = std::sqrt(var / double(n));
    if (!(sd > 0.0)) continue;  // a constant channel has no histogram to keep
    std::sort(u.begin(), u.end());
    double w1 = 0.0;
    for (std::size_t i = 0; i < n; ++i) w1 += std::fabs((u[i] - mean) / sd - q[i]);
    sum += w1 / double(n);
    ++counted;
  }
  return counted ? sum / counted : 0.0;
}

KindChoice choose_kind(const Image& exemplar, const std::vector<std::string>& allowed) {
  if (allowed.empty()) throw Error(ErrorKind::Internal, "choose_kind: no kind allowed");
  const auto is_allowed = [&](const char* k) { return std::find(allowed.begin(), allowed.end(), k) != allowed.end(); };
  KindChoice ch;
  ch.gradient_ratio = gradient_ratio(exemplar);
  ch.marginal_distance = marginal_distance(exemplar);
  bool structured =
      ch.gradient_ratio < k_auto_gradient_ratio || ch.marginal_distance > k_auto_marginal_distance;
  char buf[256];
  std::snprintf(buf, sizeof buf, "gradient ratio %.3f (%s %.2f), marginal distance %.3f (%s %.2f)",
                ch.gradient_ratio, ch.gradient_ratio < k_auto_gradient_ratio ? "<" : ">=", k_auto_gradient_ratio,
                ch.marginal_distance, ch.marginal_distance > k_auto_marginal_distance ? ">" : "<=",
                k_auto_marginal_distance);
  const std::string gauss = std::string(buf) + (structured ? ": far from Gaussian" : ": near Gaussian");

  std::string lattice_text;
  if (is_allowed(kinds::cs_spot) || is_allowed(kinds::cs_tb)) {
    ch.lattice_searched = true;
    try {
      // The autocorrelation's strongest pair of peaks first (~0.1 s): a texture that does not repeat has
      // weak peaks, and the refinement is not run on it.
      double peak0 = 0.0, peak1 = 0.0;
      const Lattice initial = autocorrelation_periods(exemplar, &peak0, &peak1);
      ch.peaks = std::min(peak0, peak1);
      if (ch.peaks < k_repeat_peaks) {
        std::snprintf(buf, sizeof buf, "no repetition (autocorrelation peaks %.2f < %.2f)", ch.peaks, k_repeat_peaks);
        lattice_text = buf;
      } else {
        try {
          ch.periods = estimate_periods(exemplar);
        } catch (const Error& e) {
          // The refinement failed on a texture that repeats: the autocorrelation lattice, as given periods
          // would be taken (d and the confidence of that lattice).
          if (e.kind() != ErrorKind::Input) throw;
          try {
            ch.periods = given_periods(exemplar, initial);
          } catch (const Error& invalid) {  // validate_lattice's Usage error: here a property of the input
            throw Error(ErrorKind::Input, invalid.what());
          }
          ch.periods.warnings.push_back(std::string("the refinement failed (") + e.what() +
                                        "): the autocorrelation's periods are used");
        }
        ch.lattice = ch.periods.confidence >= k_auto_lattice_confidence;
        const Lattice& t = ch.periods.periods;
        std::snprintf(buf, sizeof buf, "lattice (%.2f, %.2f), (%.2f, %.2f) at confidence %.2f (%s %.2f)", t.t0x,
                      t.t0y, t.t1x, t.t1y, ch.periods.confidence, ch.lattice ? ">=" : "<", k_auto_lattice_confidence);
        lattice_text = buf;
      }
    } catch (const Error& e) {
      if (e.kind() != ErrorKind::Input) throw;
      lattice_text = std::string("no lattice (") + e.what() + ")";
    }
  }
  if (ch.lattice) {
    // On a lattice, what is left once the cyclic mean is removed decides: cs-spot reproduces the cyclic mean
    // exactly and a Gaussian texture around it; tiling and blending keeps cells that differ in structure.
    const Image residual = cyclic_residual(exemplar, ch.periods.periods);
    ch.residual_gradient_ratio = gradient_ratio(residual);
    ch.residual_marginal_distance = marginal_distance(residual);
    structured = ch.residual_gradient_ratio < k_auto_gradient_ratio ||
                 ch.residual_marginal_distance > k_auto_marginal_distance;
    std::snprintf(buf, sizeof buf, "; without the cyclic mean: gradient ratio %.3f, marginal distance %.3f: %s",
                  ch.residual_gradient_ratio, ch.residual_marginal_distance,
                  structured ? "far from Gaussian" : "near Gaussian");
    lattice_text += buf;
  }

  // The preference order of each case: the best kind first, then the next best.
  std::vector<const char*> order;
  if (ch.lattice && structured)
    order = {kinds::cs_tb, kinds::cs_spot, kinds::tb, kinds::texton};
  else if (ch.lattice)
    order = {kinds::cs_spot, kinds::cs_tb, kinds::texton, kinds::tb};
  else if (structured)
    order = {kinds::tb, kinds::cs_tb, kinds::texton, kinds::cs_spot};
  else
    order = {kinds::texton, kinds::cs_spot, kinds::tb, kinds::cs_tb};
  for (const char* k : order)
    if (is_allowed(k)) {
      ch.kind = k;
      break;
    }
  if (ch.kind.empty()) throw Error(ErrorKind::Internal, "choose_kind: none of the allowed kinds can be picked");
  ch.why = gauss + (lattice_text.empty() ? std::string() : "; " + lattice_text);
  if (ch.kind != order[0]) ch.why += "; " + std::string(order[0]) + " would suit it best, but the options given exclude it";
  return ch;
}

}  // namespace stex
