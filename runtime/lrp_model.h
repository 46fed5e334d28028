// The local random-phase (LRP) noise model as the runtime consumes it (S3 §4-5): plain data, no I/O, and its
// translation into the kernel struct and tables of kernels/shared/lrp.h. Produced by analysis/lrp.{h,cpp}
// (noise by example, continuous spectra, structure), stored as kind "lrp" (docs/model-format.md), evaluated
// by runtime/lrp_renderer (device) and runtime/lrp_reference (C++).
//
// Units: positions in exemplar pixels; frequencies in bins of the T x T analysis grid (cycles per T pixels,
// integers in [-T/2, T/2)); the kernel multiplies them by 1/T.
//
// Render parameters (runtime/texton_params.h RenderParams): `seed`, `scale` and `filter` apply (a minified
// view fades every cosine by the footprint's transfer, S3 §6.4: make_lrp_setup); `mni` and `cell_factor`
// belong to Poisson-driven kinds and are ignored by LRP (its lattice spacing Delta_S is part of the model,
// S3 §4.3).
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "kernels/shared/lrp.h"
#include "runtime/texton_params.h"

namespace stex {

// One stratum S (S3 §4.2-4.3): its lattice spacing, amplitude, and J_S sub-strata, each a table of
// candidate frequencies (one is drawn per lattice cell and cosine, uniformly, plus a jitter inside its bin).
struct LrpStratum {
  double delta = 0.0;       // Delta_S = T sqrt(J_S) / sqrt(2 |S|), exemplar pixels
  // The largest cosine amplitude of the stratum: S3 eq. 3's A_S when every cosine has it (amplitudes
  // "paper"); with per-cosine amplitudes (analysis/lrp.h LrpAmplitudes) A_S max_q gain_q, and sub-stratum q's
  // cosines have amplitude x |colour weights of q| (norm gain_q / max gain <= 1).
  double amplitude = 0.0;
  double energy = 0.0;      // E_S = sum_{f in S} A^2(f) (PSD units of analysis/lrp.h)
  double psd_lo = 0.0, psd_hi = 0.0;  // the PSD interval I_S of the stratum (reporting)
  int size = 0;             // |S|: frequencies of the stratum on the full plane
  double erosion = 0.0;     // delta: the 75 % window-energy erosion radius, in bins
  std::vector<int> sub_counts;  // J_S entries: frequencies in each sub-stratum's table
};

struct LrpModel {
  int channels = 1;  // 1..4
  int period = 0;    // T: the analysis grid (power of two, 2..4096); frequencies are in cycles per T pixels
  std::array<float, 4> mean{};
  std::vector<LrpStratum> strata;  // at most STEX_LRP_MAX_STRATA
  // All sub-strata tables concatenated in stratum, sub-stratum order: (kx, ky) pairs, integers in bins.
  std::vector<std::int32_t> freqs;
  // Colour of every sub-stratum (2 * channels floats: p_c, q_c): channel c of a cosine of carrier phase
  // theta is A (p_c cos theta + q_c sin theta), A the stratum's amplitude. Grey: (g, 0), g = 1 for S3's
  // uniform amplitudes, else the sub-stratum's gain relative to the stratum's largest (norms <= 1).
  std::vector<float> colours;

  // Structure by fixed phases (S3 §5). ratio r = 0: none.
  double ratio = 0.0;          // r: energy ratio of the region R
  int block = 0;               // B: block side after the subdivision (divides T); 0 when r = 0
  int jr = 0;                  // J_R terms per block
  // blocks^2 * jr terms, block row-major, each (kx, ky, a_0, b_0, ..., a_{ch-1}, b_{ch-1}): value
  // a_c cos(2 pi k.d / B) + b_c sin(2 pi k.d / B), d = position - block origin.
  std::vector<float> terms;
  double structure_error = 0.0;  // mean |n_R - structure image| at the final subdivision (S3 §5.3)
  double sigma = 0.0;            // turbulence scale, exemplar pixels (0: off)
  // The turbulence n_T = sum_T |n_T| (S3 §5.2): strata of their own over the whole spectrum, evaluated as
  // carriers only (not added to the output); required when sigma > 0, empty otherwise. Their tables
  // (kx, ky pairs, same layout as freqs).
  std::vector<LrpStratum> turbulence;
  std::vector<std::int32_t> turb_freqs;
  bool placement = false;        // random placement by half-period blocks
  double blend = 0.25;           // placement blend band, fraction of a placement block

  // Provenance (stored, reported).
  int cosines = 0;  // J, the cosine budget
  std::uint64_t analysis_seed = 0;
  std::string source;  // "exemplar" or the analytic PSD spec ("ring:...") or "psd-image"
  std::string amplitudes = "paper";  // how the analysis set the cosines' amplitudes: paper, psd, psd-energy, fit
  bool linear = false;
  std::string exemplar_name, exemplar_hash;
  int exemplar_width = 0, exemplar_height = 0;
  std::string stex_version;

  int blocks() const { return block > 0 ? period / block : 0; }
  int total_sub_strata() const;  // of the output strata (colours are per output sub-stratum)
};

// The window integral int_0^inf r w^2(r) dr of the Kaiser-Bessel window of kernels/shared/lrp.h (alpha 3,
// radius 1.5), computed in double by Simpson's rule on I0's series (S3 eq. 3 needs it; the paper quotes
// about 0.1126 for its 5-term b_3 variant; with I0 it is 0.11958).
double lrp_window_integral();
// The window in double (I0 series to double accuracy), for the analysis and the tests.
double lrp_window(double y);

// Checks every field (sizes, ranges, finiteness, table consistency); throws stex::Error(Input) naming it.
void validate_lrp_model(const LrpModel& model);

// Everything the kernel and the reference need for one (model, parameters) pair.
struct LrpSetup {
  stex_lrp_params params{};
  std::vector<float> fdata;
  std::vector<std::uint32_t> udata;
  int channels = 0;
};

// Validates the model (Error(Input)) and the parameters (seed, scale: Error(Usage)); builds the setup.
LrpSetup make_lrp_setup(const LrpModel& model, const RenderParams& params);

}  // namespace stex
