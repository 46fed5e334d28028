// The chunked launch shared by the per-pixel ("gather") renderers of the model kinds (gabor, mix, cs-spot,
// tb, ...): the region is cut into chunks that fit the device's largest allocation (and an optional cap),
// each chunk is one launch of an entry point whose trailing arguments are
//     (long x0, long y0, int width, int height, int pitch, __global float* out,   // interleaved channels
//      STEX_WATCHDOG_ARGS)                                                          // loop_watchdog.h
// and the chunk is read back into the caller's interleaved image. The chunking never changes a pixel: every
// kernel evaluates pixels from their absolute coordinates (the invariant of runtime/noise_renderer.h).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>

#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/noise_renderer.h"
#include "runtime/program.h"

namespace stex {

// The default cap on one launch of every renderer: 64 MiB of float output (2^24 pixels of one channel,
// 2^22 of four), far below any device's largest allocation and large enough that a launch's fixed cost
// is negligible. Chunking never changes a pixel.
constexpr std::size_t k_default_chunk_bytes = std::size_t(64) << 20;
inline std::size_t default_chunk_pixels(int channels) {
  return k_default_chunk_bytes / (sizeof(float) * std::size_t(channels < 1 ? 1 : channels));
}

struct GatherChunking {
  std::size_t max_chunk_pixels = std::size_t(1) << 24;  // cap on the pixels of one launch (and its buffer)
  int max_side = 0;                                      // cap on a chunk's width and height (0: none)
  std::array<std::size_t, 2> local{16, 4};               // work-group size
  int pixels_per_item_x = 1;  // a work-item evaluates this many consecutive pixels of a row (global x: w / this)
  // Optional: called before each chunk's launch with the chunk's first pixel and size (a renderer's own
  // per-chunk pre-pass, e.g. tb's vertex pass); returns the device ms it spent (added to the stats).
  std::function<double(std::int64_t x0, std::int64_t y0, int width, int height)> before_chunk;
  // Optional: the renderer's own output buffer, kept across renders (Buffer::reserve: grown when a render's
  // chunk needs more), so that a frame allocates no device memory; else one buffer per render.
  Buffer<float>* out_buffer = nullptr;
};

// Sets the kernel's leading arguments (the model's) for the chunk whose first pixel is (x0, y0), starting
// at argument `first`; returns the index of the next argument.
using GatherLeadingArgs = std::function<cl_uint(Kernel& kernel, cl_uint first, std::int64_t x0, std::int64_t y0)>;

// Renders [x, x + width) x [y, y + height) with `channels` interleaved channels into `out` (width * height *
// channels floats). Error(Limit) if the device cannot hold one pixel; launch failures are Error(Device), and so
// is a chunk whose loops the driver still cuts short with one work-item per work-group (loop_watchdog.h).
NoiseRenderStats render_gather_chunks(Context& ctx, Kernel& kernel, int channels, std::int64_t x, std::int64_t y,
                                      int width, int height, float* out, const GatherChunking& chunking,
                                      const GatherLeadingArgs& leading_args);

}  // namespace stex
