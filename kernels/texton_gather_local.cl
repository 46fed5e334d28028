/* Texton noise, local-memory gather strategy (S1 §8 "per pixel, sum over the impulses of the cells within
 * reach", with a work-group sharing its tile's impulses): the default on GPUs.
 *
 * A work-group owns a tile of get_local_size(0) x get_local_size(1) output pixels. Its work-items first
 * generate, cooperatively, the impulses of every cell that may reach the tile (the cells of
 * stex_texton_cell_range over the tile's pixel centres) into local memory:
 *   phase 1: the count of each cell (one work-item per cell), barrier;
 *   phase 2: the two 32-bit position words of each (cell, impulse) slot with impulse < count, barrier.
 * Then each work-item sums, for its own pixel, the impulses of its own cells (a subset of the tile's: the
 * cell range is monotonic in the interval) exactly as stex_texton_eval does: cells by (ky, kx) ascending,
 * impulses by j ascending, positions rebuilt by stex_texton_coord (integers) and taps added by
 * stex_texton_add_impulse (kernels/shared/texton.h). The output therefore equals the gather kernel, the
 * splat and the C++ reference bit for bit. Only the hashing moves to local memory; the float work is
 * unchanged.
 *
 * Barriers: exactly two, each after a loading loop and outside every loop and every divergent branch (PoCL
 * issue #1167: barriers inside loops). Work-items beyond the image take part in the loading and return
 * after the last barrier.
 *
 * Local memory (kernel arguments, sized by the host, runtime/texton_renderer.cpp): `counts` holds
 * `cells_cap` uints, `words` cells_cap * slots uint2 (8 bytes per impulse), with
 *   cells_cap = stex_texton_tile_cells_max(local x) * stex_texton_tile_cells_max(local y),
 *   slots = stex_texton_cell_slots (the Poisson table's largest count).
 * The host falls back to the plain gather when that exceeds the device's local memory. Should a tile still
 * have more cells than cells_cap (it cannot, by the bound), the work-group skips the loading and every
 * work-item calls stex_texton_eval: the same bits, more hashing.
 *
 * Output: planar float, channel c of pixel (i, j) at out[c * pitch * height + j * pitch + i], i < width.
 * Global size: a multiple of the local size covering (width, height).
 */
#include "shared/texton.h"

__kernel void texton_gather_local(const stex_texton_params p_arg, __global const float* alpha,
                                  __global const uint* poisson_table, const long x0, const long y0,
                                  const int width, const int height, const int pitch, __local uint* counts,
                                  __local uint2* words, const int cells_cap, const int slots,
                                  __global float* out, STEX_WATCHDOG_ARGS) {
  const stex_texton_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  const int lid = (int)(get_local_id(1) * get_local_size(0) + get_local_id(0));
  const int group_size = (int)(get_local_size(0) * get_local_size(1));

  /* The tile's pixels, clipped to the image (the global size is rounded up to the local size). */
  const int tx0 = (int)(get_group_id(0) * get_local_size(0));
  const int ty0 = (int)(get_group_id(1) * get_local_size(1));
  const int tx1 = min(tx0 + (int)get_local_size(0), width) - 1;
  const int ty1 = min(ty0 + (int)get_local_size(1), height) - 1;
  long kx0, kx1, ky0, ky1;
  stex_texton_cell_range(p, stex_pixel_fix(x0 + tx0), stex_pixel_fix(x0 + tx1), &kx0, &kx1);
  stex_texton_cell_range(p, stex_pixel_fix(y0 + ty0), stex_pixel_fix(y0 + ty1), &ky0, &ky1);
  const long ncx_l = kx1 - kx0 + 1, ncy_l = ky1 - ky0 + 1;
  /* Uniform over the work-group: every work-item computes it from the same integers. */
  const int fits = ncx_l * ncy_l <= (long)cells_cap;
  const int ncx = (int)ncx_l;
  const int ncells = fits ? (int)(ncx_l * ncy_l) : 0;

  for (int c = lid; c < ncells; c += group_size) {
    const long kx = kx0 + c % ncx, ky = ky0 + c / ncx;
    counts[c] = stex_texton_count(p, stex_cell_key(kx, ky), poisson_table);
  }
  barrier(CLK_LOCAL_MEM_FENCE);

  for (int s = lid; s < ncells * slots; s += group_size) {
    const int c = s / slots;
    const uint k = (uint)(s - c * slots);
    if (k < counts[c]) {
      const long kx = kx0 + c % ncx, ky = ky0 + c / ncx;
      const stex_uvec4 v = stex_texton_impulse_draw(p, stex_cell_key(kx, ky), k);
      words[s] = (uint2)(v.x, v.y);
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);

  if (i >= width || j >= height) return;
  const long x = stex_pixel_fix(x0 + i), y = stex_pixel_fix(y0 + j);
  float v[STEX_MAX_CHANNELS] = {0.0f, 0.0f, 0.0f, 0.0f};
  if (fits) {
    const long a = stex_cell_size(p);
    long px0, px1, py0, py1;
    stex_texton_cell_range(p, x, x, &px0, &px1);
    stex_texton_cell_range(p, y, y, &py0, &py1);
    for (long ky = py0; ky <= py1; ++ky) {
      for (long kx = px0; kx <= px1; ++kx) {
        const int c = (int)(ky - ky0) * ncx + (int)(kx - kx0);
        const uint n = counts[c];
        for (uint k = 0; k < n; ++k) {
          const uint2 w = words[c * slots + (int)k];
          stex_texton_add_impulse(p, alpha, x, y, stex_texton_coord(kx, a, w.x), stex_texton_coord(ky, a, w.y), v);
        }
      }
    }
    for (int c = 0; c < p.channels; ++c) v[c] = stex_texton_finish(p, c, v[c]);
  } else {
    stex_texton_eval(p, alpha, poisson_table, x, y, v);
  }
  const size_t plane = (size_t)pitch * (size_t)height;
  const size_t at = (size_t)j * (size_t)pitch + (size_t)i;
  for (int c = 0; c < p.channels; ++c) out[(size_t)c * plane + at] = v[c];
  STEX_WATCHDOG_CHECK();
}
