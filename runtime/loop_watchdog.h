// The host side of the loop watchdog canary (kernels/shared/stex_platform.h, docs/portability.md): some
// drivers stop every loop of a kernel invocation after a fixed number of iterations (Mesa's llvmpipe: 65535
// per SIMD batch of work-items, shared by all the kernel's loops) and return a wrong result with success.
// Kernels with data-dependent loops end with STEX_WATCHDOG_CHECK(); a renderer binds a LoopWatchdog to the
// kernel's two trailing watchdog arguments before each launch and asks tripped() after it. A tripped launch
// wrote wrong values: the renderer re-runs it with less work per invocation (the output never depends on
// the work split) or refuses with refusal(), an Error(Device) naming the device, the kernel and the cause.
#pragma once
#include <array>
#include <cstddef>
#include <string>

#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/program.h"

namespace stex {

class LoopWatchdog {
 public:
  explicit LoopWatchdog(Context& ctx);

  // Clears the flag and sets arguments `index` (the canary's pass count, 2) and `index + 1` (the flag) of
  // `kernel`; returns index + 2.
  cl_uint bind(Kernel& kernel, cl_uint index);

  // True if a work-item of the launches since bind() saw its loops cut short. Reads the flag (a blocking
  // 4-byte read). STEX_FAULT_WATCHDOG=N (tests, docs/hardening.md) or inject_loop_watchdog_trips(N) makes
  // the next N calls report a trip, so the retry and refusal paths run on any device.
  bool tripped();

  // The Error(Device) message for a launch that still trips with the least work per invocation.
  static std::string refusal(const DeviceInfo& device, const std::string& kernel);

 private:
  Context* ctx_;
  Buffer<cl_uint> flag_;
};

// Tests: the next `count` tripped() calls of the process report a trip (replaces STEX_FAULT_WATCHDOG's count).
void inject_loop_watchdog_trips(long count);

// One launch of `kernel` over items_x x items_y work-items (rounded up to `local`; {0, 0}: the
// implementation chooses), `watchdog` bound at argument `index`; *tripped says whether its loops were cut
// short (then its output is wrong). Returns the device milliseconds. For renderers that split the work
// themselves when a launch trips (runtime/texton_filter.cpp).
double launch_checked(Context& ctx, Kernel& kernel, LoopWatchdog& watchdog, cl_uint index, std::size_t items_x,
                      std::size_t items_y, std::array<std::size_t, 2> local, bool* tripped);

// One watched launch of `kernel` over items_x x items_y work-items (rounded up to `local`; {0, 0}: the
// implementation chooses the work-group, and 1-D kernels take items_y = 1): binds `watchdog` at
// argument `index`, launches, and if the loops were cut short re-runs it with one work-item per work-group
// (the least work per invocation; kernels write pixels from their coordinates, so the output is the same);
// Error(Device) with refusal() if that trips too. Returns the device milliseconds; adds the launches made to
// *launches when given.
double launch_watched(Context& ctx, Kernel& kernel, LoopWatchdog& watchdog, cl_uint index, std::size_t items_x,
                      std::size_t items_y, std::array<std::size_t, 2> local, int* launches = nullptr);

}  // namespace stex
