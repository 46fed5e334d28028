// Gaussian and spot-noise renders of texture models on the host (`stex render --mode ...`), S2 §2.1-2.4:
//  - ADSN (`adsn`, on Z^2): mean + k * W, the convolution on Z^2 of a kernel k (the exemplar's t_u, or a
//    model's texton kernel) with a standard Gaussian white noise W keyed by absolute pixel coordinates
//    (S2 §2.1: ADSN(h) = h * W). Computed by FFT over the region plus a margin of the kernel size (S2 §2.4's
//    "larger domain and a crop"): the noise of [x - kw + 1, x + w) x [y - kh + 1, y + h) is enough for the
//    pixels of [x, x + w) x [y, y + h), and a circular convolution on a domain that large has no wrap-around
//    on them. So a pixel depends only on (kernel, seed, its coordinates): tile-invariant, up to the rounding
//    of the FFT's sums (which depend on the domain size): tiles agree with the whole to about 1e-13 relative
//    in double, i.e. within one float ulp after the conversion to float (tested). Covariance: k * k~
//    (linear).
//  - CADSN (`cadsn`, circular ADSN on Theta, S2 §2.2): mean + k (.) W by FFT on Theta = [x, x + max(w, kw)) x
//    [y, y + max(h, kh)), k zero-padded at the origin (S2 §2.4); W keyed by absolute coordinates. Periodic on
//    Theta by definition, so a render depends on its region (not tile-invariant); covariance k (.) k~ on
//    Theta. synthesize_adsn(exemplar, ...) is CADSN of t_u (S1 §3.1-3.2, the exemplar's Gaussian texture).
//  - RPN (`rpn`, random phase noise, Galerne-Gousseau-Morel, S2 ref. [4]): on the same Theta,
//    mean + IDFT(k^ sqrt(|Theta|) W^/|W^|): the modulus of the zero-padded k^ with the uniform random phase
//    of W^ (one phase for all channels, keeping the colour phase differences of k^; |W^| = 0 taken as 1). Its
//    pixel variance equals k's (sum k^2) like the ADSN. Circular (periodic on Theta), not tile-invariant.
//  - DSN (`dsn`, on Z^2) and CDSN (`cdsn`, circular on Theta = [x, x + max(w, s)) x [y, y + max(h, s))): the
//    discrete spot noise of the texton coefficients alpha, described below; CDSN adds the copies of alpha
//    circularly on Theta (S2 §2.2), by FFT (S2 §2.4), with its own Poisson stream (k_domain_cdsn_count).
// The two original functions, in detail:
//  - synthesize_adsn: the exemplar's Gaussian texture (S1 §3.1-3.2, S2 §2.1/§2.4), the limit texton noise
//    converges to (S1 Theorem 2): CADSN of t_u, a circular convolution by FFT of the normalised kernel t_u of
//    the exemplar's periodic component with W. The FFT domain is the output size, enlarged to the exemplar
//    size where the output is smaller; t_u is embedded zero-padded at the origin when the domain is larger
//    than the exemplar (S2 §2.4). The result depends on the region: not tile-invariant.
//  - DSN: discrete spot noise of the texton coefficients alpha on Z^2 (S2 §2.1, Algorithm 1 with a grid
//    Poisson process): f(p) = mean + (sum_q P(q) alpha(p - q) - lambda sum alpha) / sqrt(lambda), P(q) an
//    independent Poisson(lambda) count at every integer point q, lambda = MNI / s^2 (the mean number of
//    impacts of an s x s spot). P(q) comes from the counter RNG keyed by (seed, q) and the integer threshold
//    table (kernels/shared/poisson.h), and every pixel sums its terms in the same order, so DSN renders are
//    deterministic and tile-invariant bit for bit.
#pragma once
#include <cstdint>

#include "analysis/gaussian_model.h"
#include "analysis/image_io.h"
#include "runtime/model.h"

namespace stex {

// Keys of the comparison modes' random streams (rng.h domains; distinct from the texton streams).
constexpr std::uint32_t k_domain_adsn_noise = 0x41445357u;  // "ADSW"
constexpr std::uint32_t k_domain_dsn_count = 0x44534e43u;   // "DSNC"

// ADSN of `exemplar` on the output pixels [x, x + width) x [y, y + height). Channels as the exemplar's.
// The FFT domain max(width, exemplar width) x max(height, exemplar height) must stay within
// `pixel_budget` (stex::Error(Limit) otherwise).
Image synthesize_adsn(const Image& exemplar, std::int64_t x, std::int64_t y, int width, int height,
                      std::uint64_t seed, std::uint64_t pixel_budget = std::uint64_t(1) << 28);

// Renders below: the output region [x, x + width) x [y, y + height); channels as the kernel's; the FFT domain
// must stay within `pixel_budget` pixels (stex::Error(Limit) otherwise).
constexpr std::uint32_t k_domain_cdsn_count = 0x4344534eu;  // "CDSN"

// The texton kernel of a model, whose ADSN has the texton noise covariance (S1 Prop. 1): order 0: alpha
// (s x s); order k > 0: alpha * (q x q) ((s + k) x (s + k)) with q = bspline_spectral_factor(k), the
// spectral square root of the sampled B-spline (order 1: q = ((1 + 1/sqrt 3)/2, (1 - 1/sqrt 3)/2),
// q * q~ = (1/6, 2/3, 1/6)). Mean = the model's.
NormalisedKernel texton_kernel(const TextonModel& model);

// ADSN on Z^2 (tile-invariant), CADSN and RPN on Theta, as described above.
Image synthesize_adsn_z2(const NormalisedKernel& kernel, std::int64_t x, std::int64_t y, int width,
                         int height, std::uint64_t seed, std::uint64_t pixel_budget = std::uint64_t(1) << 28);
Image synthesize_cadsn(const NormalisedKernel& kernel, std::int64_t x, std::int64_t y, int width, int height,
                       std::uint64_t seed, std::uint64_t pixel_budget = std::uint64_t(1) << 28);
Image synthesize_rpn(const NormalisedKernel& kernel, std::int64_t x, std::int64_t y, int width, int height,
                     std::uint64_t seed, std::uint64_t pixel_budget = std::uint64_t(1) << 28);

// CDSN of the model's alpha on Theta: f(p) = mean + (sum_{q in Theta} P(q) alpha((p - q) mod Theta) -
// lambda sum alpha) / sqrt(lambda), P(q) Poisson(lambda) keyed by (seed, absolute q), lambda = MNI / s^2 as
// for DSN. MNI in (0, 10000] (stex::Error(Usage)).
Image synthesize_cdsn(const TextonModel& model, std::int64_t x, std::int64_t y, int width, int height,
                      double mni, std::uint64_t seed, std::uint64_t pixel_budget = std::uint64_t(1) << 28);

// Smallest n' >= n whose prime factors are 2, 3, 5, 7 (fast FFT sizes).
int fft_friendly_size(int n);

// The white noise W(px, py) of the ADSN, CADSN and RPN renders: a standard normal from the counter RNG keyed
// by (seed, absolute pixel), domain k_domain_adsn_noise, Box-Muller on two 24-bit uniforms.
double white_noise_at(std::int64_t px, std::int64_t py, std::uint64_t seed);

// DSN of the model's alpha on the output pixels [x, x + width) x [y, y + height) (scale 1). MNI in
// (0, 10000] (stex::Error(Usage)).
Image synthesize_dsn(const TextonModel& model, std::int64_t x, std::int64_t y, int width, int height, double mni,
                     std::uint64_t seed);

}  // namespace stex
