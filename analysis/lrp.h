// Local random-phase noise by example (S3 = Gilet et al., "Local Random-Phase Noise for Procedural
// Texturing", ACM TOG 33(6), 2014): the analysis that turns an exemplar (or an analytic PSD, or a PSD image)
// into an LrpModel (runtime/lrp_model.h), and the model's container codec (kind "lrp", docs/model-format.md).
//
// Noise by example (S3 §4):
//  - PSD by Welch's method: crops of T x T, T the largest power of two strictly below the exemplar's smaller
//    side (at most 1024), step T/2 (50 % overlap), each multiplied by a separable Hann window
//    h(i) = sin^2(pi (i + 1/2) / T) after removing the exemplar mean; P(f) = mean_crops |FFT(h u)(f)|^2 /
//    (T^2 sum h^2), so that sum_f P(f) is the variance (channels: trace of the cross-spectral matrix).
//  - L strata (default 4) of equal energy: intervals of the PSD range cut where the cumulative energy of
//    the frequencies sorted by decreasing P crosses k E / L (S3 §4.2). J_S = J_strata / L (the remainder to
//    the strongest strata).
//  - Delta_S = T sqrt(J_S) / sqrt(2 |S|) (S3 §4.3), |S| counted on the full plane.
//  - Erosion by delta = delta_1 / Delta_S where delta_1 holds 75 % of the energy of the 1-D window's spectrum
//    |w^(nu)|^2 in [-delta_1, delta_1] (solved numerically); a connected part of a stratum that the
//    erosion would sweep out keeps its deepest points (the paper's "strata smaller than delta are not
//    completely swept out").
//  - k-means into J_S sub-strata on the half plane (ky > 0, or ky = 0 and kx > 0), seeded with J_S distinct
//    random points (counter RNG keyed by the analysis seed and the stratum), Lloyd to convergence.
//  - A_S by eq. 3 with int_0^inf r w^2(r) dr computed (runtime/lrp_model.h): A_S = E_S^(1/2) (Delta_S^2 J_S
//    pi int r w^2)^(-1/2), where E_S is the stratum's energy over the area Delta_S^2 one lattice point
//    serves, E_S = Delta_S^2 sum_{f in S} P(f): a local noise's energy J_S A_S^2 Delta_S^2 pi int r w^2
//    then equals it, and the noise's variance equals the stratum's share of the exemplar's variance.
//  - Colour: one shared random phase per cosine; each sub-stratum has a complex colour vector v (unit norm),
//    the leading eigenvector of its cross-spectral matrix sum_f X(f) X(f)^H: channel c of a cosine is
//    A_S Re(v_c e^{i theta}). docs/lrp.md explains the choice.
//
// Texture by example (S3 §5): region R = the highest-P frequencies holding a fraction r of the energy,
// with amplitudes and phases of the first (top-left) Welch crop, unwindowed; J_R = round(r J) cosines per
// block; the structure image (inverse FFT of the crop's spectrum on R) is subdivided into blocks of B = T,
// T/2, ... until the mean |error| of keeping each block's J_R highest-amplitude terms is below 1/256
// (S3 Fig. 9); the strata share the remaining budget (1 - r) J over the frequencies outside R.
// Turbulence (sigma > 0): its own coarse strata over the whole spectrum (LrpParams::turbulence_*), so it
// works at any r including r = 1 (no random-phase strata left); random placement is stored for the evaluator.
#pragma once
#include <complex>
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/image_io.h"
#include "model/codecs.h"
#include "runtime/lrp_model.h"

