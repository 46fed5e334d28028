// The chunked launch of the gather renderers (chunked_gather.h).
#include "runtime/chunked_gather.h"

#include <algorithm>
#include <string>
#include <vector>

#include "core/error.h"
#include "runtime/buffer.h"
#include "runtime/loop_watchdog.h"

namespace stex {

NoiseRenderStats render_gather_chunks(Context& ctx, Kernel& kernel, int channels, std::int64_t x, std::int64_t y,
                                      int width, int height, float* out, const GatherChunking& chunking,
                                      const GatherLeadingArgs& leading_args) {
  const std::size_t ch = std::size_t(channels);
  std::size_t max_pixels = std::size_t(std::min<std::uint64_t>(chunking.max_chunk_pixels,
                                                               ctx.info().max_alloc / (sizeof(float) * ch)));
  if (max_pixels == 0) throw Error(ErrorKind::Limit, "device '" + ctx.info().name + "' cannot allocate one pixel");
  const int side_w = chunking.max_side > 0 ? std::min(width, chunking.max_side) : width;
  const int side_h = chunking.max_side > 0 ? std::min(height, chunking.max_side) : height;
  const int chunk_w = int(std::min<std::size_t>(std::size_t(side_w), max_pixels));
  const int chunk_h = int(std::min<std::size_t>(std::size_t(side_h), std::max<std::size_t>(1, max_pixels / chunk_w)));
  const std::size_t chunk_floats = std::size_t(chunk_w) * std::size_t(chunk_h) * ch;
  Buffer<float> own;
  Buffer<float>* target = chunking.out_buffer ? chunking.out_buffer : &own;
  target->reserve(ctx, chunk_floats, CL_MEM_READ_WRITE, "render chunk");
  Buffer<float>& device_out = *target;
  std::vector<float> host(chunk_w < width ? chunk_floats : 0);
  const std::array<std::size_t, 2> local = kernel.fit_local(ctx, chunking.local);  // the device's limits
  LoopWatchdog watchdog(ctx);

  NoiseRenderStats stats;
  stats.strategy = "gather";
  for (int cy = 0; cy < height; cy += chunk_h) {
    const int h = std::min(chunk_h, height - cy);
    for (int cx = 0; cx < width; cx += chunk_w) {
      const int w = std::min(chunk_w, width - cx);
      if (chunking.before_chunk) stats.device_ms += chunking.before_chunk(x + cx, y + cy, w, h);
      cl_uint a = leading_args(kernel, 0, x + cx, y + cy);
      kernel.set_arg(a++, cl_long(x + cx));
      kernel.set_arg(a++, cl_long(y + cy));
      kernel.set_arg(a++, cl_int(w));
      kernel.set_arg(a++, cl_int(h));
      kernel.set_arg(a++, cl_int(w));
      kernel.set_arg(a++, device_out);
      const std::size_t items_x = (std::size_t(w) + std::size_t(chunking.pixels_per_item_x) - 1) /
                                  std::size_t(std::max(1, chunking.pixels_per_item_x));
      // The loop watchdog (loop_watchdog.h): a chunk whose loops the driver cut short is re-run, then refused.
      stats.device_ms += launch_watched(ctx, kernel, watchdog, a, items_x, std::size_t(h), local, &stats.launches);
      const std::size_t row = std::size_t(w) * ch;
      if (w == width) {  // whole rows: straight into the caller's image
        device_out.read(out + std::size_t(cy) * row, row * std::size_t(h));
        continue;
      }
      device_out.read(host.data(), row * std::size_t(h));
      for (int j = 0; j < h; ++j)
        std::copy(host.begin() + std::ptrdiff_t(j * row), host.begin() + std::ptrdiff_t((j + 1) * row),
                  out + ((std::size_t(cy) + std::size_t(j)) * std::size_t(width) + std::size_t(cx)) * ch);
    }
  }
  return stats;
}

}  // namespace stex
