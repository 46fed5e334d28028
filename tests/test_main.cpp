// main() of every test binary (tests/CMakeLists.txt, tests/embed): GoogleTest on the device STEX_TEST_DEVICE
// selects (test_device.h). An explicit STEX_TEST_DEVICE that matches no device fails the binary (exit 1)
// before any test runs.
#include <gtest/gtest.h>

#include "test_device.h"

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  if (!stex::test::init_test_device()) return 1;
  return RUN_ALL_TESTS();
}
