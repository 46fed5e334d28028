// The texton tile splat in plain C++ with OpenMP on the host's threads (issue #5 baseline: "what a user
// would write without OpenCL"). S1 eq. 1-3 evaluated as in S1 §8, but per tile instead of per pixel: each
// thread owns a tile of pixels, walks the cells that may reach it in the global order (ky, kx, impulse j
// ascending; kernels/shared/texton.h) and adds every impulse's bilinear taps to the tile's pixels it covers.
//
// It calls the shared header functions (stex_cell_key, stex_texton_count, stex_texton_impulse,
// stex_texton_tap, stex_texton_fetch's expression, stex_texton_finish) in the same order as the C++
// reference, so its output equals runtime/reference.h bit for bit (tests/kernels/test_bench_baselines.cpp).
// At unit scale the taps of the pixels an impulse covers share one set of weights (float(D) 2^-16 is exact
// for |D| < 2^24), so the inner loop is a plain axpy-like row update that the compiler vectorises; other
// scales take one tap per pixel.
#pragma once
#include <cstdint>
#include <vector>

#include "runtime/texton_params.h"

namespace stex::bench {

struct OmpSplatOptions {
  int tile = 128;   // tile side in pixels (outputs never depend on it)
  int threads = 0;  // OpenMP threads; 0: OpenMP's default (all the host's threads)
};

// Renders output pixels [x, x + width) x [y, y + height) into `planar` (channels planes of width * height
// floats: channel c of pixel (i, j) at c * width * height + j * width + i, like the OpenCL kernels' output).
// Validates the region (stex::Error(Usage)).
void omp_splat_render(const TextonSetup& setup, std::int64_t x, std::int64_t y, int width, int height,
                      float* planar, const OmpSplatOptions& options = {});

// The same, interleaved like TextonRenderer::render (pixel (i, j) channel c at (j * width + i) * channels + c).
std::vector<float> omp_splat_render_interleaved(const TextonSetup& setup, std::int64_t x, std::int64_t y, int width,
                                                int height, const OmpSplatOptions& options = {});

// Number of threads omp_splat_render uses with these options.
int omp_splat_threads(const OmpSplatOptions& options = {});

}  // namespace stex::bench
