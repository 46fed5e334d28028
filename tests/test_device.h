// The OpenCL device of the device tests (issue 27): STEX_TEST_DEVICE=<index|name|cpu|gpu> selects it, with
// the syntax of --device (runtime/device.h select_device); unset or empty = the default device (the first
// GPU, else the first CPU: PoCL here). Every test binary links tests/test_main.cpp, which resolves the spec
// once at start, prints "stex tests: device [index] NAME (PLATFORM)", fails the binary when an explicit
// spec matches no device (it never falls back to another device), and exports the spec as STEX_DEVICE, so
// the `stex` subprocesses of the CLI tests run on the same device.
//   - in-process tests: Context::create(test_device_spec()), stex_context_create(test_device_spec().c_str())
//   - tests that only hold on PoCL (POCL_DEVICES, POCL_MEMORY_LIMIT): STEX_SKIP_UNLESS_POCL("why")
#pragma once
#include <CL/cl.h>
#include <gtest/gtest.h>

#include <string>

namespace stex::test {

// $STEX_TEST_DEVICE, or "" (the default device).
std::string test_device_spec();

// The device the spec selects, resolved once per process in a forked child, so that the test process itself
// does not start an OpenCL runtime before its tests do (tests/hardening sets POCL_MEMORY_LIMIT in forked
// children before PoCL initialises). `error` is set (and the rest empty) when nothing matches.
struct TestDevice {
  std::string spec;      // the spec resolved
  int index = -1;        // in the list of all devices (`stex info`)
  std::string name;      // CL_DEVICE_NAME
  std::string platform;  // CL_PLATFORM_NAME
  std::string error;     // select_device's message, or why the probe failed
};
const TestDevice& test_device();

// "[index] NAME (PLATFORM)", or "none (<error>)".
std::string describe_test_device();

// True when the test device is on PoCL's platform ("Portable Computing Language").
bool test_device_is_pocl();

// The test device's OpenCL platform and device ids, selected in this process (for tests that create their
// own OpenCL objects). Throws what select_device throws.
void test_device_cl(cl_platform_id* platform, cl_device_id* device);

// For main(): resolves the device, prints the line, exports STEX_DEVICE. Returns false (after printing why)
// when STEX_TEST_DEVICE is set and selects no device.
bool init_test_device();

}  // namespace stex::test

// Skips a test that only applies to PoCL's device (e.g. it sets POCL_DEVICES or POCL_MEMORY_LIMIT), naming
// the test device it skips on.
#define STEX_SKIP_UNLESS_POCL(why)                                                   \
  do {                                                                               \
    if (!::stex::test::test_device_is_pocl())                                        \
      GTEST_SKIP() << (why) << ": PoCL only; the test device (STEX_TEST_DEVICE) is " \
                   << ::stex::test::describe_test_device();                          \
  } while (0)
