// Lattice statistics of cyclostationary (CS) textures (Lutz, Sauvage, Dischler, "Cyclostationary Gaussian
// noise: theory and synthesis", EG 2021; "S4" in this repo): the period vectors t0, t1, the projection P onto
// the fundamental parallelogram Ω⁻ (eq. 2), polyphase components, the cyclic mean M (eq. 3), the coherence
// distance d(t0, t1) (eq. 10-11) and the estimation of the periods from an exemplar (S4 §6): an initial
// estimate from the peaks of the exemplar's autocorrelation, refined to sub-pixel precision by a
// deterministic pattern search on d, reported with d and a confidence.
//
// Coordinates ("model coordinates"): exemplar texel (i, j) covers [i, i + 1) x [j, j + 1), its centre is
// (i + 0.5, j + 0.5); the lattice is anchored at the origin (node k t0 + l t1). Continuous positions are read
// by bilinear interpolation between texel centres (S4 §7, "Implementation"). A phase (u, v) in [0, 1)^2 names
// the point u t0 + v t1 of Ω⁻, i.e. the polyphase component {(u + k) t0 + (v + l) t1}.
//
// Deviations from the paper, and why:
//  - d is the mean of d_PC over Ω⁻ (eq. 11 divided by |Ω⁻|): with the integral, the factor |Ω⁻| pulls the
//    minimum towards smaller parallelograms whenever d_PC > 0 (any noise), which biases sub-pixel periods.
//  - d_PC (eq. 10) is the mean over unordered pairs of distinct samples (eq. 10's double sum counts the zero
//    self-pairs and each pair twice: the same up to the factor (n - 1) / n), on a stratified set of phases
//    and at most `max_samples` samples per component, so one evaluation is bounded work.
//  - The minimisation is a deterministic pattern search (steps 1/2 pixel down to 1/256) instead of the
//    paper's stochastic gradient descent: the same input gives the same periods on every run, and the
//    public implementation's instability (issue 8) is avoided. Samples read out of the exemplar are clamped
//    to its border, and the sample set is fixed while the candidates of one step size are compared.
#pragma once
#include <string>
#include <vector>

#include "analysis/image_io.h"

