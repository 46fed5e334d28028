// Plain C++ / OpenMP tile splat of texton noise (S1 §8, per tile). See omp_splat.h.
#include "benchmarks/lib/omp_splat.h"

#include <omp.h>

#include <algorithm>
#include <cstring>

#include "core/error.h"
#include "kernels/shared/texton.h"

namespace stex::bench {
namespace {

constexpr stex_i64 k_unit = stex_i64(1) << STEX_FIX_BITS;
constexpr stex_i64 k_half_unit = k_unit >> 1;
// Row updates run over whole blocks of k_lanes pixels (one AVX-512 register): no scalar tails. The texton rows
// and the tile rows carry k_lanes zero/scratch columns on the right to absorb the overrun (see SplatLayout).
constexpr int k_lanes = 16;

// ceil(a / b) for b > 0.
stex_i64 ceil_div(stex_i64 a, stex_i64 b) { return -stex_floordiv(-a, b); }

// The unit-scale fast path's memory layout. Texton planes: the renderer's padded planes (one zero frame
// texel, stride s + 2) re-laid with `stride` = s + 2 + k_lanes columns, the extra ones zero. Tile
// accumulators: `pitch` = tile + k_lanes columns per row, the extra ones scratch. A row update rounded up to a
// multiple of k_lanes pixels then reads only zero texels past the texton's right frame (weights are >= 0, so
// each extra term is w * 0 = +0 and the pixel's sum is unchanged, bit for bit) and writes past the impulse's
// span either pixels of the tile that receive exactly +0 or scratch columns.
struct SplatLayout {
  int stride = 0, pitch = 0;
  std::size_t aplane = 0;
  std::vector<float> alpha;
};

SplatLayout make_layout(const TextonSetup& setup, int tile) {
  SplatLayout l;
  const int s2 = setup.params.stride;  // s + 2
  l.stride = s2 + k_lanes;
  l.pitch = tile + k_lanes;
  l.aplane = std::size_t(s2) * std::size_t(l.stride);
  l.alpha.assign(l.aplane * std::size_t(setup.channels), 0.0f);
  for (int c = 0; c < setup.channels; ++c)
    for (int y = 0; y < s2; ++y)
      for (int x = 0; x < s2; ++x)
        l.alpha[std::size_t(c) * l.aplane + std::size_t(y) * std::size_t(l.stride) + std::size_t(x)] =
            setup.alpha_padded[(std::size_t(c) * std::size_t(s2) + std::size_t(y)) * std::size_t(s2) + std::size_t(x)];
  return l;
}

// One impulse, one channel: `rows` rows of `blocks` x k_lanes pixels (row pitch `pitch`) each receive
// stex_texton_fetch(a, row * stride + i, stride, w) - the same expression, evaluated in the same order, as
// the reference, so every pixel gets the same float. The fixed-length inner loop vectorises without a tail.
// Cloned for AVX-512 and AVX2 (picked at run time): a user compiling for their own machine would get the same
// code from -march=native.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
__attribute__((target_clones("avx512f", "avx2", "default")))
#endif
void splat_block(float* __restrict o, int pitch, const float* __restrict a, int stride, int rows, int blocks,
                 float w00, float w10, float w01, float w11) {
  for (int r = 0; r < rows; ++r) {
    float* __restrict orow = o + std::size_t(r) * std::size_t(pitch);
    const float* __restrict a0 = a + std::size_t(r) * std::size_t(stride);
    const float* __restrict a1 = a0 + stride;
    for (int b = 0; b < blocks * k_lanes; b += k_lanes)
      for (int i = b; i < b + k_lanes; ++i)
        orow[i] += w00 * a0[i] + w10 * a0[i + 1] + w01 * a1[i] + w11 * a1[i + 1];
  }
}

// Accumulates the impulses reaching the tile of output pixels [tx0, tx0 + tw) x [ty0, ty0 + th) into `acc`
// (channels planes of th rows of layout.pitch floats, zeroed here).
void splat_tile(const TextonSetup& setup, const SplatLayout& layout, stex_i64 tx0, stex_i64 ty0, int tw, int th,
                float* acc) {
  // A local copy: the shared functions take the struct by value, and stores through `acc` could alias a
  // reference to it, which would make the compiler copy the struct at every call.
  const stex_texton_params p = setup.params;
  const int nc = setup.channels;
  const int stride = p.stride;
  const std::size_t aplane = std::size_t(stride) * std::size_t(stride);
  const int pitch = layout.pitch;
  const std::size_t tplane = std::size_t(th) * std::size_t(pitch);
  const float* alpha = setup.alpha_padded.data();
  const stex_u32* table = setup.poisson_table.data();
  std::memset(acc, 0, sizeof(float) * tplane * std::size_t(nc));

  const stex_i64 t_lo_fix = stex_i64(p.t_lo * float(k_unit)), t_hi_fix = stex_i64(p.t_hi * float(k_unit));
  // Unit scale, and every displacement inside the support below 2^24 fixed units: float(D) * 2^-16 is exact,
  // so the taps of one impulse differ only by a whole-texel shift (see the header).
  const bool unit_scale = p.inv_fix_scale == 1.0f / float(k_unit) && t_hi_fix <= (stex_i64(1) << 24) &&
                          -t_lo_fix <= (stex_i64(1) << 24);
  const stex_i64 rb = stex_join64(p.reach_back_lo, p.reach_back_hi);
  const stex_i64 rf = stex_join64(p.reach_fwd_lo, p.reach_fwd_hi);

  stex_i64 kx0, kx1, ky0, ky1;
  stex_texton_cell_range(p, stex_pixel_fix(tx0), stex_pixel_fix(tx0 + tw - 1), &kx0, &kx1);
  stex_texton_cell_range(p, stex_pixel_fix(ty0), stex_pixel_fix(ty0 + th - 1), &ky0, &ky1);

  for (stex_i64 ky = ky0; ky <= ky1; ++ky) {
    for (stex_i64 kx = kx0; kx <= kx1; ++kx) {
      const stex_uvec4 key = stex_cell_key(kx, ky);
      const stex_u32 n = stex_texton_count(p, key, table);
      for (stex_u32 j = 0; j < n; ++j) {
        stex_i64 xj, yj;
        stex_u32 mark;
        stex_texton_impulse(p, key, kx, ky, j, &xj, &yj, &mark);
        if (unit_scale) {
          // Pixels P whose centre X(P) = P 2^F + 2^(F-1) has X(P) - x_j in [t_lo 2^F, t_hi 2^F).
          const int c0 = int(std::max<stex_i64>(ceil_div(xj + t_lo_fix - k_half_unit, k_unit) - tx0, 0));
          const int c1 = int(std::min<stex_i64>(ceil_div(xj + t_hi_fix - k_half_unit, k_unit) - tx0 - 1, tw - 1));
          const int r0 = int(std::max<stex_i64>(ceil_div(yj + t_lo_fix - k_half_unit, k_unit) - ty0, 0));
          const int r1 = int(std::min<stex_i64>(ceil_div(yj + t_hi_fix - k_half_unit, k_unit) - ty0 - 1, th - 1));
          if (c0 > c1 || r0 > r1) continue;
          float w00, w10, w01, w11;
          const int idx0 = stex_texton_tap(p, stex_pixel_fix(tx0 + c0) - xj, stex_pixel_fix(ty0 + r0) - yj, &w00,
                                           &w10, &w01, &w11);
          // The same texel in the wider layout.
          const std::size_t lidx = std::size_t(idx0 / stride) * std::size_t(layout.stride) + std::size_t(idx0 % stride);
          const int blocks = (c1 - c0 + k_lanes) / k_lanes;
          for (int c = 0; c < nc; ++c)
            splat_block(acc + std::size_t(c) * tplane + std::size_t(r0) * std::size_t(pitch) + std::size_t(c0), pitch,
                        layout.alpha.data() + std::size_t(c) * layout.aplane + lidx, layout.stride, r1 - r0 + 1, blocks,
                        w00, w10, w01, w11);
          continue;
        }
        // General scale: one tap per pixel of the reach rectangle (pixels whose centre is within
        // [x_j - reach_fwd, x_j + reach_back]); taps outside the support add an exact +0.
        const int c0 = int(std::max<stex_i64>(ceil_div(xj - rf - k_half_unit, k_unit) - tx0, 0));
        const int c1 = int(std::min<stex_i64>(stex_floordiv(xj + rb - k_half_unit, k_unit) - tx0, tw - 1));
        const int r0 = int(std::max<stex_i64>(ceil_div(yj - rf - k_half_unit, k_unit) - ty0, 0));
        const int r1 = int(std::min<stex_i64>(stex_floordiv(yj + rb - k_half_unit, k_unit) - ty0, th - 1));
        for (int r = r0; r <= r1; ++r) {
          const stex_i64 dy = stex_pixel_fix(ty0 + r) - yj;
          for (int i = c0; i <= c1; ++i) {
            float w00, w10, w01, w11;
            const int idx = stex_texton_tap(p, stex_pixel_fix(tx0 + i) - xj, dy, &w00, &w10, &w01, &w11);
            for (int c = 0; c < nc; ++c)
              acc[std::size_t(c) * tplane + std::size_t(r) * std::size_t(pitch) + std::size_t(i)] +=
                  stex_texton_fetch(alpha + std::size_t(c) * aplane, idx, stride, w00, w10, w01, w11);
          }
        }
      }
    }
  }
}

}  // namespace

int omp_splat_threads(const OmpSplatOptions& options) {
  return options.threads > 0 ? options.threads : omp_get_max_threads();
}

void omp_splat_render(const TextonSetup& setup, std::int64_t x, std::int64_t y, int width, int height, float* planar,
                      const OmpSplatOptions& options) {
  validate_region(x, y, width, height);
  if (options.tile < 1) throw Error(ErrorKind::Usage, "OpenMP splat tile must be at least 1 pixel");
  const int tile = options.tile;
  const int ntx = (width + tile - 1) / tile, nty = (height + tile - 1) / tile;
  const int nc = setup.channels;
  const std::size_t plane = std::size_t(width) * std::size_t(height);
  const SplatLayout layout = make_layout(setup, tile);
#pragma omp parallel num_threads(omp_splat_threads(options))
  {
    std::vector<float> acc(std::size_t(tile) * std::size_t(layout.pitch) * std::size_t(nc));
    const stex_texton_params p = setup.params;  // local: see splat_tile
#pragma omp for schedule(dynamic, 1)
    for (int t = 0; t < ntx * nty; ++t) {
      const int bx = (t % ntx) * tile, by = (t / ntx) * tile;
      const int tw = std::min(tile, width - bx), th = std::min(tile, height - by);
      splat_tile(setup, layout, x + bx, y + by, tw, th, acc.data());
      const std::size_t tplane = std::size_t(th) * std::size_t(layout.pitch);
      for (int c = 0; c < nc; ++c)
        for (int r = 0; r < th; ++r) {
          const float* src = acc.data() + std::size_t(c) * tplane + std::size_t(r) * std::size_t(layout.pitch);
          float* dst = planar + std::size_t(c) * plane + (std::size_t(by) + std::size_t(r)) * std::size_t(width) + bx;
          for (int i = 0; i < tw; ++i) dst[i] = stex_texton_finish(p, c, src[i]);
        }
    }
  }
}

std::vector<float> omp_splat_render_interleaved(const TextonSetup& setup, std::int64_t x, std::int64_t y, int width,
                                                int height, const OmpSplatOptions& options) {
  validate_region(x, y, width, height);
  const int nc = setup.channels;
  const std::size_t plane = std::size_t(width) * std::size_t(height);
  std::vector<float> planar(plane * std::size_t(nc));
  omp_splat_render(setup, x, y, width, height, planar.data(), options);
  std::vector<float> out(planar.size());
  for (std::size_t i = 0; i < plane; ++i)
    for (int c = 0; c < nc; ++c) out[i * std::size_t(nc) + std::size_t(c)] = planar[std::size_t(c) * plane + i];
  return out;
}

}  // namespace stex::bench
