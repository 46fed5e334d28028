// stex.hpp: header-only C++17 wrapper of the C API (stex/stex.h; read its comments for the semantics,
// coordinates, layouts and thread safety, which this wrapper does not change). RAII handles, parameters
// with the library's defaults, and exceptions: every failing call throws stex::Error carrying the
// stex_status and the message of stex_last_error().
//
//   stex::Context ctx("cpu");
//   stex::Model model = stex::Model::analyse("gravel.png");
//   stex::RenderParams params;            // the library's defaults
//   params.mni = 20;
//   std::vector<float> pixels = ctx.render(model, params, 0, 0, 256, 256);   // 256 x 256 x channels
//
// The classes live in the inline namespace stex::api0 (spelled stex::Context etc.), so their symbols never
// collide with stex's internal C++ classes of the same names inside libstex; the two are not meant to be
// included in one translation unit.
#ifndef STEX_STEX_HPP
#define STEX_STEX_HPP

#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "stex/stex.h"

namespace stex {
inline namespace api0 {

// A failed stex call: status() is the C status code, what() the library's message.
class Error : public std::runtime_error {
 public:
  Error(stex_status status, const std::string& message) : std::runtime_error(message), status_(status) {}
  stex_status status() const noexcept { return status_; }
  const char* status_name() const noexcept { return stex_status_name(status_); }

 private:
  stex_status status_;
};

namespace detail {

inline void check(stex_status status) {
  if (status != STEX_OK) throw Error(status, stex_last_error());
}

}  // namespace detail

// Analysis parameters: the C struct with the library's defaults (support 64, iterations 50, ...).
struct AnalysisParams : stex_analysis_params {
  AnalysisParams() : stex_analysis_params() {
    detail::check(stex_analysis_params_init(this, sizeof(stex_analysis_params)));
  }
};

// Render parameters: the C struct with the library's defaults (mni 30, cell_factor 0.6, scale 1, ...).
struct RenderParams : stex_render_params {
  RenderParams() : stex_render_params() {
    detail::check(stex_render_params_init(this, sizeof(stex_render_params)));
  }
};

// Surface-noise parameters: the C struct with the library's defaults (mni 60, cell_factor 0.6, texel 1, ...).
struct SurfaceParams : stex_surface_eval_params {
  SurfaceParams() : stex_surface_eval_params() {
    detail::check(stex_surface_eval_params_init(this, sizeof(stex_surface_eval_params)));
  }
};

// A noise model of any kind (Model::load reads every kind; the analyses make texton models). Immutable, so copies share one handle (released with the last copy) and may be
// used from any number of threads.
class Model {
 public:
  Model() = default;  // empty: only assignable

  static Model load(const std::string& path) {
    stex_model* m = nullptr;
    detail::check(stex_model_load(path.c_str(), &m));
    return Model(m);
  }
  static Model analyse(const std::string& path, const AnalysisParams& params = AnalysisParams()) {
    stex_model* m = nullptr;
    detail::check(stex_model_analyse_file(path.c_str(), &params, &m));
    return Model(m);
  }
  // Interleaved float pixels (see stex_model_analyse_pixels); row_stride_bytes 0 = packed.
  static Model analyse(const float* pixels, int width, int height, int channels,
                       std::size_t row_stride_bytes = 0, const AnalysisParams& params = AnalysisParams()) {
    stex_model* m = nullptr;
    detail::check(stex_model_analyse_pixels(pixels, width, height, channels, row_stride_bytes, &params, &m));
    return Model(m);
  }

  void save(const std::string& path) const { detail::check(stex_model_save(get(), path.c_str())); }

  stex_model_info info() const {
    stex_model_info i{};
    i.struct_size = sizeof i;
    detail::check(stex_model_get_info(get(), &i));
    return i;
  }
  int channels() const { return info().channels; }
  // "texton", "lrp", "gabor", ...
  std::string kind() const {
    const char* k = nullptr;
    detail::check(stex_model_kind(get(), &k));
    return k;
  }

  const stex_model* get() const { return handle_.get(); }
  explicit operator bool() const { return bool(handle_); }

 private:
  explicit Model(stex_model* m) : handle_(m, stex_model_destroy) {}
  std::shared_ptr<stex_model> handle_;
};

// A device context (stex/stex.h "Contexts"). Move-only. May be shared by threads (calls serialise).
class Context {
 public:
  // Progress callback: receives the fraction done; return true to cancel (the call then throws Error with
  // status STEX_CANCELLED). An exception thrown by the callback cancels and is rethrown to the caller.
  using Progress = std::function<bool(double fraction)>;

  // stex's own context on the device `device_spec` selects ("" = default, "cpu", "gpu", index, name).
  explicit Context(const std::string& device_spec = "") {
    stex_context* c = nullptr;
    detail::check(stex_context_create(device_spec.c_str(), &c));
    handle_.reset(c);
  }

  // A context on the caller's OpenCL objects (retained by stex; pass cl_context, cl_device_id,
  // cl_command_queue).
  static Context borrow(struct _cl_context* context, struct _cl_device_id* device,
                        struct _cl_command_queue* queue) {
    stex_context* c = nullptr;
    detail::check(stex_context_create_from_cl(context, device, queue, &c));
    return Context(c);
  }

  std::string device_name() const {
    const char* name = nullptr;
    detail::check(stex_context_device_name(get(), &name));
    return name;
  }

  // Renders [x, x + width) x [y, y + height) into `out` (interleaved; row_stride_bytes 0 = packed).
  void render(const Model& model, const RenderParams& params, std::int64_t x, std::int64_t y, int width,
              int height, float* out, std::size_t row_stride_bytes = 0,
              const Progress& progress = Progress()) {
    call_with_progress(progress, [&](stex_progress_fn fn, void* user) {
      return stex_render(get(), model.get(), &params, x, y, width, height, out, row_stride_bytes, fn, user);
    });
  }
  // The same region as a packed vector of width * height * channels floats.
  std::vector<float> render(const Model& model, const RenderParams& params, std::int64_t x, std::int64_t y,
                            int width, int height, const Progress& progress = Progress()) {
    const std::size_t n = (width > 0 && height > 0 ? std::size_t(width) * std::size_t(height) : 0) *
                          std::size_t(model ? model.channels() : 0);
    std::vector<float> out(n ? n : 1);
    render(model, params, x, y, width, height, out.data(), 0, progress);
    out.resize(n);
    return out;
  }

  // Renders into an OpenCL buffer of this context (see stex_render_cl for the layout).
  void render_cl(const Model& model, const RenderParams& params, std::int64_t x, std::int64_t y, int width,
                 int height, struct _cl_mem* buffer, std::size_t offset_bytes = 0,
                 std::size_t row_stride_bytes = 0, const Progress& progress = Progress()) {
    call_with_progress(progress, [&](stex_progress_fn fn, void* user) {
      return stex_render_cl(get(), model.get(), &params, x, y, width, height, buffer, offset_bytes,
                            row_stride_bytes, fn, user);
    });
  }

  // Point queries: xy holds (x, y) pairs in output-pixel coordinates; out receives count * channels floats.
  void eval_points(const Model& model, const RenderParams& params, std::size_t count, const double* xy,
                   float* out) {
    detail::check(stex_eval_points(get(), model.get(), &params, count, xy, out));
  }
  std::vector<float> eval_points(const Model& model, const RenderParams& params,
                                 const std::vector<double>& xy) {
    if (xy.size() % 2 != 0) throw Error(STEX_INVALID_ARGUMENT, "eval_points: xy must hold (x, y) pairs");
    const std::size_t count = xy.size() / 2;
    std::vector<float> out(count * std::size_t(model ? model.channels() : 0));
    eval_points(model, params, count, xy.data(), out.data());
    return out;
  }

  // Surface point queries (stex_eval_surface_points): positions and normals 3 * count doubles, tangents
  // nullptr or 3 * count doubles; out receives count * channels floats.
  void eval_surface_points(const Model& model, const SurfaceParams& params, std::size_t count,
                           const double* positions, const double* normals, const double* tangents,
                           float* out) {
    detail::check(stex_eval_surface_points(get(), model.get(), &params, count, positions, normals, tangents, out));
  }
  // The same with vectors of (x, y, z) triples; tangents empty = none.
  std::vector<float> eval_surface_points(const Model& model, const SurfaceParams& params,
                                         const std::vector<double>& positions, const std::vector<double>& normals,
                                         const std::vector<double>& tangents = std::vector<double>()) {
    if (positions.size() % 3 != 0 || normals.size() != positions.size() ||
        (!tangents.empty() && tangents.size() != positions.size()))
      throw Error(STEX_INVALID_ARGUMENT,
                  "eval_surface_points: positions, normals (and tangents, if any) must hold the same number of "
                  "(x, y, z) triples");
    const std::size_t count = positions.size() / 3;
    std::vector<float> out(count * std::size_t(model ? model.channels() : 0));
    eval_surface_points(model, params, count, positions.data(), normals.data(),
                        tangents.empty() ? nullptr : tangents.data(), out.data());
    return out;
  }

  stex_context* get() const { return handle_.get(); }

 private:
  struct Deleter {
    void operator()(stex_context* c) const { stex_context_destroy(c); }
  };
  explicit Context(stex_context* c) : handle_(c) {}

  struct ProgressState {
    const Progress* progress;
    std::exception_ptr error;
  };
  static int progress_trampoline(double fraction, void* user) {
    ProgressState* state = static_cast<ProgressState*>(user);
    try {
      return (*state->progress)(fraction) ? 1 : 0;
    } catch (...) {  // never let an exception unwind through the C library
      state->error = std::current_exception();
      return 1;
    }
  }
  template <class Call>
  static void call_with_progress(const Progress& progress, Call&& call) {
    ProgressState state{&progress, nullptr};
    const stex_status status =
        progress ? call(&Context::progress_trampoline, static_cast<void*>(&state)) : call(nullptr, nullptr);
    if (state.error) std::rethrow_exception(state.error);
    detail::check(status);
  }

  std::unique_ptr<stex_context, Deleter> handle_;
};

inline std::string version() { return stex_version_string(); }

}  // namespace api0
}  // namespace stex

#endif  // STEX_STEX_HPP
