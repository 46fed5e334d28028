// Typed RAII device buffers. The size is checked against CL_DEVICE_MAX_MEM_ALLOC_SIZE and the device's
// global memory before clCreateBuffer is called: an oversize request is a stex::Error(Limit) that names
// both sizes, never an OpenCL failure.
#pragma once
#include <CL/cl.h>

#include <cstddef>
#include <string>
#include <vector>

#include "runtime/cl_error.h"
#include "runtime/context.h"

namespace stex {

// Throws stex::Error(Limit) if `bytes` cannot be allocated on ctx's device (0 is allowed: 1 byte is
// allocated). Overflow-safe: `count * elem_size` is checked before multiplying.
std::size_t checked_buffer_bytes(const Context& ctx, std::size_t count, std::size_t elem_size,
                                 const char* what);
// The same check against a device description (the limits it reads: name, max_alloc, global_mem).
std::size_t checked_buffer_bytes(const DeviceInfo& dev, std::size_t count, std::size_t elem_size,
                                 const char* what);

template <class T>
class Buffer {
 public:
  Buffer() = default;
  Buffer(Context& ctx, std::size_t count, cl_mem_flags flags = CL_MEM_READ_WRITE, const char* what = "buffer")
      : ctx_(&ctx), count_(count) {
    std::size_t bytes = checked_buffer_bytes(ctx, count, sizeof(T), what);
    cl_int err = CL_SUCCESS;
    mem_ = clCreateBuffer(ctx.context(), flags, bytes ? bytes : 1, nullptr, &err);
    cl_check(err, "clCreateBuffer");
  }
  Buffer(Context& ctx, const std::vector<T>& host, cl_mem_flags flags = CL_MEM_READ_ONLY,
         const char* what = "buffer")
      : Buffer(ctx, host.size(), flags, what) {
    if (!host.empty()) write(host.data(), host.size());
  }
  ~Buffer() { reset(); }
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  Buffer(Buffer&& o) noexcept : ctx_(o.ctx_), mem_(o.mem_), count_(o.count_) {
    o.mem_ = nullptr;
    o.count_ = 0;
  }
  Buffer& operator=(Buffer&& o) noexcept {
    if (this != &o) {
      reset();
      ctx_ = o.ctx_;
      mem_ = o.mem_;
      count_ = o.count_;
      o.mem_ = nullptr;
      o.count_ = 0;
    }
    return *this;
  }

  void write(const T* host, std::size_t count, std::size_t offset = 0) {
    check_range(count, offset);
    if (count == 0) return;  // nothing to do (and a default-constructed Buffer has no queue)
    cl_check(clEnqueueWriteBuffer(ctx_->queue(), mem_, CL_TRUE, offset * sizeof(T), count * sizeof(T), host, 0,
                                  nullptr, nullptr),
             "clEnqueueWriteBuffer");
  }
  void read(T* host, std::size_t count, std::size_t offset = 0) const {
    check_range(count, offset);
    if (count == 0) return;
    cl_check(clEnqueueReadBuffer(ctx_->queue(), mem_, CL_TRUE, offset * sizeof(T), count * sizeof(T), host, 0,
                                 nullptr, nullptr),
             "clEnqueueReadBuffer");
  }
  std::vector<T> read() const {
    std::vector<T> out(count_);
    if (count_) read(out.data(), count_);
    return out;
  }

  // Grows the buffer to hold at least `count` elements: kept as it is when it already does, else released and
  // allocated anew (released first: the device may not hold both). Its contents are not kept.
  void reserve(Context& ctx, std::size_t count, cl_mem_flags flags, const char* what) {
    if (mem_ && count_ >= count) return;
    *this = Buffer();
    *this = Buffer(ctx, count, flags, what);
  }

  cl_mem get() const { return mem_; }
  std::size_t size() const { return count_; }
  std::size_t bytes() const { return count_ * sizeof(T); }

 private:
  void reset() {
    if (mem_) clReleaseMemObject(mem_);
    mem_ = nullptr;
  }
  void check_range(std::size_t count, std::size_t offset) const {
    if (offset > count_ || count > count_ - offset)
      throw Error(ErrorKind::Internal, "buffer access out of range");
  }
  Context* ctx_ = nullptr;
  cl_mem mem_ = nullptr;
  std::size_t count_ = 0;
};

}  // namespace stex
