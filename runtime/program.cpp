// Programs from the embedded kernel sources (include resolution, build, build log) and kernels with a
// launch helper that returns the device time from profiling events (program.h).
//
// Include resolution: a line `#include "name"` in a kernel file or shared header is replaced by the text of
// `name`, looked up first relative to the including file's directory ("rng.h" inside "shared/texton.h" is
// "shared/rng.h"), then relative to kernels/. Each file is inlined once (the shared headers also have
// include guards). `#include <...>` lines are left alone: they only occur in the host branch of
// stex_platform.h, which the OpenCL compiler skips. `#line` directives keep the compiler's messages
// pointing at the original file and line. The resolver does not parse comments or #if: an #include line
// inside a comment or a host-only branch is inlined too (harmless for headers written in the dialect).
#include "runtime/program.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

#include "core/error.h"
#include "runtime/context.h"
#include "runtime/kernel_sources.h"
#include "runtime/selftest.h"

namespace stex {

namespace {

// Build options stex always uses. No -cl-fast-relaxed-math / -cl-mad-enable: kernels and the C++ reference
// must agree bit for bit (kernels/shared/stex_platform.h).
constexpr const char* k_base_options = "-cl-std=CL1.2";

// Build logs of heavily templated failures can be huge; keep the start (the first error is what matters).
constexpr std::size_t k_max_log_chars = 64 * 1024;

const char* kernel_dir_override() {
  const char* dir = std::getenv("STEX_KERNEL_DIR");
  return (dir && *dir) ? dir : nullptr;
}

// Text of a kernel file by its name relative to kernels/, or false if there is none.
bool find_source(const std::string& name, std::string* text) {
  if (const char* dir = kernel_dir_override()) {
    std::ifstream in(std::string(dir) + "/" + name, std::ios::binary);
    if (!in) return false;
    std::ostringstream os;
    os << in.rdbuf();
    *text = os.str();
    return true;
  }
  std::size_t count = 0;
  const EmbeddedSource* sources = embedded_sources(&count);
  for (std::size_t i = 0; i < count; ++i) {
    if (name == sources[i].name) {
      *text = sources[i].text;
      return true;
    }
  }
  return false;
}

std::string available_sources() {
  if (const char* dir = kernel_dir_override()) return std::string("files in STEX_KERNEL_DIR=") + dir;
  std::size_t count = 0;
  const EmbeddedSource* sources = embedded_sources(&count);
  std::string list;
  for (std::size_t i = 0; i < count; ++i) list += (i ? ", " : "") + std::string(sources[i].name);
  return "embedded: " + list;
}

// The quoted name of an `#include "name"` line, or "" if the line is not one.
std::string quoted_include(const std::string& line) {
  std::size_t i = line.find_first_not_of(" \t");
  if (i == std::string::npos || line[i] != '#') return "";
  i = line.find_first_not_of(" \t", i + 1);
  if (i == std::string::npos || line.compare(i, 7, "include") != 0) return "";
  i = line.find_first_not_of(" \t", i + 7);
  if (i == std::string::npos || line[i] != '"') return "";
  std::size_t end = line.find('"', i + 1);
  if (end == std::string::npos) return "";
  return line.substr(i + 1, end - i - 1);
}

void resolve_into(const std::string& name, const std::string& text, std::set<std::string>* done,
                  std::string* out) {
  const std::string dir = name.find('/') == std::string::npos ? "" : name.substr(0, name.rfind('/') + 1);
  *out += "#line 1 \"" + name + "\"\n";
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string inc = quoted_include(line);
    if (inc.empty()) {
      *out += line;
      *out += '\n';
      continue;
    }
    std::string child_name = dir + inc, child_text;
    if (!find_source(child_name, &child_text)) {
      child_name = inc;
      if (!find_source(child_name, &child_text))
        throw Error(ErrorKind::Internal, name + ":" + std::to_string(line_no) +
                                             ": cannot resolve #include \"" + inc + "\" (" +
                                             available_sources() + ")");
    }
    if (done->insert(child_name).second) resolve_into(child_name, child_text, done, out);
    *out += "#line " + std::to_string(line_no + 1) + " \"" + name + "\"\n";
  }
}

std::string program_build_log(cl_program program, cl_device_id device) {
  std::size_t size = 0;
  if (clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, 0, nullptr, &size) != CL_SUCCESS ||
      size == 0)
    return "";
  std::string log(size, '\0');
  if (clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, size, log.data(), nullptr) != CL_SUCCESS)
    return "";
  while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) log.pop_back();
  if (log.size() > k_max_log_chars) log = log.substr(0, k_max_log_chars) + "\n[build log truncated]";
  return log;
}

