// Histogram transfer tables: validation and the device form. See cs_hist.h.
#include "runtime/cs_hist.h"

#include <cmath>

#include "core/error.h"

namespace stex {

static_assert(sizeof(stex_cs_hist_params) == 32, "stex_cs_hist_params must match the OpenCL layout (32 bytes)");

const char* cs_hist_mode_name(int mode) { return mode == 1 ? "stationary" : mode == 2 ? "cs" : "none"; }

void validate_cs_hist(const CsHistTable& t, int channels, int width, int height, const std::string& what) {
  auto bad = [&](const std::string& msg) { throw Error(ErrorKind::Input, what + ": histogram " + msg); };
  if (t.mode == 0) {
    if (!t.quantiles.empty()) bad("mode none carries no table");
    return;
  }
  if (t.mode != 1 && t.mode != 2) bad("mode must be none, stationary or cs");
  if (t.delta < 0 || t.delta > k_cs_hist_max_delta) bad("delta must be 0.." + std::to_string(k_cs_hist_max_delta));
  if (t.channels != channels) bad("channels do not match the model's");
  if (t.m0 < 1 || t.m1 < 1 || t.m0 > 4096 || t.m1 > 4096) bad("bins must be 1..4096 on each side");
  if (t.mode == 1 && (t.m0 != 1 || t.m1 != 1)) bad("a stationary transfer has one bin");
  if (t.q < 2 || t.q > 65536) bad("q must be 2..65536 quantiles");
  // The table is no larger than the exemplar (per channel): S4 §5.3.2's memory bound.
  if (double(t.m0) * t.m1 * t.q > double(width) * height)
    bad("table (" + std::to_string(t.m0) + " x " + std::to_string(t.m1) + " bins x " + std::to_string(t.q) +
        " quantiles) is larger than the exemplar");
  const std::size_t n = std::size_t(t.m0) * t.m1 * std::size_t(channels) * t.q;
  if (t.quantiles.size() != n) bad("quantiles size does not match bins x channels x q");
  for (std::size_t s = 0; s < n; s += std::size_t(t.q))
    for (int k = 0; k < t.q; ++k) {
      const float v = t.quantiles[s + k];
      if (!std::isfinite(v) || std::fabs(v) > 1e30f) bad("a quantile is not finite");
      if (k > 0 && v < t.quantiles[s + k - 1]) bad("quantiles must be non-decreasing within a bin");
    }
  if (!t.basis.empty() && t.basis.size() != std::size_t(channels) * (channels + 1))
    bad("basis must have channels x (channels + 1) floats");
  for (float v : t.basis)
    if (!std::isfinite(v) || std::fabs(v) > 1e30f) bad("basis has a non-finite value");
}

stex_cs_hist_params cs_hist_params(const CsHistTable& t) {
  stex_cs_hist_params h{};
  if (!t.enabled()) {
    h.m0 = h.m1 = 1;
    h.q = 0;
    h.channels = 1;
    h.phi_size = 2;
    return h;
  }
  h.m0 = t.m0;
  h.m1 = t.m1;
  h.q = t.q;
  h.channels = t.channels;
  h.phi_size = k_cs_hist_phi_size;
  h.phi_lo = float(k_cs_hist_phi_lo);
  h.phi_scale = float(double(k_cs_hist_phi_size - 1) / (k_cs_hist_phi_hi - k_cs_hist_phi_lo));
  h.basis = t.basis.empty() ? 0 : 1;
  return h;
}

std::vector<float> cs_hist_device_table(const CsHistTable& t) {
  if (!t.enabled()) return {0.0f};
  std::vector<float> out(static_cast<std::size_t>(k_cs_hist_phi_size), 0.0f);
  for (int i = 0; i < k_cs_hist_phi_size; ++i) {
    const double g = k_cs_hist_phi_lo + (k_cs_hist_phi_hi - k_cs_hist_phi_lo) * i / (k_cs_hist_phi_size - 1);
    out[std::size_t(i)] = float(0.5 * std::erfc(-(g - 0.5) * 6.0 / std::sqrt(2.0)));
  }
  out.insert(out.end(), t.quantiles.begin(), t.quantiles.end());
  out.insert(out.end(), t.basis.begin(), t.basis.end());
  return out;
}

}  // namespace stex
