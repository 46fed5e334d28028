// Tests of runtime/device (discovery, selection by type, index and name, errors that list the devices) and
// runtime/cl_error (error names and kinds). Selection rules are also checked on synthetic device lists, so
// the GPU-first default is tested on a machine without a GPU.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/error.h"
#include "runtime/cl_error.h"
#include "runtime/device.h"

namespace stex {
namespace {

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::toupper(c)); });
  return s;
}

DeviceInfo fake(const std::string& name, cl_device_type type, const std::string& platform = "Fake Platform") {
  DeviceInfo d;
  d.name = name;
  d.type = type;
  d.type_name = type == CL_DEVICE_TYPE_GPU ? "GPU" : type == CL_DEVICE_TYPE_CPU ? "CPU" : "ACCELERATOR";
  d.platform_name = platform;
  return d;
}

// Expects select_device(spec, devices) to fail with a Device error that lists every device.
void expect_no_match(const std::string& spec, const std::vector<DeviceInfo>& devices) {
  try {
    DeviceInfo d = select_device(spec, devices);
    FAIL() << "'" << spec << "' selected " << d.name;
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Device);
    const std::string msg = e.what();
    EXPECT_NE(msg.find("'" + spec + "'"), std::string::npos) << msg;
    for (std::size_t i = 0; i < devices.size(); ++i)
      EXPECT_NE(msg.find("[" + std::to_string(i) + "] " + devices[i].type_name + " " + devices[i].name),
                std::string::npos)
          << msg;
  }
}

TEST(Devices, ListIsConsistentWithPlatforms) {
  std::vector<DeviceInfo> devices = list_devices();
  ASSERT_FALSE(devices.empty());
  std::vector<PlatformInfo> platforms = list_platforms();
  ASSERT_FALSE(platforms.empty());
  std::size_t listed = 0;
  for (const PlatformInfo& p : platforms) {
    EXPECT_FALSE(p.name.empty());
    for (int i : p.devices) {
      ASSERT_GE(i, 0);
      ASSERT_LT(std::size_t(i), devices.size());
      EXPECT_EQ(devices[i].platform, p.id);
      EXPECT_EQ(devices[i].platform_name, p.name);
      ++listed;
    }
  }
  EXPECT_EQ(listed, devices.size());
  for (std::size_t i = 0; i < devices.size(); ++i) {
    const DeviceInfo& d = devices[i];
    EXPECT_EQ(d.index, int(i));
    EXPECT_FALSE(d.name.empty());
    EXPECT_GT(d.compute_units, 0u);
    EXPECT_GT(d.global_mem, 0u);
    EXPECT_GT(d.max_alloc, 0u);
    EXPECT_LE(d.max_alloc, d.global_mem);
    EXPECT_GT(d.max_work_group_size, 0u);
    EXPECT_EQ(d.opencl_c_version.rfind("OpenCL C ", 0), 0u) << d.opencl_c_version;
    EXPECT_TRUE(d.type_name == "GPU" || d.type_name == "CPU" || d.type_name == "ACCELERATOR" ||
                d.type_name == "OTHER");
  }
}

TEST(Devices, SelectByTypeIndexAndNameSubstring) {
  std::vector<DeviceInfo> devices = list_devices();
  ASSERT_FALSE(devices.empty());

  auto cpu = std::find_if(devices.begin(), devices.end(),
                          [](const DeviceInfo& d) { return (d.type & CL_DEVICE_TYPE_CPU) != 0; });
  if (cpu != devices.end()) {
    DeviceInfo d = select_device("cpu");
    EXPECT_EQ(d.index, cpu->index);
    EXPECT_EQ(d.id, cpu->id);
    EXPECT_EQ(select_device(" CPU ").id, cpu->id) << "case and surrounding blanks do not matter";
  }
  for (std::size_t i = 0; i < devices.size(); ++i) {
    DeviceInfo d = select_device(std::to_string(i));
    EXPECT_EQ(d.index, int(i));
    EXPECT_EQ(d.id, devices[i].id);
  }
  // A case-insensitive substring from the middle of the last device's name selects the first device whose
  // name contains it.
  const std::string& name = devices.back().name;
  ASSERT_GE(name.size(), 3u);
  const std::string sub = upper(name.substr(name.size() / 3, std::max<std::size_t>(3, name.size() / 3)));
  DeviceInfo by_name = select_device(sub);
  EXPECT_NE(upper(by_name.name).find(sub), std::string::npos);
  EXPECT_LE(by_name.index, devices.back().index);
  // The platform name works too when no device name contains it.
  DeviceInfo by_platform = select_device(devices.front().platform_name);
  EXPECT_EQ(by_platform.platform, devices.front().platform);
}

