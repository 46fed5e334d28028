// The host side of the loop watchdog canary (loop_watchdog.h).
#include "runtime/loop_watchdog.h"

#include <atomic>
#include <cstdlib>

#include "core/error.h"

namespace stex {

namespace {
// Trips still to inject: STEX_FAULT_WATCHDOG at the first use, then inject_loop_watchdog_trips (tests).
std::atomic<long>& injected_trips() {
  static std::atomic<long> trips{[] {
    const char* v = std::getenv("STEX_FAULT_WATCHDOG");
    return v ? std::atol(v) : 0L;
  }()};
  return trips;
}
bool injected_trip() {
  std::atomic<long>& trips = injected_trips();
  for (long n = trips.load(); n > 0;)
    if (trips.compare_exchange_weak(n, n - 1)) return true;
  return false;
}
}  // namespace

void inject_loop_watchdog_trips(long count) { injected_trips().store(count); }

LoopWatchdog::LoopWatchdog(Context& ctx) : ctx_(&ctx), flag_(ctx, 1, CL_MEM_READ_WRITE, "loop watchdog flag") {}

cl_uint LoopWatchdog::bind(Kernel& kernel, cl_uint index) {
  const cl_uint zero = 0;
  flag_.write(&zero, 1);
  kernel.set_arg(index, cl_int(2));
  kernel.set_arg(index + 1, flag_);
  return index + 2;
}

bool LoopWatchdog::tripped() {
  cl_uint flag = 0;
  flag_.read(&flag, 1);
  if (injected_trip()) return true;
  return flag != 0;
}

std::string LoopWatchdog::refusal(const DeviceInfo& device, const std::string& kernel) {
  return "device '" + device.name + "' (platform '" + device.platform_name + "', driver " + device.driver_version +
         ") cut the loops of kernel '" + kernel +
         "' short even with one work-item per work-group: its driver caps the loop iterations of a kernel "
         "invocation (Mesa's llvmpipe: 65535) and this render needs more, so its values would be wrong "
         "(docs/portability.md, loop watchdog); render on another device";
}

double launch_checked(Context& ctx, Kernel& kernel, LoopWatchdog& watchdog, cl_uint index, std::size_t items_x,
                      std::size_t items_y, std::array<std::size_t, 2> local, bool* tripped) {
  watchdog.bind(kernel, index);
  double ms = 0.0;
  if (local[0] == 0 || local[1] == 0) {  // the implementation chooses the work-group
    ms = kernel.launch(ctx, NDRange(items_x, items_y));
  } else {
    const std::size_t gx = (items_x + local[0] - 1) / local[0] * local[0];
    const std::size_t gy = (items_y + local[1] - 1) / local[1] * local[1];
    ms = kernel.launch(ctx, NDRange(gx, gy), NDRange(local[0], local[1]));
  }
  *tripped = watchdog.tripped();
  return ms;
}

double launch_watched(Context& ctx, Kernel& kernel, LoopWatchdog& watchdog, cl_uint index, std::size_t items_x,
                      std::size_t items_y, std::array<std::size_t, 2> local, int* launches) {
  double ms = 0.0;
  for (;; local = {1, 1}) {
    bool tripped = false;
    ms += launch_checked(ctx, kernel, watchdog, index, items_x, items_y, local, &tripped);
    if (launches) ++*launches;
    if (!tripped) return ms;
    if (local[0] * local[1] == 1) throw Error(ErrorKind::Device, LoopWatchdog::refusal(ctx.info(), kernel.name()));
  }
}

}  // namespace stex