namespace stex {

// Period vectors in model pixels (any parallelogram, sub-pixel).
struct Lattice {
  double t0x = 0.0, t0y = 0.0, t1x = 0.0, t1y = 0.0;
};

// |det(t0, t1)| = |Ω⁻| in pixels^2.
double lattice_area(const Lattice& t);
// Lattice coordinates (a, b) of the point (x, y): (x, y) = a t0 + b t1.
void lattice_coords(const Lattice& t, double x, double y, double* a, double* b);
// The phase of (x, y): the fractional parts of its lattice coordinates, in [0, 1) (eq. 2's P, in the basis).
void lattice_phase(const Lattice& t, double x, double y, double* u, double* v);
// The same lattice in reduced form (Lagrange-Gauss): |t0| <= |t1| <= |t1 - t0|, |t1 + t0|, t0 pointing to
// x > 0 (or straight down the +y axis), det(t0, t1) > 0. Two bases of one lattice reduce to the same basis
// (up to ties of equal lengths).
Lattice reduce_lattice(const Lattice& t);
// Whether a and b span the same lattice up to `tol` pixels: each basis vector of b is within tol of an integer
// combination of a's, that integer matrix is unimodular (|det| = 1: neither is a sub- or super-lattice of the
// other), and the same holds from a to b. The error (pixels) of the worst vector goes to *error if given.
bool lattices_match(const Lattice& a, const Lattice& b, double tol, double* error = nullptr);
// Checks user periods against an exemplar of width x height: finite, each at least 1 pixel long, Ω⁻ at
// least 2 pixels^2 and not degenerate (the angle between t0 and t1 at least 5 degrees), and Ω⁻ smaller than
// a quarter of the exemplar (so that each polyphase component has samples; 2 % more is let through for the
// sub-pixel error of an estimate of exactly two repetitions per axis). Error(Usage) naming the problem.
void validate_lattice(const Lattice& t, int width, int height);
// "t0x,t0y,t1x,t1y" -> Lattice (Error(Usage) for anything else; not validated against an exemplar).
Lattice parse_lattice(const std::string& text);

// Bilinear read of channel c at model position (x, y) (texel centres at i + 0.5); outside the hull of the
// texel centres the position is clamped to it (the nearest border value).
double sample_bilinear(const Image& img, double x, double y, int c);

// Positions (x, y) of the samples of polyphase component (u, v) whose bilinear footprint lies inside the
// exemplar (the hull [0.5, w - 0.5] x [0.5, h - 0.5] of texel centres): the estimate E^x of S4 §5.3.2.
std::vector<std::pair<double, double>> polyphase_positions(const Lattice& t, int width, int height, double u, double v);
// Their values, channels interleaved (positions.size() x img.channels).
std::vector<float> polyphase_component(const Image& img, const Lattice& t, double u, double v);

// The cyclic mean M (eq. 3) sampled on an n0 x n1 grid of phases (u, v) = (i / n0, j / n1), with
// n0 = ceil(2 |t0|), n1 = ceil(2 |t1|) (grid spacing at most 1/2 pixel along each period: sub-pixel periods
// put the samples of one component at every sub-pixel offset, so M is finer than the exemplar's pixels;
// 4 |Ω⁻| <= |E| keeps the grid no larger than the exemplar): each value is the mean of the polyphase
// component's samples. at() interpolates bilinearly on the periodic grid, so M is defined at every point of
// the plane: M(x) = at(phase(x)).
struct CyclicMean {
  Lattice periods;
  int n0 = 0, n1 = 0, channels = 0;
  std::vector<float> values;  // ((j * n0) + i) * channels + c
  int min_samples = 0;        // the fewest samples any grid phase had
  double at(double u, double v, int c) const;
  double at_point(double x, double y, int c) const;
};
// Error(Input) when a grid phase has fewer than 2 samples (the exemplar is too small for these periods).
CyclicMean cyclic_mean(const Image& img, const Lattice& t);

// eq. 10-11 as described above: mean over `phases` x `phases` stratified phases of the mean pairwise
// Euclidean (over channels) distance between at most `max_samples` samples of each component.
struct DistanceOptions {
  int phases = 16;
  int max_samples = 48;
};
double lattice_distance(const Image& img, const Lattice& t, const DistanceOptions& options = {});

// A lattice the estimator considered, with its distance d.
struct PeriodCandidate {
  Lattice periods;     // reduced
  double d = 0.0;
  std::string source;  // "autocorrelation peaks", "finer (index 2)", "refined", ...
};

struct PeriodEstimate {
  Lattice periods;           // refined, reduced
  Lattice initial;           // the autocorrelation estimate (reduced)
  double d = 0.0;            // lattice_distance at `periods`
  double d_initial = 0.0;    // at `initial`
  double d_stationary = 0.0; // the mean distance of random pairs of the exemplar: what d is without a lattice
  // (1 - d / d_stationary) x min(1, (d_finer - d) / (k_separation (d_stationary - d))), in [0, 1]: the share
  // of the exemplar's pair differences that the lattice explains, scaled down when the best lattice one step
  // finer is nearly as good (ambiguous, or a super-lattice). ~0.03 for a stationary exemplar; 0.22-0.36 on
  // the tile photographs of data/. Below k_low_confidence a warning is added.
  double confidence = 0.0;
  double peak0 = 0.0, peak1 = 0.0;  // normalised autocorrelation at the initial t0, t1 (1 = perfect repeat)
  int evaluations = 0;       // evaluations of d by the refinement
  double d_finer = 0.0;      // the lowest d of the lattices one step finer than `periods` (index 2, 3)
  std::vector<PeriodCandidate> candidates;  // best first
  std::vector<std::string> warnings;  // e.g. low confidence
};

// Decision thresholds, in units of the gap between the random pairs' distance and d:
//  - k_fit: a coarser candidate, or a lattice one step finer, "fits" when its d is within k_fit of the gap of
//    the best d (the primitive lattice is the smallest cell that fits);
//  - k_separation: the confidence is scaled down when the best finer lattice's excess over d is below
//    k_separation of the gap (an ambiguous or super-lattice estimate).
inline constexpr double k_low_confidence = 0.25;
// The weaker of the autocorrelation's two peaks that span the initial lattice, below which the exemplar does not
// repeat: estimate_periods then reports that lattice unrefined with confidence 0 and a warning. Measured: at
// most 0.11 on stochastic photographs and Gaussian noises (data/'s gravel, grass, leaves, brick and their
// ADSN), at least 0.18 on the 200 generated near-regular exemplars of `stex periods --corpus 200` (seed 1) and
// 0.45 on the tile photographs (docs/cyclostationary.md).
inline constexpr double k_repeat_peaks = 0.15;
inline constexpr double k_fit = 0.15;
inline constexpr double k_separation = 0.5;

struct EstimateOptions {
  DistanceOptions distance;
  double min_step = 1.0 / 256.0;  // the pattern search stops below this step (pixels)
  double max_step = 0.5;
};

// The estimation, on the exemplar with its lighting flattened (flatten_lighting) and blurred by a 1 px Gaussian
// (d, d_stationary and the confidence are of that image):
//  1. candidates: the lattices spanned by pairs of the shortest strong peaks of the autocorrelation (lags up
//     to half the exemplar along each axis, so two repetitions suffice), ordered by autocorrelation_candidates;
//  2. the first, refined by the pattern search to 1/16 pixel;
//  3. while the best lattice one step coarser (index 2 or 3, cells up to an eighth of the exemplar) has a d
//     lower by more than k_fit of the gap, that one (the peaks spanned a lattice finer than the texture's);
//     then while a lattice one step finer (t0 / 2, (t0 + t1) / 2, t1 / 3, ...) fits within k_fit, that one:
//     the primitive lattice, never a super-lattice of it;
//  4. sub-pixel registration of t0, t1, t0 +- t1 and their multiples on the gradient of the exemplar, the
//     lattice fitted by least squares; reduced; d, d_finer, confidence (the share of the random pairs'
//     distance explained, scaled down when a finer lattice is close: see k_separation), warnings that say
//     what to do.
// Error(Input) when the exemplar is smaller than 16 x 16, constant, or its autocorrelation has no two
// independent peaks.
PeriodEstimate estimate_periods(const Image& img, const EstimateOptions& options = {});
// The refinement alone, from a user's initial estimate (validated: Error(Usage)); S4 §6. A warning when a
// finer lattice fits as well (the periods given may be a multiple of the texture's).
PeriodEstimate refine_periods(const Image& img, const Lattice& initial, const EstimateOptions& options = {});
// Periods used as given (validated against the exemplar: Error(Usage)): d, the random pairs' distance and the
// confidence 1 - d / d_stationary, with a warning below k_low_confidence; no refinement.
PeriodEstimate given_periods(const Image& img, const Lattice& periods);
// The candidate lattices of step 1 with their d (coarse options), the first the chosen one: the smallest cell
// among those whose d is within k_fit of the gap of the lowest, then the others by d. Error(Input) as above.
// peak0, peak1: the autocorrelation values of the peaks that span the first.
std::vector<PeriodCandidate> autocorrelation_candidates(const Image& img, double* peak0 = nullptr, double* peak1 = nullptr);
// The first of them.
Lattice autocorrelation_periods(const Image& img, double* peak0 = nullptr, double* peak1 = nullptr);
// Each channel divided by its least-squares plane (times the plane's mean), or, where the plane comes near
// zero, minus it: a lighting gradient across the exemplar no longer separates its cells.
Image flatten_lighting(const Image& img);

// The mean distance between random pairs of texels (fixed pseudo-random pairs): d_stationary above.
double stationary_distance(const Image& img);

}  // namespace stex
