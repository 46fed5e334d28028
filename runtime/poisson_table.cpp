// Host side of kernels/shared/poisson.h. See poisson_table.h.
#include "runtime/poisson_table.h"

#include <cmath>
#include <sstream>

#include "core/error.h"
#include "kernels/shared/poisson.h"

namespace stex {

std::vector<std::uint32_t> poisson_threshold_table(double mean) {
  if (!std::isfinite(mean) || mean <= 0.0) {
    std::ostringstream os;
    os << "Poisson mean must be positive and finite, got " << mean;
    throw Error(ErrorKind::Usage, os.str());
  }
  const long double two32 = 4294967296.0L;
  const long double m = mean;
  const long double log_m = std::log(m);
  std::vector<std::uint32_t> table;
  long double cdf = 0.0L;
  for (std::uint32_t k = 0;; ++k) {
    if (k >= STEX_POISSON_MAX_TABLE) {
      std::ostringstream os;
      os << "Poisson mean " << mean << " needs a threshold table longer than " << STEX_POISSON_MAX_TABLE
         << " entries (lower the MNI or the cell size)";
      throw Error(ErrorKind::Usage, os.str());
    }
    // p(k) in log space: exact enough in long double and free of underflow for the means allowed here.
    long double log_p = -m + static_cast<long double>(k) * log_m - std::lgamma(static_cast<long double>(k) + 1.0L);
    cdf += std::exp(log_p);
    long double scaled = cdf * two32;
    if (scaled >= two32 - 1.0L) {
      table.push_back(0xffffffffu);
      break;
    }
    table.push_back(static_cast<std::uint32_t>(std::floor(scaled)));
  }
  return table;
}

}  // namespace stex
