// Histogram transfer tables of cyclostationary models (S4 §5.3; kernels/shared/cs_hist.h evaluates them,
// analysis/cs_hist.h builds them). Used by cs-spot and cs-tb.
//
// Fields:
//  - mode: 0 none (no table), 1 stationary (one bin: m0 = m1 = 1), 2 cyclostationary (per polyphase bin).
//  - delta: the neighbourhood (S4 §5.3.3) the bins' samples were pooled over (information; 0 for stationary).
//  - m0 x m1 bins over the phases (u, v) of the lattice (bin (i, j) = u in [i/m0, (i+1)/m0), v likewise).
//  - q quantiles per bin and channel at p_k = (k + 1/2) / q, non-decreasing in k.
//  - basis (optional): the PCA basis of the transferred channels (cs-spot; cs-tb has its own).
//  Memory bound: m0 * m1 * q <= the exemplar's pixel count (the table is at most as large as the exemplar,
//  S4 §5.3.2), checked by validate_cs_hist.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "kernels/shared/cs_hist.h"

namespace stex {

struct CsHistTable {
  int mode = 0;  // 0 none, 1 stationary, 2 cs
  int delta = 0;
  int m0 = 0, m1 = 0, q = 0, channels = 0;
  std::vector<float> quantiles;  // ((j * m0 + i) * channels + c) * q + k
  // Empty, or the PCA basis the values are in (cs-spot): channels means, then channels x channels rows of B
  // (y = B (x - mean)); the render maps back with mean + B^T y.
  std::vector<float> basis;
  bool enabled() const { return mode != 0; }
};

inline constexpr int k_cs_hist_phi_size = 4096;
inline constexpr double k_cs_hist_phi_lo = -0.25, k_cs_hist_phi_hi = 1.25;  // g range (0.5 -+ 4.5 sigma)
inline constexpr int k_cs_hist_max_delta = 64;

// "none", "stationary", "cs" (names of the modes, as in the CLI and the model file).
const char* cs_hist_mode_name(int mode);
// Checks every field against the model's channels and exemplar size; throws Error(Input) starting with
// `what` ("invalid cs-tb model: histogram ...").
void validate_cs_hist(const CsHistTable& t, int channels, int width, int height, const std::string& what);
// The kernel parameters (q = 0 when disabled) and the device table (the CDF table then the quantiles; a
// single 0 when disabled, so that a buffer can always be made).
stex_cs_hist_params cs_hist_params(const CsHistTable& t);
std::vector<float> cs_hist_device_table(const CsHistTable& t);

}  // namespace stex