// Releases an event however the launch ends.
struct EventGuard {
  cl_event event = nullptr;
  ~EventGuard() {
    if (event) clReleaseEvent(event);
  }
};

}  // namespace

std::string resolve_kernel_source(const std::string& source_name) {
  std::string text;
  if (!find_source(source_name, &text))
    throw Error(ErrorKind::Internal,
                "unknown kernel source '" + source_name + "' (" + available_sources() + ")");
  std::set<std::string> done{source_name};
  std::string out;
  resolve_into(source_name, text, &done, &out);
  return out;
}

Program::Program(Context& ctx, const std::string& source, const std::string& options,
                 const std::string& label)
    : label_(label) {
  const char* text = source.c_str();
  const std::size_t length = source.size();
  cl_int err = CL_SUCCESS;
  program_ = clCreateProgramWithSource(ctx.context(), 1, &text, &length, &err);
  if (err != CL_SUCCESS) throw OpenCLError("clCreateProgramWithSource", err, "program '" + label + "'");

  std::string all_options = k_base_options;
  if (!options.empty()) all_options += " " + options;
  // Test builds only (STEX_TESTING): STEX_TEST_KERNEL_DEFINES, e.g. the self-test's fault (runtime/selftest.h).
  if (const std::string extra = test_kernel_defines(); !extra.empty()) all_options += " " + extra;
  cl_device_id device = ctx.device();
  const auto start = std::chrono::steady_clock::now();
  err = clBuildProgram(program_, 1, &device, all_options.c_str(), nullptr, nullptr);
  build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (err != CL_SUCCESS) {
    std::string detail = "building program '" + label + "' for device '" + ctx.info().name +
                         "' with options '" + all_options + "'";
    const std::string log = program_build_log(program_, device);
    detail += log.empty() ? " (the compiler gave no build log)" : "; build log:\n" + log;
    clReleaseProgram(program_);
    program_ = nullptr;
    throw OpenCLError("clBuildProgram", err, detail);
  }
}

Program::~Program() {
  if (program_) clReleaseProgram(program_);
}

Kernel::Kernel(Program& program, const std::string& name) : name_(name) {
  cl_int err = CL_SUCCESS;
  kernel_ = clCreateKernel(program.get(), name.c_str(), &err);
  if (err != CL_SUCCESS)
    throw OpenCLError("clCreateKernel", err, "kernel '" + name + "' in program '" + program.label() + "'");
}

Kernel::~Kernel() {
  if (kernel_) clReleaseKernel(kernel_);
}

Kernel::Kernel(Kernel&& other) noexcept : kernel_(other.kernel_), name_(std::move(other.name_)) {
  other.kernel_ = nullptr;
}

void Kernel::set_arg_raw(cl_uint index, std::size_t size, const void* value) {
  cl_int err = clSetKernelArg(kernel_, index, size, value);
  if (err != CL_SUCCESS)
    throw OpenCLError("clSetKernelArg", err,
                      "kernel '" + name_ + "', argument " + std::to_string(index) + " (" +
                          std::to_string(size) + " bytes)");
}

std::size_t Kernel::max_work_group(const Context& ctx) const {
  if (max_work_group_ == 0) {
    std::size_t n = 0;
    cl_check(clGetKernelWorkGroupInfo(kernel_, ctx.device(), CL_KERNEL_WORK_GROUP_SIZE, sizeof(n), &n, nullptr),
             "clGetKernelWorkGroupInfo");
    const std::size_t device_max = ctx.info().max_work_group_size;
    max_work_group_ = std::max<std::size_t>(1, device_max ? std::min(n, device_max) : n);
  }
  return max_work_group_;
}

