// OpenCL programs built from the embedded kernel sources (runtime/kernel_sources.h), and kernels with a
// launch helper that returns the device time of the launch (profiling events; benchmarks use it).
//
// Shared headers are handed to the compiler under their include names: a kernel writes
// `#include "shared/texton.h"` (and a shared header `#include "rng.h"`); the runtime resolves includes
// itself by inlining the embedded files (once each, like #pragma once), so no file system path is
// involved and the build is the same for every device. STEX_KERNEL_DIR=<dir> loads sources from <dir>
// instead of the embedded copies (development).
#pragma once
#include <CL/cl.h>

#include <array>
#include <cstddef>
#include <string>
#include <type_traits>

#include "runtime/cl_error.h"

namespace stex {

class Context;
template <class T>
class Buffer;

// The full source of an embedded kernel file with its includes resolved (throws stex::Error(Internal) for
// an unknown name or include).
std::string resolve_kernel_source(const std::string& source_name);

// Builds a program from arbitrary source text (tests use it for deliberately broken kernels). Throws
// stex::Error(Device) with the build log on failure.
class Program {
 public:
  Program(Context& ctx, const std::string& source, const std::string& options, const std::string& label);
  ~Program();
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;
  cl_program get() const { return program_; }
  const std::string& label() const { return label_; }
  double build_seconds() const { return build_seconds_; }

 private:
  cl_program program_ = nullptr;
  std::string label_;
  double build_seconds_ = 0.0;
};

struct NDRange {
  std::size_t dims = 0;  // 0 = let the runtime choose (for the local size)
  std::array<std::size_t, 3> size{1, 1, 1};
  NDRange() = default;
  NDRange(std::size_t x) : dims(1), size{x, 1, 1} {}
  NDRange(std::size_t x, std::size_t y) : dims(2), size{x, y, 1} {}
  NDRange(std::size_t x, std::size_t y, std::size_t z) : dims(3), size{x, y, z} {}
};

class Kernel {
 public:
  Kernel(Program& program, const std::string& name);
  ~Kernel();
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;
  Kernel(Kernel&& other) noexcept;

  template <class T>
  void set_arg(cl_uint index, const Buffer<T>& buffer) {
    cl_mem m = buffer.get();
    set_arg_raw(index, sizeof(cl_mem), &m);
  }
  template <class T, class = std::enable_if_t<std::is_trivially_copyable_v<T>>>
  void set_arg(cl_uint index, const T& value) {
    set_arg_raw(index, sizeof(T), &value);
  }
  void set_arg_raw(cl_uint index, std::size_t size, const void* value);
  void set_local_arg(cl_uint index, std::size_t bytes);

  // Enqueues on ctx's queue, waits for completion, returns the device time in milliseconds
  // (CL_PROFILING_COMMAND_END - START). `global` is rounded up by the caller, not here. An empty global
  // range launches nothing and returns 0; so does a borrowed queue created without profiling.
  double launch(Context& ctx, const NDRange& global, const NDRange& local = NDRange());

  // The largest work-group this kernel accepts on ctx's device: CL_KERNEL_WORK_GROUP_SIZE, bounded by the
  // device's CL_DEVICE_MAX_WORK_GROUP_SIZE as ctx.info() has it (queried once per kernel).
  std::size_t max_work_group(const Context& ctx) const;

  // A 2-D work-group size this kernel can launch with on ctx's device: `wanted`, its larger side halved
  // (rounded up) until both sides fit CL_DEVICE_MAX_WORK_ITEM_SIZES and their product fits max_work_group.
  // Callers round their global range up to the result. Outputs never depend on it (every kernel writes a
  // pixel from its coordinates alone), so devices with small work-groups get the same bits.
  std::array<std::size_t, 2> fit_local(const Context& ctx, std::array<std::size_t, 2> wanted) const;

  cl_kernel get() const { return kernel_; }
  const std::string& name() const { return name_; }

 private:
  cl_kernel kernel_ = nullptr;
  std::string name_;
  mutable std::size_t max_work_group_ = 0;  // 0: not queried yet
};

}  // namespace stex
