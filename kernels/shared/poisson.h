/* Poisson counts from an integer threshold table, bit-identical on every device.
 *
 * The host computes the table once per mean (runtime/poisson_table.cpp): entry k is
 *   T[k] = min(floor(F(k) * 2^32), 2^32 - 1),  F the Poisson(mean) CDF, k = 0 .. K-1,
 * where K-1 is the first k with F(k) * 2^32 >= 2^32 - 1 (the tail beyond has mass < 2^-32 and is folded into
 * K-1). A count is the smallest k with u < T[k] for a uniform 32-bit word u (K-1 if none): the inverse CDF
 * quantised to 2^-32 in probability. No floating point is involved on the device, so the count of a cell
 * is the same integer for every strategy and device. Never Box-Muller counts.
 */
#ifndef STEX_POISSON_H
#define STEX_POISSON_H
#include "stex_platform.h"

#define STEX_POISSON_MAX_TABLE 4096

/* Binary search: smallest k in [0, len) with u < table[k]; len - 1 if none. len >= 1. */
STEX_FN stex_u32 stex_poisson_count(const STEX_GLOBAL stex_u32* table, stex_u32 len, stex_u32 u) {
  stex_u32 lo = 0, hi = len - 1;
  while (lo < hi) {
    stex_u32 mid = (lo + hi) >> 1;
    if (u < table[mid])
      hi = mid;
    else
      lo = mid + 1;
  }
  return lo;
}

#endif /* STEX_POISSON_H */
