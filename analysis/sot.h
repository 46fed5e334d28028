// The synthesis-oriented texton (SOT): S2 §3, Algorithm 2, on an arbitrary support mask S
// (analysis/support_mask.h), for grey and colour exemplars, with a tolerance stop and an iteration cap; and
// the statistics of S2 Fig. 2 (mean and standard deviation of the RME after n iterations over random
// initialisations).
//
// Algorithm 2 is S1 Algorithm 1 with b^ = 1 (analysis/texton.h, order 0) and the square support replaced by
// S; the same conventions hold:
//  - t_u = (p - mean)/sqrt(|Omega|) of the exemplar's periodic component p (S2 eq. 3);
//  - initialisation: alpha_0 = the white Gaussian noise of texton_initial_noise(seed) (one field per
//    channel). The first projection p_{t_u}(alpha_0) = t_u^ e^{i psi} with psi = arg(t_u^* alpha_0^) (per
//    frequency, jointly over the channels): psi is uniform and independent across frequencies up to the
//    Hermitian symmetry of a real image, so this is S2's random-phase initialisation t^ <- t_u^ e^{i psi}
//    (the RPN of t_u, Galerne-Gousseau-Morel) and iteration 1 yields its crop q_S(RPN);
//  - iteration: t <- q_S(p_{t_u}(t)), with p_{t_u} the projection of S2 eq. 2 (per frequency, the
//    orthogonal projection of t^(xi) onto the C^d-circle {e^{i phi} t_u^(xi)}; where t_u^* t^ = 0 the phase
//    1 is taken, which stays on the circle, whereas eq. 2's indicator would give 0) and q_S(t) = t 1_S with S
//    at [0, s)^2 of Omega;
//  - RME_n = RME(t_n, t_u) of S2 §3.2 (analysis/ot_distance.h: sqrt of the squared OT distance of eq. 1
//    between CADSN(t_u) and CADSN(t_n) on Omega, xi != 0, over the marginal variance sum_{xi!=0} |t_u^|^2).
//    It is computed from the forward transform that the next iteration needs anyway, so the history costs
//    O(|Omega|) per iteration. RME_n is non-increasing in n: it is the distance from t_n to the modulus
//    constraint set, and each half-step of an alternating projection onto a set and a subspace cannot
//    increase it (Fienup's error-reduction argument);
//  - stop: after the cap n = max_iterations, or after iteration n >= 2 when |RME_n - RME_{n-1}| < tolerance
//    (tolerance 0 runs the cap).
// The model (TextonModel, order 0, support s = the mask's size, alpha zero outside S) renders with
// `stex render` (texton noise of order 0 = S2's DSN with the grid Poisson process) and the comparison modes.
// Colour: the colour covariance correction of analysis/texton.h (S2 §4: "a 3x3 linear transform of the
// colour channels") is applied after the iterations unless disabled; it keeps alpha zero outside S.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/fft.h"
#include "analysis/gaussian_model.h"
#include "analysis/image_io.h"
#include "analysis/support_mask.h"
#include "runtime/model.h"

namespace stex {

struct SotRun {
  std::vector<double> alpha;        // planar channels x s x s, zero outside the mask (not colour-corrected)
  int iterations = 0;               // iterations run
  bool converged = false;           // stopped by the tolerance (false: the cap)
  std::vector<double> rme_history;  // RME_n for n = 1..iterations (RME of the returned alpha = back())
};

// The fixed data of Algorithm 2 on one exemplar and one mask: t_u, its spectrum, the RME denominator. Runs
// are independent and const (thread-safe: each run owns its FFT buffers).
class SotSolver {
 public:
  // Error(Input) for a malformed exemplar or one smaller than the mask (in either dimension).
  SotSolver(const Image& exemplar, const SupportMask& mask);
  SotSolver(NormalisedKernel tu, const SupportMask& mask);

  // Algorithm 2 from the initialisation of `seed` (or the injected alpha0: planar channels x H x W).
  // Error(Usage) for max_iterations < 1, a negative or non-finite tolerance, a wrong alpha0 size.
  SotRun run(std::uint64_t seed, int max_iterations, double tolerance = 0.0,
             const std::vector<double>* alpha0 = nullptr) const;

  // RME (S2 §3.2) of an order-0 texton alpha (planar channels x s x s, placed at [0, s)^2) against t_u.
  double rme(const std::vector<double>& alpha) const;

  const NormalisedKernel& kernel() const { return tu_; }
  const std::vector<Complex>& kernel_spectrum() const { return u_hat_; }  // full, planar
  const SupportMask& mask() const { return mask_; }
  int width() const { return tu_.width; }
  int height() const { return tu_.height; }
  int channels() const { return tu_.channels; }

 private:
  void init();
  NormalisedKernel tu_;
  SupportMask mask_;
  std::vector<Complex> u_hat_;   // full spectrum of t_u, planar
  std::vector<Complex> u_half_;  // half spectrum (kx <= W/2), planar
  double den_ = 0.0;             // sum_{xi != 0} |t_u^(xi)|^2
};

struct SotParams {
  SupportMask mask = square_mask(31);
  int max_iterations = 1000;  // the cap
  double tolerance = 0.0;     // |RME_n - RME_{n-1}| < tolerance stops (0: run the cap)
  std::uint64_t seed = 0;
  bool colour_correction = true;
  bool linear = false;                          // recorded in the model
  const std::vector<double>* alpha0 = nullptr;  // injected initialisation (tests)
};

struct SotReport {
  int iterations = 0;
  bool converged = false;
  std::vector<double> rme_history;
  double rme = 0.0;            // RME of the SOT before the colour correction (= rme_history.back())
  double rme_corrected = 0.0;  // after it
  double variance_kept = 0.0;  // trace of the model's colour covariance / the exemplar's, before correction
  std::vector<double> colour_matrix;
  std::size_t support_pixels = 0;  // |S|
  double ms_total = 0.0;
  std::vector<std::string> warnings;
};

// Algorithm 2 + colour correction into an order-0 TextonModel (support = mask size, alpha zero outside S).
// Errors as SotSolver / SotSolver::run (Error(Usage) for bad parameters, Error(Input) for the exemplar).
TextonModel analyse_sot(const Image& exemplar, const SotParams& params, SotReport* report = nullptr);
// Loads `path` (load_exemplar with opts), analyses it, records the exemplar's file name and SHA-256.
TextonModel analyse_sot_file(const std::string& path, const LoadOptions& opts, SotParams params,
                             SotReport* report = nullptr, std::vector<std::string>* warnings = nullptr);

// S2 Fig. 2: RME_n over `inits` random initialisations (seeds first_seed, first_seed + 1, ...), n
// = 1..iterations (no tolerance stop): empirical mean and standard deviation (n - 1 normalisation) for every
// n. `threads` workers (>= 1) share the initialisations; the result does not depend on `threads` (per-seed
// histories are combined in seed order).
struct SotConvergence {
  int inits = 0, iterations = 0;
  std::vector<double> mean, stddev;  // index n - 1
  std::vector<double> final_rme;     // RME_iterations of every initialisation, in seed order
  double ms_total = 0.0;
};
SotConvergence sot_convergence(const SotSolver& solver, int inits, int iterations,
                               std::uint64_t first_seed = 0, int threads = 1);

}  // namespace stex
