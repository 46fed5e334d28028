// Comparison renders for texton noise (`stex render --mode adsn|dsn`), both on the host:
//  - ADSN: the exemplar's Gaussian texture (S1 §3.1-3.2, S2 §2.1/§2.4), the limit texton noise converges to
//    (S1 Theorem 2): mean + t_u (*) W, a circular convolution by FFT of the normalised kernel t_u of the
//    exemplar's periodic component with a standard Gaussian white noise W. The FFT domain is the output
//    size, enlarged to the exemplar size where the output is smaller; t_u is embedded zero-padded at the
//    origin when the domain is larger than the exemplar (S2 §2.4). W is keyed by absolute output pixel
//    coordinates and the seed, but the result depends on the region (the convolution is circular): ADSN
//    renders are not tile-invariant.
//  - DSN: discrete spot noise of the texton coefficients alpha on Z^2 (S2 §2.1, Algorithm 1 with a grid
//    Poisson process): f(p) = mean + (sum_q P(q) alpha(p - q) - lambda sum alpha) / sqrt(lambda), P(q) an
//    independent Poisson(lambda) count at every integer point q, lambda = MNI / s^2 (the mean number of
//    impacts of an s x s spot). P(q) comes from the counter RNG keyed by (seed, q) and the integer threshold
//    table (kernels/shared/poisson.h), and every pixel sums its terms in the same order, so DSN renders are
//    deterministic and tile-invariant bit for bit.
#pragma once
#include <cstdint>

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

// DSN of the model's alpha on the output pixels [x, x + width) x [y, y + height) (scale 1). MNI in
// (0, 10000] (stex::Error(Usage)).
Image synthesize_dsn(const TextonModel& model, std::int64_t x, std::int64_t y, int width, int height, double mni,
                     std::uint64_t seed);

}  // namespace stex
