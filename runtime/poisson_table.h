// Host side of kernels/shared/poisson.h: the integer threshold table of a Poisson(mean) count.
#pragma once
#include <cstdint>
#include <vector>

namespace stex {

// T[k] = min(floor(F(k) 2^32), 2^32 - 1) for k = 0 .. K-1, K-1 the first k with F(k) 2^32 >= 2^32 - 1.
// F is computed in long double by the recurrence p(k) = p(k-1) mean / k, from the mode outwards for large
// means so that nothing underflows. Throws stex::Error(Usage) for mean <= 0, non-finite, or a table longer
// than STEX_POISSON_MAX_TABLE (mean above about 3500).
std::vector<std::uint32_t> poisson_threshold_table(double mean);

}  // namespace stex
