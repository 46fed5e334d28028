// STEX_TEST_DEVICE (tests/test_device.h, issue 27): the device tests run on the device it selects, in process
// (Context::create(test_device_spec())) and in the `stex` subprocesses (STEX_DEVICE exported by the test
// main); the binary prints the device at start; a spec that matches no device fails the binary before any
// test runs instead of falling back to another device. The last two run this test binary again as a child.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_run.h"
#include "runtime/context.h"
#include "runtime/device.h"
#include "test_device.h"

namespace stex::test {
namespace {

namespace fs = std::filesystem;

// Runs `env <env_args> <program> <args>` (env operands: `-u VAR`, `VAR=value`); stdout and stderr apart.
CliRun run_env(const std::string& env_args, const std::string& program, const std::string& args,
               const std::string& scratch) {
  return run_program(program, args, scratch, "", "env " + env_args);
}

// This test binary again, with a gtest filter.
CliRun run_self(const std::string& env_args, const std::string& filter, const std::string& scratch) {
  return run_env(env_args, fs::read_symlink("/proc/self/exe").string(),
                 "--gtest_color=no --gtest_filter='" + filter + "'", scratch);
}

std::string first_line(const std::string& s) { return s.substr(0, s.find('\n')); }

TEST(TestDevice, ContextsAreOnTheDeviceTheSpecSelects) {
  const TestDevice& d = test_device();
  ASSERT_TRUE(d.error.empty()) << d.error;
  EXPECT_EQ(d.spec, test_device_spec());
  const DeviceInfo expected = select_device(test_device_spec());
  EXPECT_EQ(d.index, expected.index);
  EXPECT_EQ(d.name, expected.name);
  EXPECT_EQ(d.platform, expected.platform_name);
  const std::unique_ptr<Context> ctx = Context::create(test_device_spec());
  EXPECT_EQ(ctx->info().id, expected.id);
  EXPECT_EQ(ctx->info().name, d.name);
  cl_platform_id platform = nullptr;
  cl_device_id device = nullptr;
  test_device_cl(&platform, &device);
  EXPECT_EQ(device, expected.id);
  EXPECT_EQ(platform, expected.platform);
  EXPECT_EQ(test_device_is_pocl(), expected.platform_name == "Portable Computing Language");
  EXPECT_EQ(describe_test_device(), "[" + std::to_string(expected.index) + "] " + expected.name + " (" +
                                        expected.platform_name + ")");
}

TEST(TestDevice, SubprocessesGetItAsStexDevice) {
  const char* exported = std::getenv("STEX_DEVICE");
  ASSERT_NE(exported, nullptr);
  EXPECT_EQ(std::string(exported), test_device_spec());
  // `stex` run as the CLI tests run it (inheriting the environment) selects the test device.
  const CliRun r = run_stex_cli("info --json", "test_device_info");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out).at("selected_device").get<int>(), test_device().index) << r.out;
}

TEST(TestDevice, PrintedAtStartAndSelectsLlvmpipeUnderRusticl) {
  // rusticl lists its llvmpipe device only under RUSTICL_ENABLE=llvmpipe (mesa-opencl-icd, install-deps.sh).
  const std::string env = "RUSTICL_ENABLE=llvmpipe STEX_TEST_DEVICE=llvmpipe";
  const CliRun info = run_env("RUSTICL_ENABLE=llvmpipe", STEX_CLI_PATH, "--device llvmpipe info --json",
                              "test_device_rusticl_info");
  if (info.code == 4) GTEST_SKIP() << "no rusticl llvmpipe device here (mesa-opencl-icd): " << info.err;
  ASSERT_EQ(info.code, 0) << info.err;
  const nlohmann::json j = nlohmann::json::parse(info.out);
  const int index = j.at("selected_device").get<int>();
  const std::string name = j.at("devices")[index].at("name").get<std::string>();
  ASSERT_NE(name.find("llvmpipe"), std::string::npos) << info.out;

  const CliRun child =
      run_self(env, "TestDevice.ContextsAreOnTheDeviceTheSpecSelects:TestDevice.SubprocessesGet*",
               "test_device_child_llvmpipe");
  EXPECT_EQ(child.code, 0) << child.out << child.err;
  EXPECT_EQ(first_line(child.out),
            "stex tests: device [" + std::to_string(index) + "] " + name + " (rusticl)")
      << child.out;
  EXPECT_NE(child.out.find("[  PASSED  ] 2 tests"), std::string::npos) << child.out;
}

TEST(TestDevice, UnknownSpecFailsTheBinaryBeforeAnyTest) {
  const CliRun child =
      run_self("STEX_TEST_DEVICE=no-such-device-xyz", "TestDevice.ContextsAreOnTheDeviceTheSpecSelects",
               "test_device_child_unknown");
  EXPECT_EQ(child.code, 1) << child.out << child.err;
  EXPECT_NE(
      child.err.find("stex tests: STEX_TEST_DEVICE='no-such-device-xyz' selects no device: no OpenCL device "
                     "matches --device/STEX_DEVICE 'no-such-device-xyz'"),
      std::string::npos)
      << child.err;
  EXPECT_NE(child.err.find("[0] "), std::string::npos) << "lists the devices: " << child.err;
  EXPECT_EQ(child.out.find("[ RUN"), std::string::npos) << "no test may run: " << child.out;
  EXPECT_EQ(child.out.find("stex tests: device"), std::string::npos) << child.out;

  // Unset and empty are the default device.
  const int def = default_device_index(list_devices());
  for (const char* env : {"-u STEX_TEST_DEVICE", "STEX_TEST_DEVICE="}) {
    const CliRun d =
        run_self(env, "TestDevice.ContextsAreOnTheDeviceTheSpecSelects", "test_device_child_default");
    EXPECT_EQ(d.code, 0) << env << d.out << d.err;
    EXPECT_EQ(first_line(d.out).rfind("stex tests: device [" + std::to_string(def) + "] ", 0), 0u)
        << env << d.out;
  }
}

}  // namespace
}  // namespace stex::test
