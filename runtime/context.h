// RAII OpenCL context + in-order command queue with profiling enabled, and the per-context program cache.
// A Context either owns its objects (created from a DeviceInfo) or borrows a caller's context, device and
// queue (retained while the Context lives; the embedding API uses that).
#pragma once
#include <CL/cl.h>

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "runtime/device.h"

namespace stex {

class Program;

class Context {
 public:
  explicit Context(const DeviceInfo& device);
  // Borrowed: retains the three objects; the queue should have profiling enabled for device timings.
  Context(cl_context context, cl_device_id device, cl_command_queue queue);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  // Convenience: select_device(spec) then construct.
  static std::unique_ptr<Context> create(const std::string& device_spec = "");

  cl_context context() const { return context_; }
  cl_device_id device() const { return device_; }
  cl_command_queue queue() const { return queue_; }
  const DeviceInfo& info() const { return info_; }

  // Builds (once per process and context) the program whose main source is the embedded kernel file
  // `source_name` (e.g. "texton_splat.cl"), with `options` appended to stex's own build options. Cached
  // by (source hash of the file and every shared header, options). Build failure: stex::Error(Device)
  // whose message contains the build log.
  Program& program(const std::string& source_name, const std::string& options = "");

  // The source names of the programs built so far, one per build (tests: which kernels a render needed).
  std::vector<std::string> built_programs();

  void finish() const;

 private:
  cl_context context_ = nullptr;
  cl_device_id device_ = nullptr;
  cl_command_queue queue_ = nullptr;
  bool borrowed_ = false;  // the device was retained (borrowed constructor) and is released in ~Context
  DeviceInfo info_;
  std::mutex mutex_;
  std::map<std::string, std::unique_ptr<Program>> programs_;
};

}  // namespace stex
