/* Entry points that expose the shared RNG and Poisson sampler (shared/rng.h, shared/poisson.h) so tests can
 * compare the device with the C++ reference bit for bit, and `stex demo-rng` can draw the RNG as an image.
 * Cell coordinates are 64-bit (cells as (cx, cy) pairs of longs), so huge and near-INT64-limit cells are
 * exercised exactly as the renderers use them.
 */
#include "shared/poisson.h"
#include "shared/rng.h"

/* keys[4 i .. 4 i + 3] = stex_cell_key(cells[2 i], cells[2 i + 1]). Global size: number of cells. */
__kernel void rng_cell_keys(__global const long* cells, __global uint* keys) {
  const size_t i = get_global_id(0);
  stex_uvec4 k = stex_cell_key(cells[2 * i], cells[2 * i + 1]);
  keys[4 * i + 0] = k.x;
  keys[4 * i + 1] = k.y;
  keys[4 * i + 2] = k.z;
  keys[4 * i + 3] = k.w;
}

/* Draws index0 .. index0 + n_index - 1 of `domain` for every cell. Item g = cell * n_index + j writes the
 * four words of stex_draw to words[4 g ..] and their stex_uniform24 floats to uniforms[4 g ..].
 * Global size: number of cells * n_index. */
__kernel void rng_draws(__global const long* cells, uint n_index, uint index0, uint seed_lo, uint seed_hi,
                        uint domain, __global uint* words, __global float* uniforms) {
  const size_t g = get_global_id(0);
  const size_t cell = g / n_index;
  const uint j = (uint)(g % n_index);
  stex_uvec4 key = stex_cell_key(cells[2 * cell], cells[2 * cell + 1]);
  stex_uvec4 v = stex_draw(key, seed_lo, seed_hi, index0 + j, domain);
  words[4 * g + 0] = v.x;
  words[4 * g + 1] = v.y;
  words[4 * g + 2] = v.z;
  words[4 * g + 3] = v.w;
  uniforms[4 * g + 0] = stex_uniform24(v.x);
  uniforms[4 * g + 1] = stex_uniform24(v.y);
  uniforms[4 * g + 2] = stex_uniform24(v.z);
  uniforms[4 * g + 3] = stex_uniform24(v.w);
}

/* counts[i] = stex_poisson_count(table, len, u[i]). Global size: number of words. */
__kernel void poisson_lookup(__global const uint* table, uint len, __global const uint* u, __global uint* counts) {
  const size_t i = get_global_id(0);
  counts[i] = stex_poisson_count(table, len, u[i]);
}

/* Poisson count of cell (x0 + gx, y0 + gy), drawn the way renderers draw it (draw 0 of STEX_DOMAIN_COUNT,
 * first word). counts[gy * width + gx]. Global size: (width, height). */
__kernel void poisson_cells(__global const uint* table, uint len, long x0, long y0, uint seed_lo, uint seed_hi,
                            __global uint* counts) {
  const size_t gx = get_global_id(0), gy = get_global_id(1);
  stex_uvec4 key = stex_cell_key(x0 + (long)gx, y0 + (long)gy);
  stex_uvec4 v = stex_draw(key, seed_lo, seed_hi, 0u, STEX_DOMAIN_COUNT);
  counts[gy * get_global_size(0) + gx] = stex_poisson_count(table, len, v.x);
}

/* An RGB8 picture of the RNG: pixel (x, y) of the image whose top-left pixel is (x0, y0) lies in cell
 * (floor((x0 + x) / cell_px), floor((y0 + y) / cell_px)) and shows the top bytes of the first three words of
 * that cell's draw 0 in STEX_DOMAIN_TEST. rgb[3 (y width + x) ..]. Global size: (width, height). */
__kernel void rng_image(long x0, long y0, uint cell_px, uint seed_lo, uint seed_hi, __global uchar* rgb) {
  const size_t x = get_global_id(0), y = get_global_id(1);
  const long cx = stex_floordiv(x0 + (long)x, (long)cell_px);
  const long cy = stex_floordiv(y0 + (long)y, (long)cell_px);
  stex_uvec4 v = stex_draw(stex_cell_key(cx, cy), seed_lo, seed_hi, 0u, STEX_DOMAIN_TEST);
  const size_t o = 3 * (y * get_global_size(0) + x);
  rgb[o + 0] = (uchar)(v.x >> 24);
  rgb[o + 1] = (uchar)(v.y >> 24);
  rgb[o + 2] = (uchar)(v.z >> 24);
}
