// RAII OpenCL context and profiling command queue, and the per-context program cache (context.h).
#include "runtime/context.h"

#include <cstdint>
#include <cstdio>

#include "core/error.h"
#include "runtime/cl_error.h"
#include "runtime/program.h"

namespace stex {

namespace {

// FNV-1a, 64 bit: a stable hash of the resolved source for the cache key (collisions only matter within
// one process and one context, between sources that also share a name and options).
std::uint64_t fnv1a64(const std::string& s) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  return h;
}

}  // namespace

Context::Context(const DeviceInfo& device) : device_(device.id), info_(device) {
  if (!device.id || !device.platform)
    throw Error(ErrorKind::Internal, "Context: the DeviceInfo has no device (use select_device())");
  cl_int err = CL_SUCCESS;
  cl_context_properties props[] = {CL_CONTEXT_PLATFORM,
                                   reinterpret_cast<cl_context_properties>(device.platform), 0};
  context_ = clCreateContext(props, 1, &device_, nullptr, nullptr, &err);
  if (err != CL_SUCCESS) throw OpenCLError("clCreateContext", err, "device '" + device.name + "'");
  queue_ = clCreateCommandQueue(context_, device_, CL_QUEUE_PROFILING_ENABLE, &err);
  if (err != CL_SUCCESS) {
    clReleaseContext(context_);
    context_ = nullptr;
    throw OpenCLError("clCreateCommandQueue", err, "device '" + device.name + "'");
  }
}

Context::Context(cl_context context, cl_device_id device, cl_command_queue queue)
    : context_(context), device_(device), queue_(queue) {
  if (!context || !device || !queue)
    throw Error(ErrorKind::Usage, "Context: a borrowed context, device and queue must all be non-null");
  info_ = query_device(device);
  cl_check(clRetainContext(context_), "clRetainContext");
  cl_int err = clRetainCommandQueue(queue_);
  if (err != CL_SUCCESS) {
    clReleaseContext(context_);
    throw OpenCLError("clRetainCommandQueue", err);
  }
  // clRetainDevice is a no-op for root devices and keeps a caller's sub-device alive.
  err = clRetainDevice(device_);
  if (err != CL_SUCCESS) {
    clReleaseCommandQueue(queue_);
    clReleaseContext(context_);
    throw OpenCLError("clRetainDevice", err);
  }
  borrowed_ = true;
}

Context::~Context() {
  programs_.clear();  // programs hold the context: release them first
  if (queue_) {
    clFinish(queue_);
    clReleaseCommandQueue(queue_);
  }
  if (borrowed_ && device_) clReleaseDevice(device_);
  if (context_) clReleaseContext(context_);
}

std::unique_ptr<Context> Context::create(const std::string& device_spec) {
  return std::make_unique<Context>(select_device(device_spec));
}

Program& Context::program(const std::string& source_name, const std::string& options) {
  const std::string source = resolve_kernel_source(source_name);
  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(fnv1a64(source)));
  const std::string key = std::string(hash) + '\n' + source_name + '\n' + options;
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = programs_.find(key);
  if (it != programs_.end()) return *it->second;
  auto program = std::make_unique<Program>(*this, source, options, source_name);
  Program& ref = *program;
  programs_.emplace(key, std::move(program));
  return ref;
}

std::vector<std::string> Context::built_programs() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::string> names;
  for (const auto& entry : programs_) names.push_back(entry.second->label());
  return names;
}

void Context::finish() const { cl_check(clFinish(queue_), "clFinish"); }

}  // namespace stex
