// Size checks for device buffers (buffer.h): every allocation is checked against the device's
// CL_DEVICE_MAX_MEM_ALLOC_SIZE and CL_DEVICE_GLOBAL_MEM_SIZE before clCreateBuffer, so an oversize request is
// a stex::Error(Limit) naming the sizes instead of an OpenCL failure (or a driver that over-commits).
#include "runtime/buffer.h"

#include <cstdint>
#include <cstdio>
#include <limits>

#include "core/error.h"

namespace stex {

namespace {

// "123456789 bytes (117.7 MiB)"
std::string bytes_text(std::uint64_t bytes) {
  char buf[96];
  const double mib = double(bytes) / (1024.0 * 1024.0);
  if (mib >= 1024.0)
    std::snprintf(buf, sizeof buf, "%llu bytes (%.1f GiB)", static_cast<unsigned long long>(bytes),
                  mib / 1024.0);
  else
    std::snprintf(buf, sizeof buf, "%llu bytes (%.1f MiB)", static_cast<unsigned long long>(bytes), mib);
  return buf;
}

}  // namespace

std::size_t checked_buffer_bytes(const Context& ctx, std::size_t count, std::size_t elem_size,
                                 const char* what) {
  return checked_buffer_bytes(ctx.info(), count, elem_size, what);
}

std::size_t checked_buffer_bytes(const DeviceInfo& dev, std::size_t count, std::size_t elem_size,
                                 const char* what) {
  const std::string name = what ? what : "buffer";
  if (elem_size != 0 && count > std::numeric_limits<std::size_t>::max() / elem_size)
    throw Error(ErrorKind::Limit, name + ": " + std::to_string(count) + " elements of " +
                                      std::to_string(elem_size) +
                                      " bytes overflow the address space (device '" + dev.name + "' allows " +
                                      bytes_text(dev.max_alloc) + " per allocation)");
  const std::size_t bytes = count * elem_size;
  const std::string request = name + " needs " + bytes_text(bytes) + " (" + std::to_string(count) + " x " +
                              std::to_string(elem_size) + " bytes)";
  if (std::uint64_t(bytes) > dev.max_alloc)
    throw Error(ErrorKind::Limit, request + " but device '" + dev.name + "' allows at most " +
                                      bytes_text(dev.max_alloc) +
                                      " per allocation (CL_DEVICE_MAX_MEM_ALLOC_SIZE)");
  if (std::uint64_t(bytes) > dev.global_mem)
    throw Error(ErrorKind::Limit, request + " but device '" + dev.name + "' has " +
                                      bytes_text(dev.global_mem) +
                                      " of global memory (CL_DEVICE_GLOBAL_MEM_SIZE)");
  return bytes;
}

}  // namespace stex