std::array<std::size_t, 2> Kernel::fit_local(const Context& ctx, std::array<std::size_t, 2> wanted) const {
  const std::size_t limit = max_work_group(ctx);
  const auto& items = ctx.info().max_work_item_sizes;
  for (std::size_t d = 0; d < 2; ++d) {
    wanted[d] = std::max<std::size_t>(1, wanted[d]);
    while (items[d] && wanted[d] > items[d]) wanted[d] = (wanted[d] + 1) / 2;
  }
  while (wanted[0] * wanted[1] > limit) {
    std::size_t& side = wanted[0] >= wanted[1] ? wanted[0] : wanted[1];
    side = (side + 1) / 2;
  }
  return wanted;
}

void Kernel::set_local_arg(cl_uint index, std::size_t bytes) { set_arg_raw(index, bytes, nullptr); }

double Kernel::launch(Context& ctx, const NDRange& global, const NDRange& local) {
  if (global.dims == 0 || global.dims > 3)
    throw Error(ErrorKind::Internal, "kernel '" + name_ + "': the global range needs 1 to 3 dimensions");
  if (local.dims != 0 && local.dims != global.dims)
    throw Error(ErrorKind::Internal, "kernel '" + name_ + "': the local range has " +
                                         std::to_string(local.dims) + " dimensions, the global range " +
                                         std::to_string(global.dims));
  for (std::size_t d = 0; d < global.dims; ++d)
    if (global.size[d] == 0) return 0.0;  // nothing to run (OpenCL 1.2 rejects empty ranges)

  EventGuard event;
  const auto wall0 = std::chrono::steady_clock::now();
  cl_int err = clEnqueueNDRangeKernel(ctx.queue(), kernel_, cl_uint(global.dims), nullptr, global.size.data(),
                                      local.dims ? local.size.data() : nullptr, 0, nullptr, &event.event);
  if (err != CL_SUCCESS) {
    std::ostringstream os;
    os << "kernel '" << name_ << "', global";
    for (std::size_t d = 0; d < global.dims; ++d) os << (d ? "x" : " ") << global.size[d];
    if (local.dims) {
      os << ", local";
      for (std::size_t d = 0; d < local.dims; ++d) os << (d ? "x" : " ") << local.size[d];
    }
    throw OpenCLError("clEnqueueNDRangeKernel", err, os.str());
  }
  err = clWaitForEvents(1, &event.event);
  cl_int status = CL_COMPLETE;
  cl_int status_err =
      clGetEventInfo(event.event, CL_EVENT_COMMAND_EXECUTION_STATUS, sizeof status, &status, nullptr);
  if (status_err == CL_SUCCESS && status < 0)
    throw OpenCLError("kernel execution", status, "kernel '" + name_ + "'");
  if (err != CL_SUCCESS) throw OpenCLError("clWaitForEvents", err, "kernel '" + name_ + "'");
  const double wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall0).count();

  cl_ulong t0 = 0, t1 = 0;
  err = clGetEventProfilingInfo(event.event, CL_PROFILING_COMMAND_START, sizeof t0, &t0, nullptr);
  if (err == CL_PROFILING_INFO_NOT_AVAILABLE) return 0.0;  // a borrowed queue without profiling
  if (err != CL_SUCCESS) throw OpenCLError("clGetEventProfilingInfo", err, "kernel '" + name_ + "'");
  cl_check(clGetEventProfilingInfo(event.event, CL_PROFILING_COMMAND_END, sizeof t1, &t1, nullptr),
           "clGetEventProfilingInfo");
  // A driver whose profiling events are placeholders (rusticl 22.3: queued, submit, start, end = 0, 1, 2, 3 ns;
  // docs/portability.md root cause 8): the host's time from enqueue to completion, an upper bound of the
  // device time, so that calibrations and statistics stay meaningful. No real launch takes under 1 us.
  return t1 >= t0 + 1000 ? double(t1 - t0) * 1e-6 : wall_ms;
}

}  // namespace stex
