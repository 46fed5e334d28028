// The self-test part of `stex serve`'s /api/health (docs/serve.md): for every row of `stex selftest` on the
// service's device, what this process met (its renders check their path before the first render:
// runtime/selftest.h) or, failing that, what the self-test cache holds from earlier runs on this device, else
// "untested"; rows of other paths the process checked follow.
#pragma once
#include <nlohmann/json.hpp>

#include "runtime/device.h"

namespace stex::service {

// {"status": "pass" (every row passed) | "fail" (a row failed) | "partial" (no failure, some untested),
//  "passed", "failed", "untested", "cache", "rows": [{"kind", "path", "state": "pass"|"fail"|"untested",
//  "source": "this process"|"cache"|"", "expected", "actual", "error"}]}
nlohmann::json selftest_health(const DeviceInfo& device);

}  // namespace stex::service
