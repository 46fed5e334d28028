/* Test kernel of the loop watchdog canary (kernels/shared/stex_platform.h, tests/kernels/
 * test_device_capabilities.cpp): a loop of `n` passes whose pass count each work-item writes, then the
 * canary. On a driver that caps a kernel invocation's loop iterations (Mesa's llvmpipe: 65535) a large n
 * writes fewer passes and the canary sets *watchdog; below the cap, and on other drivers, neither happens. */
#include "shared/stex_platform.h"

__kernel void watchdog_probe(const int n, __global int* passes, STEX_WATCHDOG_ARGS) {
  int count = 0;
  uint h = (uint)get_global_id(0);
  for (int i = 0; i < n; ++i) {
    h = h * 747796405u + 2891336453u; /* a recurrence no compiler folds: the loop stays a loop */
    ++count;
  }
  passes[get_global_id(0)] = count + (int)(h & 0u);
  STEX_WATCHDOG_CHECK();
}