TEST(Devices, DefaultIsFirstGpuElseFirstCpu) {
  std::vector<DeviceInfo> devices = list_devices();
  const int def = default_device_index(devices);
  EXPECT_EQ(select_device("").id, devices[def].id);
  EXPECT_EQ(select_device("").index, def);
  bool any_gpu = false;
  for (const DeviceInfo& d : devices) any_gpu |= (d.type & CL_DEVICE_TYPE_GPU) != 0;
  if (any_gpu)
    EXPECT_NE(devices[def].type & CL_DEVICE_TYPE_GPU, 0u);
  else
    EXPECT_NE(devices[def].type & CL_DEVICE_TYPE_CPU, 0u) << "PoCL's CPU device is the default without a GPU";

  // The rule itself, on synthetic lists.
  std::vector<DeviceInfo> cpu_gpu{fake("cpu0", CL_DEVICE_TYPE_CPU), fake("acc", CL_DEVICE_TYPE_ACCELERATOR),
                                  fake("gpu0", CL_DEVICE_TYPE_GPU), fake("gpu1", CL_DEVICE_TYPE_GPU)};
  EXPECT_EQ(default_device_index(cpu_gpu), 2);
  EXPECT_EQ(select_device("", cpu_gpu).name, "gpu0");
  EXPECT_EQ(select_device("", cpu_gpu).index, 2);
  std::vector<DeviceInfo> acc_cpu{fake("acc", CL_DEVICE_TYPE_ACCELERATOR), fake("cpu0", CL_DEVICE_TYPE_CPU),
                                  fake("cpu1", CL_DEVICE_TYPE_CPU)};
  EXPECT_EQ(default_device_index(acc_cpu), 1);
  std::vector<DeviceInfo> acc_only{fake("acc", CL_DEVICE_TYPE_ACCELERATOR)};
  EXPECT_EQ(default_device_index(acc_only), 0);

  EXPECT_EQ(select_device("gpu", cpu_gpu).name, "gpu0");
  EXPECT_EQ(select_device("cpu", cpu_gpu).name, "cpu0");
  EXPECT_EQ(select_device("accelerator", cpu_gpu).name, "acc");
  EXPECT_EQ(select_device("3", cpu_gpu).name, "gpu1");
  EXPECT_EQ(select_device("GPU1", cpu_gpu).name, "gpu1");
  EXPECT_EQ(select_device("fake plat", cpu_gpu).name, "cpu0");
}

TEST(Devices, BadSelectionListsTheDevices) {
  std::vector<DeviceInfo> devices = list_devices();
  bool any_gpu = false;
  for (const DeviceInfo& d : devices) any_gpu |= (d.type & CL_DEVICE_TYPE_GPU) != 0;
  if (!any_gpu) expect_no_match("gpu", devices);
  expect_no_match("99", devices);
  expect_no_match("99999999999999999999", devices);
  expect_no_match("nosuchdevice", devices);
  // The one-argument form queries the real devices and fails the same way.
  EXPECT_THROW(select_device("nosuchdevice"), Error);

  std::vector<DeviceInfo> cpus{fake("cpu0", CL_DEVICE_TYPE_CPU), fake("cpu1", CL_DEVICE_TYPE_CPU)};
  expect_no_match("gpu", cpus);
  expect_no_match("2", cpus);
  expect_no_match("-1", cpus);
  EXPECT_THROW(select_device("", std::vector<DeviceInfo>{}), Error);
}

