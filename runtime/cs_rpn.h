// Cyclostationary random-phase noise from user spectra (S4 §3.3 eq. 6, §4.2, Fig. 1 left and 4; kind
// "cs-rpn"): the model, its render setup (stex_csr_params of kernels/shared/cs_rpn.h, the spectrum tables, the
// node table of cs.h, the Poisson table), the C++ reference on the shared header, the expected local PSD, and
// the device renderer (kernels/cs_rpn.cl). Making a model from spectrum specs and the codec are in
// analysis/cs_rpn_model.h.
//
// Model fields, documented once here:
//  - variant: random-phase (local random-phase sums on a lattice, S3 eq. 1), gabor (sparse Gabor convolution),
//    phasor (Tricard et al. 2019 on the Gabor impulses), fourier (S4 Fig. 4's Fourier series, eq. 6 as
//    written: repeats every 1 / bin model pixels): kernels/shared/cs_rpn.h gives each formula.
//  - periods t0, t1 (model pixels): the parallelogram over which the spectra are laid out.
//  - grid k0 x k1 (1..16 each) of spectra: spectrum j * k0 + i sits at phase (i / k0, j / k1); the local PSD
//    at phase u is their periodic bilinear interpolation.
//  - spectra: each an energy E_g >= 0 (the variance it gives the noise; at least one > 0) and bins (fx, fy,
//    weight) in cycles per model pixel, |f| <= 0.5, weight > 0 (relative power; a half plane: f and -f are
//    one cosine's two lobes).
//  - bin (cycles per model pixel, (0, 0.25]): every drawn frequency is jittered uniformly in a bin of this
//    width around its table entry (the grid step of the spectra: a continuous spectrum, not a comb).
//    fourier: 1 / bin = T must be a power of two 16..1024 and every bin on the grid k / T (no jitter).
//  - mean: the output mean.
//  - bandwidth a (gabor, phasor; [1/1024, 1], 1 / model pixel): the envelope exp(-pi a^2 |d|^2).
//  - spacing Delta (random phase; [1, 4096] model pixels) and cosines J (1..256) per lattice point.
// Render parameters (runtime/texton_params.h RenderParams): seed and scale; gabor and phasor also take mni
// (mean number of impulses whose envelope disc covers a point) and cell_factor as `gabor`; random phase
// ignores them (the lattice is part of the model). Output: 1 channel.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "kernels/shared/cs_rpn.h"
#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/gather_renderer.h"
#include "runtime/noise_renderer.h"
#include "runtime/program.h"
#include "runtime/texton_params.h"

namespace stex {

enum class CsRpnVariant {
  RandomPhase = STEX_CSR_RANDOM_PHASE,
  Gabor = STEX_CSR_GABOR,
  Phasor = STEX_CSR_PHASOR,
  Fourier = STEX_CSR_FOURIER
};

// "random-phase", "gabor", "phasor", "fourier".
std::string cs_rpn_variant_name(CsRpnVariant v);
// The inverse; Error(Usage) naming the accepted names.
CsRpnVariant parse_cs_rpn_variant(const std::string& name);

struct CsRpnSpectrum {
  double energy = 0.0225;   // E_g
  std::vector<float> bins;  // (fx, fy, weight) per bin
  std::string source;       // where it came from ("bilobe:0.1,30,0.01", an image name); informative only
};

struct CsRpnModel {
  CsRpnVariant variant = CsRpnVariant::Gabor;
  double t0x = 64.0, t0y = 0.0, t1x = 0.0, t1y = 64.0;
  int k0 = 1, k1 = 1;
  std::vector<CsRpnSpectrum> spectra;  // k0 * k1
  double bin = 1.0 / 64.0;
  double mean = 0.5;
  double bandwidth = 0.05;
  double spacing = 16.0;
  int cosines = 16;
};

inline constexpr int k_cs_rpn_max_bins = 65536;          // per spectrum
inline constexpr std::size_t k_cs_rpn_max_total_bins = 1u << 20;
inline constexpr int k_cs_rpn_max_cosines = 256;
inline constexpr std::size_t k_cs_rpn_max_fourier = 16384;  // frequencies of a Fourier series

// Checks every field; Error(Input) naming it ("invalid cs-rpn model: ...").
void validate_cs_rpn_model(const CsRpnModel& model);

struct CsRpnSetup {
  stex_csr_params params{};
  std::vector<float> fdata;            // E_g, then (fx, fy) per bin
  std::vector<std::uint32_t> udata;    // (offset, count) per spectrum, then thresholds
  std::vector<std::uint32_t> reduce;   // node table (cs.h)
  std::vector<std::uint32_t> poisson;  // Poisson thresholds (gabor, phasor; one dummy entry otherwise)
  double lambda = 0.0;                 // impulses per model pixel^2 (gabor, phasor)
};

// Validates model (Error(Input)) and parameters (Error(Usage): seed, scale, mni, cell; the period vectors must
// stay at least 1 output pixel long). With params.filter at scale < 1, the variants that filter
// (cs_rpn_filters) get the filtered tables of a minified view (kernels/shared/cs_rpn.h, docs/filtering.md).
CsRpnSetup make_cs_rpn_setup(const CsRpnModel& model, const RenderParams& params);
// Whether a minified view of the model is filtered: every variant but phasor.
bool cs_rpn_filters(const CsRpnModel& model);

// The expected local PSD at phase (u, v) of the parallelogram on a T x T grid of frequency bins (FFT order,
// index (ky mod T) * T + (kx mod T), bin k = k / T cycles per model pixel), before the kernels' spectral
// blur: sum_g w_g(u) E_g p_g, each bin's power split between f and -f, jitter included (the power of a
// table entry spread over the bins its jitter square overlaps). Sums to E(u). For the tests and docs.
std::vector<double> cs_rpn_local_psd(const CsRpnModel& model, double u, double v, int period);
// E(u) (the interpolated energy).
double cs_rpn_energy(const CsRpnModel& model, double u, double v);

// The C++ reference: stex_csr_eval compiled as C++, one call per pixel (single-threaded; tests).
class CsRpnReference {
 public:
  CsRpnReference(const CsRpnModel& model, const RenderParams& params) : setup_(make_cs_rpn_setup(model, params)) {}
  // Pixels [x, x + width) x [y, y + height), row-major, 1 channel. Validates the region (Error(Usage)).
  std::vector<float> render(std::int64_t x, std::int64_t y, int width, int height) const;
  const CsRpnSetup& setup() const { return setup_; }

 private:
  CsRpnSetup setup_;
};

class CsRpnNoise final : public GatherRenderer {
 public:
  // Validates the model (Error(Input)); options.strategy must be "auto" or "gather" (Error(Usage)).
  CsRpnNoise(Context& ctx, const CsRpnModel& model, const NoiseRendererOptions& options = {});
  std::string kind() const override { return "cs-rpn"; }
  int channels() const override { return 1; }
  const CsRpnModel& model() const { return model_; }

 private:
  void set_params(const RenderParams& params) override;
  cl_uint set_model_args(Kernel& kernel, cl_uint first) override;

  CsRpnModel model_;
  CsRpnSetup setup_;
  Buffer<float> fdata_;
  Buffer<std::uint32_t> udata_, reduce_, poisson_;
};

}  // namespace stex
