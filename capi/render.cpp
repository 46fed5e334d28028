// C API rendering (include/stex/stex.h "Rendering"): regions into caller memory with a row stride (through
// runtime/texton_renderer.h), regions into a caller's cl_mem (the C API's region kernel, or the renderer
// plus a rectangular buffer write), and point queries at fixed-point positions round(x * 2^16) (the C API's
// points kernel). Work is done in chunks of rows so that the progress callback can report and cancel.
#include <CL/cl.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "capi/api_internal.h"
#include "model/render_request.h"
#include "runtime/cl_error.h"
#include "runtime/loop_watchdog.h"

namespace stex::capi {
namespace {

static_assert(sizeof(std::size_t) != 8 || sizeof(stex_render_params) == k_render_params_v0_size,
              "stex_render_params changed size: append fields and keep k_render_params_v0_size");

constexpr std::size_t k_chunk_pixels = std::size_t(1) << 20;  // per chunk of rows (one launch or a few)
constexpr int k_chunk_row_multiple = 16;                      // the splat kernel's default band height
constexpr std::size_t k_point_batch = std::size_t(1) << 20;   // points per launch

stex_render_params default_render_params() {
  const RenderParams r;
  stex_render_params p{};
  p.struct_size = sizeof p;
  p.mni = r.mni;
  p.cell_factor = r.cell_factor;
  p.scale = r.scale;
  p.seed = r.seed;
  p.strategy = STEX_STRATEGY_AUTO;
  p.filter = STEX_FILTER_AUTO;
  return p;
}

// The caller's render parameters: API misuse is STEX_INVALID_ARGUMENT, values out of range STEX_USAGE.
RenderParams read_render_params(const stex_render_params* user, TextonStrategy* strategy,
                                FilterMode* filter = nullptr) {
  const stex_render_params p =
      read_sized(user, default_render_params(), k_render_params_v0_size, "stex_render_params");
  switch (p.filter) {
    case STEX_FILTER_AUTO:
    case STEX_FILTER_ON:
    case STEX_FILTER_OFF:
      if (filter)
        *filter = p.filter == STEX_FILTER_ON ? FilterMode::On : p.filter == STEX_FILTER_OFF ? FilterMode::Off
                                                                                           : FilterMode::Auto;
      break;
    default:
      invalid_argument("stex_render_params.filter " + std::to_string(p.filter) + " is not a stex_filter");
  }
  switch (p.strategy) {
    case STEX_STRATEGY_AUTO:
      *strategy = TextonStrategy::Auto;
      break;
    case STEX_STRATEGY_SPLAT:
      *strategy = TextonStrategy::Splat;
      break;
    case STEX_STRATEGY_GATHER:
      *strategy = TextonStrategy::Gather;
      break;
    default:
      invalid_argument("stex_render_params.strategy " + std::to_string(p.strategy) +
                       " is not a stex_strategy");
  }
  RenderParams r;
  r.mni = p.mni;
  r.cell_factor = p.cell_factor;
  r.scale = p.scale;
  r.seed = p.seed;
  validate_render_params(r);
  return r;
}

const stex_model& checked_model(const stex_model* model) {
  if (!model) invalid_argument("model is NULL");
  return *model;
}

stex_context& checked_context(stex_context* context) {
  if (!context) invalid_argument("context is NULL");
  return *context;
}

// Bytes per packed row, and the effective stride (0 = packed); checks the stride.
std::size_t row_stride(int width, int channels, std::size_t row_stride_bytes, std::size_t* packed) {
  *packed = std::size_t(width) * std::size_t(channels) * sizeof(float);
  const std::size_t stride = row_stride_bytes ? row_stride_bytes : *packed;
  if (stride < *packed || stride % sizeof(float) != 0)
    invalid_argument("row_stride_bytes " + std::to_string(row_stride_bytes) +
                     " must be 0 (packed) or a multiple of 4 of at least width * channels * 4 = " +
                     std::to_string(*packed));
  return stride;
}

// Rows per chunk: about k_chunk_pixels, a multiple of the splat band; with a progress callback also at
// most an eighth of the region (rounded up to the band), so that the callback is called a few times.
int chunk_rows(int width, int height, bool progress) {
  const std::size_t by_pixels = k_chunk_pixels / std::size_t(width);
  int rows = int(
      std::max<std::size_t>(k_chunk_row_multiple, by_pixels / k_chunk_row_multiple * k_chunk_row_multiple));
  if (progress) {
    const int eighth = (height + 7) / 8;
    const int eighth_up = (eighth + k_chunk_row_multiple - 1) / k_chunk_row_multiple * k_chunk_row_multiple;
    rows = std::min(rows, std::max(k_chunk_row_multiple, eighth_up));
  }
  return std::min(rows, height);
}

// Calls chunk(first_row, rows) for consecutive chunks, reporting progress before and after each.
template <class Chunk>
void run_rows(int height, int rows, stex_progress_fn progress, void* user, Chunk&& chunk) {
  auto report = [&](double fraction) {
    if (progress && progress(fraction, user) != 0) {
      char pct[32];
      std::snprintf(pct, sizeof pct, "%.1f %%", 100.0 * fraction);
      throw ApiError(STEX_CANCELLED, std::string("cancelled by the progress callback at ") + pct);
    }
  };
  report(0.0);
  for (int r0 = 0; r0 < height; r0 += rows) {
    const int n = std::min(rows, height - r0);
    chunk(r0, n);
    report(r0 + n == height ? 1.0 : double(r0 + n) / double(height));
  }
}

template <class T>
T mem_info(cl_mem buffer, cl_mem_info what, const char* name) {
  T value{};
  const cl_int err = clGetMemObjectInfo(buffer, what, sizeof value, &value, nullptr);
  if (err == CL_INVALID_MEM_OBJECT) invalid_argument("buffer is not a valid cl_mem");
  if (err != CL_SUCCESS) throw OpenCLError("clGetMemObjectInfo", err, std::string("querying ") + name);
  return value;
}

// Checks that `buffer` belongs to the context, is device-writable and holds the region.
void check_buffer(const stex_context& context, cl_mem buffer, std::size_t offset, std::size_t stride,
                  std::size_t packed, int height) {
  if (mem_info<cl_context>(buffer, CL_MEM_CONTEXT, "CL_MEM_CONTEXT") != context.ctx->context())
    invalid_argument("buffer belongs to another cl_context than the stex context's");
  if (mem_info<cl_mem_flags>(buffer, CL_MEM_FLAGS, "CL_MEM_FLAGS") & CL_MEM_READ_ONLY)
    invalid_argument("buffer is CL_MEM_READ_ONLY");
  const std::size_t size = mem_info<std::size_t>(buffer, CL_MEM_SIZE, "CL_MEM_SIZE");
  const std::size_t rows_before = std::size_t(height) - 1;
  const std::size_t max = std::numeric_limits<std::size_t>::max();
  const bool overflow =
      offset > max - packed || (rows_before && stride > (max - offset - packed) / rows_before);
  if (overflow || offset + rows_before * stride + packed > size)
    invalid_argument("buffer holds " + std::to_string(size) +
                     " bytes, the region needs offset_bytes + (height - 1) * "
                     "row_stride_bytes + width * channels * 4 = " +
                     (overflow ? std::string("more than SIZE_MAX")
                               : std::to_string(offset + rows_before * stride + packed)));
}

// Host rows (packed, `rows` of `packed` bytes) -> the buffer's rows first_row.. at offset/stride; blocking.
void write_rows(Context& ctx, cl_mem buffer, std::size_t offset, std::size_t stride, std::size_t packed,
                int first_row, int rows, const float* host) {
  cl_command_queue queue = ctx.queue();
  const std::size_t at = offset + std::size_t(first_row) * stride;
  if (stride == packed) {
    cl_check(clEnqueueWriteBuffer(queue, buffer, CL_TRUE, at, packed * std::size_t(rows), host, 0, nullptr,
                                  nullptr),
             "clEnqueueWriteBuffer");
    return;
  }
  // Strided: one rectangular write when each row stays within one stride of the buffer, else row by row.
  if (offset % stride + packed <= stride) {
    const std::size_t buffer_origin[3] = {offset % stride, offset / stride + std::size_t(first_row), 0};
    const std::size_t host_origin[3] = {0, 0, 0};
    const std::size_t region[3] = {packed, std::size_t(rows), 1};
    cl_check(clEnqueueWriteBufferRect(queue, buffer, CL_TRUE, buffer_origin, host_origin, region, stride, 0,
                                      packed, 0, host, 0, nullptr, nullptr),
             "clEnqueueWriteBufferRect");
    return;
  }
  const unsigned char* bytes = reinterpret_cast<const unsigned char*>(host);
  for (int j = 0; j < rows; ++j)
    cl_check(clEnqueueWriteBuffer(queue, buffer, CL_FALSE, at + std::size_t(j) * stride, packed,
                                  bytes + std::size_t(j) * packed, 0, nullptr, nullptr),
             "clEnqueueWriteBuffer");
  ctx.finish();
}

// Strategies other than AUTO name the texton kind's splat and gather; the registry's other kinds have one.
void check_strategy(const stex_model& model, TextonStrategy strategy) {
  if (!model.texton && strategy != TextonStrategy::Auto)
    throw Error(ErrorKind::Usage, "stex_render_params.strategy: splat and gather are strategies of texton "
                                  "models; this model is of kind '" + model.loaded.container.kind +
                                      "' (use STEX_STRATEGY_AUTO)");
}

// Whether a region with these parameters is filtered (model/render_request.h: the CLI's and the service's
// rule); Error(Usage) for STEX_FILTER_ON on a model that does not filter.
bool filtered_region(const stex_model& m, const RenderParams& params, FilterMode mode, std::int64_t x,
                     std::int64_t y, int width, int height) {
  const RenderRequest r = RenderRequest::region(x, y, width, height, params, "auto", mode);
  validate_render_request(m.loaded, r);
  return uses_filter(m.loaded, r);
}

// Rows [y, y + rows) of the region into `out` (packed), with the entry's renderer of the model's kind; filtered:
// RenderParams::filter, which every kind that filters reads (texton and mix: the box prefilter).
void render_rows(ModelEntry& entry, const RenderParams& params, bool filtered,
                 const TextonRenderOptions& options, std::int64_t x, std::int64_t y, int width, int rows,
                 float* out) {
  RenderParams p = params;
  p.filter = filtered;
  if (entry.renderer)
    entry.renderer->render(p, x, y, width, rows, out, options);
  else
    entry.noise->render(p, x, y, width, rows, out);
}

// x * 2^16 rounded to the nearest integer, halfway cases away from zero (exact: the product is exact).
std::int64_t to_fixed(double v) {
  return std::int64_t(std::llround(v * double(std::int64_t(1) << STEX_FIX_BITS)));
}

}  // namespace
}  // namespace stex::capi