TEST(Devices, KernelCacheDirectoryIsLeftAloneWhenSet) {
  // ctest sets POCL_CACHE_DIR for each test binary: configure_kernel_cache() must not override it. (The unset
  // case runs in a subprocess: see test_cli_info.cpp.)
  const char* before = std::getenv("POCL_CACHE_DIR");
  if (!before) GTEST_SKIP() << "POCL_CACHE_DIR is not set in this environment";
  const std::string saved = before;
  configure_kernel_cache();
  ASSERT_NE(std::getenv("POCL_CACHE_DIR"), nullptr);
  EXPECT_EQ(std::string(std::getenv("POCL_CACHE_DIR")), saved);
}

TEST(ClError, NamesAndKinds) {
  EXPECT_EQ(cl_error_name(CL_SUCCESS), "CL_SUCCESS");
  EXPECT_EQ(cl_error_name(CL_INVALID_VALUE), "CL_INVALID_VALUE");
  EXPECT_EQ(cl_error_name(CL_OUT_OF_RESOURCES), "CL_OUT_OF_RESOURCES");
  EXPECT_EQ(cl_error_name(CL_BUILD_PROGRAM_FAILURE), "CL_BUILD_PROGRAM_FAILURE");
  EXPECT_EQ(cl_error_name(CL_INVALID_DEVICE_PARTITION_COUNT), "CL_INVALID_DEVICE_PARTITION_COUNT");
  EXPECT_EQ(cl_error_name(-1001), "CL_PLATFORM_NOT_FOUND_KHR");
  EXPECT_EQ(cl_error_name(-12345), "CL_UNKNOWN_ERROR(-12345)");
  // Every OpenCL 1.2 code has a name (0 .. -19 and -30 .. -68).
  for (cl_int c = 0; c >= -68; --c) {
    if (c < -19 && c > -30) {
      EXPECT_EQ(cl_error_name(c).rfind("CL_UNKNOWN_ERROR", 0), 0u) << c;
      continue;
    }
    EXPECT_EQ(cl_error_name(c).rfind("CL_UNKNOWN_ERROR", 0), std::string::npos) << c;
  }

  EXPECT_EQ(cl_error_kind(CL_OUT_OF_RESOURCES), ErrorKind::Retryable);
  EXPECT_EQ(cl_error_kind(CL_MEM_OBJECT_ALLOCATION_FAILURE), ErrorKind::Retryable);
  EXPECT_EQ(cl_error_kind(CL_OUT_OF_HOST_MEMORY), ErrorKind::Retryable);
  EXPECT_EQ(cl_error_kind(-1001), ErrorKind::Device);
  EXPECT_EQ(cl_error_kind(CL_DEVICE_NOT_FOUND), ErrorKind::Device);
  EXPECT_EQ(cl_error_kind(CL_BUILD_PROGRAM_FAILURE), ErrorKind::Device);
  EXPECT_EQ(cl_error_kind(CL_INVALID_VALUE), ErrorKind::Internal);
  EXPECT_EQ(cl_error_kind(CL_INVALID_KERNEL_ARGS), ErrorKind::Internal);

  OpenCLError e("clCreateBuffer", CL_INVALID_BUFFER_SIZE, "image tile");
  EXPECT_STREQ(e.what(), "clCreateBuffer failed: CL_INVALID_BUFFER_SIZE (-61): image tile");
  EXPECT_EQ(e.code(), CL_INVALID_BUFFER_SIZE);
  EXPECT_EQ(e.call(), "clCreateBuffer");
  EXPECT_EQ(e.kind(), ErrorKind::Internal);
  EXPECT_EQ(e.exit_code(), 1);
  EXPECT_STREQ(OpenCLError("clFinish", CL_OUT_OF_RESOURCES).what(),
               "clFinish failed: CL_OUT_OF_RESOURCES (-5)");
  EXPECT_EQ(OpenCLError("clFinish", CL_OUT_OF_RESOURCES).exit_code(), 75);

  EXPECT_NO_THROW(cl_check(CL_SUCCESS, "clFlush"));
  try {
    cl_check(CL_INVALID_COMMAND_QUEUE, "clFlush");
    FAIL();
  } catch (const OpenCLError& err) {
    EXPECT_EQ(err.code(), CL_INVALID_COMMAND_QUEUE);
    EXPECT_NE(std::string(err.what()).find("clFlush failed: CL_INVALID_COMMAND_QUEUE"), std::string::npos);
  }
}

}  // namespace
}  // namespace stex
