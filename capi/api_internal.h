// Internals of the C API (include/stex/stex.h): the structs behind the opaque handles, the error firewall
// every exported function runs its body in, and the reading of the size-prefixed parameter structs.
// Private to capi/*.cpp; nothing here is exported (libstex.so exports the STEX_API functions only).
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <list>
#include <memory>
#include <mutex>
#include <string>

#include "model/codecs.h"
#include "model/kinds.h"
#include "model/loaded_model.h"
#include "core/error.h"
#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/model.h"
#include "runtime/noise_renderer.h"
#include "runtime/program.h"
#include "runtime/surface.h"
#include "runtime/texton_params.h"
#include "runtime/texton_renderer.h"
#include "stex/stex.h"

namespace stex::capi {

// An error raised by the C API layer itself (argument checks, cancellation), with its status.
class ApiError : public std::exception {
 public:
  ApiError(stex_status status, std::string message) : status_(status), message_(std::move(message)) {}
  stex_status status() const noexcept { return status_; }
  const char* what() const noexcept override { return message_.c_str(); }

 private:
  stex_status status_;
  std::string message_;
};

[[noreturn]] inline void invalid_argument(const std::string& message) {
  throw ApiError(STEX_INVALID_ARGUMENT, message);
}

// The status an internal error kind maps to (same numeric values: stex.h mirrors core/error.h).
stex_status status_of(ErrorKind kind) noexcept;

// Clears the calling thread's last error (start of every call).
void begin_call() noexcept;
// Records "<function>: <message>" as the calling thread's last error and returns `status`.
stex_status fail(const char* function, stex_status status, const char* message) noexcept;

// The error firewall: runs `body`, maps every exception to a status and the last-error text.
template <class Body>
stex_status guard(const char* function, Body&& body) noexcept {
  begin_call();
  try {
    body();
    return STEX_OK;
  } catch (const ApiError& e) {
    return fail(function, e.status(), e.what());
  } catch (const Error& e) {
    return fail(function, status_of(e.kind()), e.what());
  } catch (const std::bad_alloc&) {
    return fail(function, STEX_LIMIT, "out of host memory");
  } catch (const std::exception& e) {
    return fail(function, STEX_INTERNAL, e.what());
  } catch (...) {
    return fail(function, STEX_INTERNAL, "unknown exception");
  }
}

// Sizes of the first published version of each struct. Frozen: a later version appends fields, and a
// caller built against this version keeps passing these sizes.
constexpr std::size_t k_analysis_params_v0_size = 48;
constexpr std::size_t k_render_params_v0_size = 48;
constexpr std::size_t k_model_info_v0_size = 80;
constexpr std::size_t k_surface_eval_params_v0_size = 48;

// Reads a caller's size-prefixed struct: NULL -> defaults; struct_size below the first version's size ->
// invalid; fields the caller's version lacks keep their defaults; a larger struct (a caller built against
// a newer stex) is accepted when the fields this library does not know are all zero.
template <class T>
T read_sized(const T* user, const T& defaults, std::size_t v0_size, const char* what) {
  if (!user) return defaults;
  std::size_t n = user->struct_size;
  if (n < v0_size)
    invalid_argument(std::string(what) + ".struct_size is " + std::to_string(n) + ", expected at least " +
                     std::to_string(v0_size) + " (call the *_init function first)");
  if (n > sizeof(T)) {
    const unsigned char* bytes = reinterpret_cast<const unsigned char*>(user);
    for (std::size_t i = sizeof(T); i < n; ++i)
      if (bytes[i] != 0)
        invalid_argument(std::string(what) + " sets fields this stex (" + STEX_VERSION_STRING +
                         ") does not know (struct_size " + std::to_string(n) + " > " +
                         std::to_string(sizeof(T)) + ")");
    n = sizeof(T);
  }
  T out = defaults;
  std::memcpy(&out, user, n);
  out.struct_size = sizeof(T);
  return out;
}

// Fills the first struct_size bytes of a caller's struct from `full` (struct_size is set to the caller's
// size); fields of a newer version, unknown to this library, are zeroed (zero = "not set").
template <class T>
void write_sized(T* user, std::size_t struct_size, T full, std::size_t v0_size, const char* what) {
  if (struct_size < v0_size)
    invalid_argument(std::string(what) + ".struct_size is " + std::to_string(struct_size) +
                     ", expected at least " + std::to_string(v0_size));
  full.struct_size = struct_size;
  std::memcpy(user, &full, struct_size < sizeof(T) ? struct_size : sizeof(T));
  if (struct_size > sizeof(T))
    std::memset(reinterpret_cast<unsigned char*>(user) + sizeof(T), 0, struct_size - sizeof(T));
}

// The device copies and renderer of one model on one context (cached per context, least recently used).
struct ModelEntry {
  std::uint64_t serial = 0;
  std::unique_ptr<TextonRenderer> renderer;  // texton: region rendering (splat / gather, host output)
  std::unique_ptr<NoiseRenderer> noise;      // other kinds: the registry's renderer (analysis/noise_kinds.h)
  std::unique_ptr<SurfaceRenderer> surface;  // texton: surface point queries (created on first use)
  // For the C API's own kernels (point queries, region into a caller's cl_mem):
  std::unique_ptr<TextonSetup> setup;
  RenderParams setup_params;
  Buffer<float> alpha;
  Buffer<std::uint32_t> table;
};

}  // namespace stex::capi

// A model of any registered kind, loaded once (container, SHA-256, decoded model, summary), and a view of the
// decoded texton model for texton models (the kind with point queries, surface noise and the C API's own
// kernels).
struct stex_model {
  stex::LoadedModel loaded;                  // decoded once (model/loaded_model.h)
  const stex::TextonModel* texton = nullptr;  // loaded.as<TextonModel>(): texton models only
  std::uint64_t serial = 0;  // unique per process: keys the per-context device caches (never reused)
};

struct stex_context {
  std::unique_ptr<stex::Context> ctx;
  std::string device_name;
  std::mutex mutex;  // serialises everything that uses the device (and the members below)
  std::list<stex::capi::ModelEntry> models;  // most recently used first; declared after ctx: freed first
  std::unique_ptr<stex::Program> program;    // the C API's kernels (capi/device_kernels.cpp)
  std::unique_ptr<stex::Kernel> points_kernel, region_kernel;

  ~stex_context() {
    // Kernels and buffers before the program, all before the Context (which releases the queue).
    points_kernel.reset();
    region_kernel.reset();
    models.clear();
    program.reset();
  }
};

namespace stex::capi {

constexpr std::size_t k_model_cache_size = 4;

// The cache entry of `model` on `context` (created, or moved to the front). The context's mutex must be held.
ModelEntry& model_entry(stex_context& context, const stex_model& model);

// The model's texton form; Error(Input) naming `what` (the operation) for another kind.
const TextonModel& texton_of(const stex_model& model, const char* what);

// The entry's TextonSetup for `params`, with alpha and the Poisson table on the device.
const TextonSetup& device_setup(stex_context& context, ModelEntry& entry, const TextonModel& model,
                                const RenderParams& params);

// Builds (once per context) the C API's kernels.
void ensure_kernels(stex_context& context);

// The OpenCL C source of the C API's entry points (appended to the resolved shared texton header).
const char* device_kernel_source();

}  // namespace stex::capi