using stex::capi::guard;
using stex::capi::invalid_argument;

extern "C" {

STEX_API stex_status stex_render_params_init(stex_render_params* params, size_t struct_size) {
  return guard("stex_render_params_init", [&] {
    if (!params) invalid_argument("params is NULL");
    stex::capi::write_sized(params, struct_size, stex::capi::default_render_params(),
                            stex::capi::k_render_params_v0_size, "stex_render_params");
  });
}

STEX_API stex_status stex_render(stex_context* context, const stex_model* model,
                                 const stex_render_params* params, int64_t x, int64_t y, int32_t width,
                                 int32_t height, float* out, size_t row_stride_bytes,
                                 stex_progress_fn progress, void* user) {
  using namespace stex::capi;
  return guard("stex_render", [&] {
    stex_context& ctx = checked_context(context);
    const stex_model& m = checked_model(model);
    if (!out) invalid_argument("out is NULL");
    if (reinterpret_cast<std::uintptr_t>(out) % alignof(float) != 0)
      invalid_argument("out is not aligned to a float");
    stex::TextonStrategy strategy = stex::TextonStrategy::Auto;
    stex::FilterMode filter = stex::FilterMode::Auto;
    const stex::RenderParams rp = read_render_params(params, &strategy, &filter);
    check_strategy(m, strategy);
    stex::validate_region(x, y, width, height);
    const bool filtered = filtered_region(m, rp, filter, x, y, width, height);
    const int nc = m.loaded.summary.channels;
    std::size_t packed = 0;
    const std::size_t stride = row_stride(width, nc, row_stride_bytes, &packed);
    const int rows = chunk_rows(width, height, progress != nullptr);
    const std::size_t row_floats = std::size_t(width) * std::size_t(nc);
    std::vector<float> staging(stride == packed ? 0 : std::size_t(rows) * row_floats);

    std::lock_guard<std::mutex> lock(ctx.mutex);
    ModelEntry& entry = model_entry(ctx, m);
    stex::TextonRenderOptions options;
    options.strategy = strategy;
    unsigned char* bytes = reinterpret_cast<unsigned char*>(out);
    run_rows(height, rows, progress, user, [&](int r0, int n) {
      float* dst = stride == packed ? out + std::size_t(r0) * row_floats : staging.data();
      render_rows(entry, rp, filtered, options, x, y + r0, width, n, dst);
      if (stride != packed)
        for (int j = 0; j < n; ++j)
          std::memcpy(bytes + (std::size_t(r0) + std::size_t(j)) * stride,
                      staging.data() + std::size_t(j) * row_floats, packed);
    });
  });
}

STEX_API stex_status stex_render_cl(stex_context* context, const stex_model* model,
                                    const stex_render_params* params, int64_t x, int64_t y, int32_t width,
                                    int32_t height, struct _cl_mem* buffer, size_t offset_bytes,
                                    size_t row_stride_bytes, stex_progress_fn progress, void* user) {
  using namespace stex::capi;
  return guard("stex_render_cl", [&] {
    stex_context& ctx = checked_context(context);
    const stex_model& m = checked_model(model);
    if (!buffer) invalid_argument("buffer is NULL");
    if (offset_bytes % sizeof(float) != 0)
      invalid_argument("offset_bytes " + std::to_string(offset_bytes) + " is not a multiple of 4");
    stex::TextonStrategy strategy = stex::TextonStrategy::Auto;
    stex::FilterMode filter = stex::FilterMode::Auto;
    const stex::RenderParams rp = read_render_params(params, &strategy, &filter);
    check_strategy(m, strategy);
    stex::validate_region(x, y, width, height);
    const bool filtered = filtered_region(m, rp, filter, x, y, width, height);
    const int nc = m.loaded.summary.channels;
    std::size_t packed = 0;
    const std::size_t stride = row_stride(width, nc, row_stride_bytes, &packed);
    check_buffer(ctx, buffer, offset_bytes, stride, packed, height);
    const int rows = chunk_rows(width, height, progress != nullptr);

    std::lock_guard<std::mutex> lock(ctx.mutex);
    ModelEntry& entry = model_entry(ctx, m);
    // Gather and gather-local (auto on GPUs) write the caller's buffer directly with the plain gather kernel:
    // the same bits, no staging copy.
    const stex::TextonStrategy resolved =
        entry.renderer ? entry.renderer->resolve(strategy) : stex::TextonStrategy::Auto;
    if (entry.renderer && !filtered &&
        (resolved == stex::TextonStrategy::Gather || resolved == stex::TextonStrategy::GatherLocal)) {
      ensure_kernels(ctx);
      const stex::TextonSetup& setup = device_setup(ctx, entry, *m.texton, rp);
      stex::Kernel& kernel = *ctx.region_kernel;
      stex::LoopWatchdog watchdog(*ctx.ctx);
      run_rows(height, rows, progress, user, [&](int r0, int n) {
        cl_uint a = 0;
        kernel.set_arg(a++, setup.params);
        kernel.set_arg(a++, entry.alpha);
        kernel.set_arg(a++, entry.table);
        kernel.set_arg(a++, cl_long(x));
        kernel.set_arg(a++, cl_long(y + r0));
        kernel.set_arg(a++, cl_int(width));
        kernel.set_arg(a++, cl_int(n));
        kernel.set_arg(a++, buffer);
        kernel.set_arg(a++, cl_ulong((offset_bytes + std::size_t(r0) * stride) / sizeof(float)));
        kernel.set_arg(a++, cl_ulong(stride / sizeof(float)));
        stex::launch_watched(*ctx.ctx, kernel, watchdog, a, std::size_t(width), std::size_t(n), {0, 0});
      });
    } else {
      std::vector<float> staging(std::size_t(rows) * std::size_t(width) * std::size_t(nc));
      stex::TextonRenderOptions options;
      options.strategy = strategy;
      run_rows(height, rows, progress, user, [&](int r0, int n) {
        render_rows(entry, rp, filtered, options, x, y + r0, width, n, staging.data());
        write_rows(*ctx.ctx, buffer, offset_bytes, stride, packed, r0, n, staging.data());
      });
    }
  });
}

STEX_API stex_status stex_eval_points(stex_context* context, const stex_model* model,
                                      const stex_render_params* params, size_t count, const double* xy,
                                      float* out) {
  using namespace stex::capi;
  return guard("stex_eval_points", [&] {
    stex_context& ctx = checked_context(context);
    const stex_model& m = checked_model(model);
    if (count > 0 && (!xy || !out)) invalid_argument("xy or out is NULL");
    stex::TextonStrategy ignored = stex::TextonStrategy::Auto;
    const stex::RenderParams rp = read_render_params(params, &ignored);
    const stex::TextonModel& texton = texton_of(m, "point queries");
    if (count == 0) return;
    const std::size_t nc = std::size_t(texton.channels);
    if (count > std::numeric_limits<std::size_t>::max() / (2 * sizeof(double) * nc))
      invalid_argument("count " + std::to_string(count) + " is too large");
    // Every position is checked before any device work.
    const double limit = double(stex::k_max_pixel_coordinate);
    for (std::size_t k = 0; k < 2 * count; ++k) {
      const double v = xy[k];
      if (!std::isfinite(v) || std::fabs(v) >= limit) {
        char value[64];
        std::snprintf(value, sizeof value, "%.17g", v);
        throw stex::Error(stex::ErrorKind::Usage, std::string("point ") + std::to_string(k / 2) + ": " +
                                                      (k % 2 ? "y" : "x") + " = " + value +
                                                      " is not a finite coordinate with |coordinate| < 2^46");
      }
    }

    std::lock_guard<std::mutex> lock(ctx.mutex);
    ModelEntry& entry = model_entry(ctx, m);
    ensure_kernels(ctx);
    const stex::TextonSetup& setup = device_setup(ctx, entry, texton, rp);
    const std::size_t batch = std::min(count, k_point_batch);
    stex::Buffer<cl_long> positions(*ctx.ctx, 2 * batch, CL_MEM_READ_ONLY, "point positions");
    stex::Buffer<float> values(*ctx.ctx, batch * nc, CL_MEM_WRITE_ONLY, "point values");
    std::vector<cl_long> fixed(2 * batch);
    stex::Kernel& kernel = *ctx.points_kernel;
    stex::LoopWatchdog watchdog(*ctx.ctx);
    for (std::size_t k0 = 0; k0 < count; k0 += batch) {
      const std::size_t n = std::min(batch, count - k0);
      for (std::size_t i = 0; i < 2 * n; ++i) fixed[i] = cl_long(to_fixed(xy[2 * k0 + i]));
      positions.write(fixed.data(), 2 * n);
      cl_uint a = 0;
      kernel.set_arg(a++, setup.params);
      kernel.set_arg(a++, entry.alpha);
      kernel.set_arg(a++, entry.table);
      kernel.set_arg(a++, positions);
      kernel.set_arg(a++, cl_uint(n));
      kernel.set_arg(a++, values);
      stex::launch_watched(*ctx.ctx, kernel, watchdog, a, n, 1, {0, 0});
      values.read(out + k0 * nc, n * nc);
    }
  });
}

}  // extern "C"
