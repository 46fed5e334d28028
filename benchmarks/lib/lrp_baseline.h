// LRP noise (S3 eq. 1, 2, 4) in plain C++ with OpenMP, compiled with -O3 -ffast-math: the baseline of the
// issue #7 speed check ("LRP with J = 50 on PoCL within 1.5x of the same algorithm in plain C++ with
// -ffast-math"). Same algorithm and tables as kernels/shared/lrp.h (the same RNG draws, lattice, window and
// structure), written as a C++ programmer would: std::cos / std::sin of 2 pi t, std::sqrt and the I0 series
// for the window. Not bit-identical to the reference (fast-math, libm); tests bound the difference.
#pragma once
#include <cstdint>
#include <vector>

#include "runtime/lrp_model.h"

namespace stex::bench {

// Interleaved output like LrpNoise::render. threads = 0: OpenMP's default.
void lrp_fastmath_render(const LrpSetup& setup, std::int64_t x, std::int64_t y, int width, int height, float* out,
                         int threads = 0);

// The same with the kernel's cos/sin (stex_lrp_cossin of kernels/shared/lrp.h, the phase in turns) in place
// of std::cos / std::sin: the baseline with exactly the kernel's cosine operations, for the comparison
// with the library-cos baseline (docs/lrp.md).
void lrp_fastmath_polycos_render(const LrpSetup& setup, std::int64_t x, std::int64_t y, int width, int height,
                                 float* out, int threads = 0);

}  // namespace stex::bench