namespace stex {

// The cosines' amplitudes. Paper: S3 as written: J / L cosines per stratum, all of eq. 3's A_S, sub-strata
// of equal area (k-means). The others give the strata J_S proportional to sqrt|S| (LrpParams::
// allocation_power; a bigger Delta_S, so a narrower window spectrum, for the big low-power strata) and each
// sub-stratum's cosines their own amplitude: Psd: sub-strata of equal area, each carrying the PSD's energy over
// its cell (normalised so that each stratum keeps eq. 3's energy); PsdEnergy: the same on sub-strata of about
// equal energy (k-means weighted by P^2); Fit: PsdEnergy's sub-strata and gains, then every amplitude fitted
// to the target spectrum through the model's exact expected spectrum (analysis/lrp_psd.h lrp_fit_gains).
// docs/lrp.md compares them.
enum class LrpAmplitudes { Paper, Psd, PsdEnergy, Fit };
const char* lrp_amplitudes_name(LrpAmplitudes a);
// "paper", "psd", "psd-energy", "fit"; Error(Usage) naming the choices otherwise.
LrpAmplitudes parse_lrp_amplitudes(const std::string& name);

// Parameters of the LRP analysis; documented once here (`stex analyze --method lrp --help` draws on it).
struct LrpParams {
  int cosines = 50;         // J: the cosine budget per lattice point (S3 §6.3: about 50 for textures)
  int strata = 5;           // L (S3 §4.2 uses 4 in all the paper's examples; 5 with fitted amplitudes, docs/lrp.md)
  double ratio = 0.0;       // r in [0, 1]: energy ratio of the fixed-phase region R (S3 §5.1); 0 = noise
  double sigma = 0.0;       // turbulence scale in exemplar pixels (S3 §5.2); needs r > 0
  bool placement = false;   // random placement by half-period blocks (S3 §5.2); needs r > 0
  std::uint64_t seed = 0;   // k-means seeding
  LrpAmplitudes amplitudes = LrpAmplitudes::Fit;  // per-cosine amplitudes (see LrpAmplitudes)
  // Cosine budget per stratum unless amplitudes are Paper (S3: J / L each): J_S proportional to |S|^power.
  double allocation_power = 0.5;
  int fit_iterations = 500;  // LrpAmplitudes::Fit: multiplicative updates (converged to 1e-3 on data/'s exemplars)
  double erosion_energy = 0.75;         // the 75 % window-energy rule (S3 §4.3)
  double stop_error = 1.0 / 256.0;      // the colour-precision stop of the block subdivision (S3 §5.3)
  int max_period = 1024;                // cap on T (analysis time and model size)
  // The turbulence n_T (S3 §5.2, built when sigma > 0): "a rough stratification and a low cosine budget"
  // of the whole spectrum (R included), its own strata, carriers only.
  int turbulence_strata = 2;
  int turbulence_cosines = 8;
};

// A T x T spectrum in FFT order (index (ky mod T) * T + (kx mod T)).
struct LrpSpectrum {
  int period = 0, channels = 0;
  std::vector<double> psd;                     // P(f): trace over channels; sum = total variance
  std::vector<std::complex<double>> cross;     // channels^2 per frequency (row-major X_a conj(X_b)); may be empty
  std::vector<std::complex<double>> phases;    // channels planes of the first crop's FFT (unwindowed); may be empty
  std::vector<double> mean;                    // per channel
  int crops = 0;
};

struct LrpStratumReport {
  double energy_share = 0.0;  // E_S / E (sum of P over S / total)
  int size = 0, eroded_size = 0, js = 0;
  double delta = 0.0, erosion = 0.0, amplitude = 0.0;  // amplitude: eq. 3's A_S
  double max_amplitude = 0.0;  // the largest cosine amplitude of the stratum (A_S for LrpAmplitudes::Paper)
};

struct LrpReport {
  int period = 0, crops = 0;
  double variance = 0.0;         // sum_f P(f)
  double window_integral = 0.0;  // int r w^2 dr
  double delta1 = 0.0;           // erosion constant for Delta = 1 (cycles)
  std::vector<LrpStratumReport> strata;
  std::vector<LrpStratumReport> turbulence;  // the turbulence strata (sigma > 0)
  int region_size = 0;           // |R| (full plane)
  double region_share = 0.0;     // energy of R / total
  int jr = 0, block = 0, levels = 0;
  double structure_error = 0.0;
  double ms = 0.0;
};

// Welch PSD of an exemplar (see above). Error(Input) when the exemplar is smaller than 4 x 4.
LrpSpectrum lrp_welch(const Image& exemplar, int max_period = 1024);

// Analytic PSD (continuous-spectrum mode, S3 Fig. 3 and 10) on a T x T grid, normalised to variance
// `variance`: "ring:F,W" (radius F cycles/pixel, Gaussian radial width W), "bilobe:F,A,W" (two Gaussian
// lobes of width W at +-F cycles/pixel in direction A degrees), "gauss:FX,FY,W[;FX,FY,W...]" (Gaussian lobes
// at (+-FX, +-FY)). The weakest frequencies holding together at most 1e-4 of the energy are set to 0 (also
// for PSD images): they would otherwise count in |S| and shrink Delta_S (see lrp.cpp). Error(Usage) naming
// the problem.
LrpSpectrum lrp_analytic_psd(const std::string& spec, int period = 256, double variance = 0.0225);
// A PSD given as a square power-of-two grey image with the zero frequency at the centre (pixel (T/2, T/2));
// values are relative powers (symmetrised), normalised to `variance`. Error(Input) for a bad image.
LrpSpectrum lrp_psd_from_image(const Image& image, double variance = 0.0225);

// The erosion constant: delta_1 such that `fraction` of the 1-D window spectrum's energy lies in
// [-delta_1, delta_1] (cycles, for Delta = 1).
double lrp_erosion_delta1(double fraction = 0.75);

// The analysis proper on a spectrum (exemplar or analytic). Error(Usage) for bad parameters.
LrpModel lrp_from_spectrum(const LrpSpectrum& spectrum, const LrpParams& params, LrpReport* report = nullptr);
// Welch + lrp_from_spectrum.
// `spectrum`, when given, receives the exemplar's Welch PSD.
LrpModel analyse_lrp(const Image& exemplar, const LrpParams& params, LrpReport* report = nullptr,
                     LrpSpectrum* spectrum = nullptr);
// Loads the exemplar and records its name and SHA-256.
LrpModel analyse_lrp_file(const std::string& path, const LoadOptions& opts, const LrpParams& params,
                          LrpReport* report = nullptr, std::vector<std::string>* warnings = nullptr,
                          LrpSpectrum* spectrum = nullptr);

// The structure image of a spectrum for a ratio r (T x T x channels interleaved, mean added): the inverse
// FFT of the first crop's spectrum on R. Exposed for the tests (r = 1 is the crop itself).
std::vector<float> lrp_structure_image(const LrpSpectrum& spectrum, double ratio);
// The region R of a ratio r as a T x T mask (FFT order; conjugate pairs together; empty region for r = 0).
std::vector<char> lrp_region_mask(const LrpSpectrum& spectrum, double ratio);


}  // namespace stex
