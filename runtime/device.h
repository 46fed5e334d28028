// OpenCL device discovery and selection (--device / STEX_DEVICE): "cpu", "gpu", an index into the list of
// all devices of all platforms, or a case-insensitive substring of the device name (or platform name).
// Default (empty spec): the first GPU, else the first CPU device, else the first device.
#pragma once
#include <CL/cl.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace stex {

struct DeviceInfo {
  int index = -1;  // position in list_devices()
  cl_platform_id platform = nullptr;
  cl_device_id id = nullptr;
  std::string name, vendor, version, driver_version, opencl_c_version;
  std::string platform_name, platform_version;
  cl_device_type type = 0;
  std::string type_name;  // "GPU", "CPU", "ACCELERATOR", "OTHER"
  cl_uint compute_units = 0;
  cl_uint native_float_width = 1;  // CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT (16 on AVX-512 CPUs under PoCL)
  std::uint64_t global_mem = 0, max_alloc = 0, local_mem = 0;
  std::size_t max_work_group_size = 0;
  std::array<std::size_t, 3> max_work_item_sizes{0, 0, 0};  // CL_DEVICE_MAX_WORK_ITEM_SIZES (first three)
  bool fp64 = false, image_support = false;
};

struct PlatformInfo {
  int index = -1;  // position in list_platforms()
  cl_platform_id id = nullptr;
  std::string name, vendor, version;
  std::vector<int> devices;  // indices into list_devices() of this platform's devices
  std::string error;         // why its devices could not be listed (the platform is then skipped), or ""
};

// All OpenCL platforms. Throws stex::Error(Device) with a clear message when there is none.
std::vector<PlatformInfo> list_platforms();

// The properties of one device (used for borrowed contexts too; `index` is left to the caller).
DeviceInfo query_device(cl_device_id id);

// One line per device, "  [index] TYPE name (platform)", as used in selection errors and `stex info`.
std::string describe_devices(const std::vector<DeviceInfo>& devices);

// All devices of all platforms, in platform order then device order. Throws stex::Error(Device) with a
// clear message when there is no OpenCL platform (CL_PLATFORM_NOT_FOUND_KHR: no ICD installed or
// OCL_ICD_VENDORS points at an empty directory) or no device at all.
std::vector<DeviceInfo> list_devices();

// The index (into `devices`) of the default device: the first GPU, else the first CPU, else 0.
int default_device_index(const std::vector<DeviceInfo>& devices);

// Selects by spec (see above). No match: stex::Error(Device) whose message lists every device with its
// index, type and name.
DeviceInfo select_device(const std::string& spec);
DeviceInfo select_device(const std::string& spec, const std::vector<DeviceInfo>& devices);

// Points PoCL's on-disk kernel cache at a per-user directory ($XDG_CACHE_HOME/stex/pocl, else
// ~/.cache/stex/pocl) unless POCL_CACHE_DIR is already set. The `stex` CLI calls it first thing in main();
// the library never does on its own (it would change an embedding application's environment, and setenv is
// not safe against other threads' getenv).
void configure_kernel_cache();

}  // namespace stex
