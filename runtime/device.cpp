// OpenCL platform and device discovery, device selection (--device / STEX_DEVICE), and the location of
// PoCL's on-disk kernel cache. See device.h for the selection rules.
#include "runtime/device.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <sstream>
#include <system_error>

#include "core/error.h"
#include "runtime/cl_error.h"

namespace stex {

namespace {

constexpr cl_int k_platform_not_found_khr = -1001;

std::string platform_string(cl_platform_id id, cl_platform_info param) {
  std::size_t size = 0;
  cl_check(clGetPlatformInfo(id, param, 0, nullptr, &size), "clGetPlatformInfo");
  std::string s(size, '\0');
  if (size) cl_check(clGetPlatformInfo(id, param, size, s.data(), nullptr), "clGetPlatformInfo");
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

std::string device_string(cl_device_id id, cl_device_info param) {
  std::size_t size = 0;
  cl_check(clGetDeviceInfo(id, param, 0, nullptr, &size), "clGetDeviceInfo");
  std::string s(size, '\0');
  if (size) cl_check(clGetDeviceInfo(id, param, size, s.data(), nullptr), "clGetDeviceInfo");
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

template <class T>
T device_value(cl_device_id id, cl_device_info param) {
  T value{};
  cl_check(clGetDeviceInfo(id, param, sizeof(T), &value, nullptr), "clGetDeviceInfo");
  return value;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

std::string trim(const std::string& s) {
  std::size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  std::size_t e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::string type_name(cl_device_type type) {
  if (type & CL_DEVICE_TYPE_GPU) return "GPU";
  if (type & CL_DEVICE_TYPE_CPU) return "CPU";
  if (type & CL_DEVICE_TYPE_ACCELERATOR) return "ACCELERATOR";
  return "OTHER";
}

const char* k_no_platform_message =
    "no OpenCL platform found (clGetPlatformIDs: CL_PLATFORM_NOT_FOUND_KHR): no OpenCL driver (ICD) is "
    "installed or visible. Install one (on Debian: apt-get install pocl-opencl-icd for the CPU, or your "
    "GPU vendor's OpenCL driver) and check OCL_ICD_VENDORS if it is set";

// Platforms and their devices, in one consistent order.
void enumerate(std::vector<PlatformInfo>* platforms, std::vector<DeviceInfo>* devices) {
  cl_uint count = 0;
  cl_int err = clGetPlatformIDs(0, nullptr, &count);
  if (err == k_platform_not_found_khr || (err == CL_SUCCESS && count == 0))
    throw Error(ErrorKind::Device, k_no_platform_message);
  if (err != CL_SUCCESS) throw OpenCLError("clGetPlatformIDs", err, "cannot list OpenCL platforms");
  std::vector<cl_platform_id> ids(count);
  cl_check(clGetPlatformIDs(count, ids.data(), nullptr), "clGetPlatformIDs");

  for (cl_uint p = 0; p < count; ++p) {
    PlatformInfo pi;
    pi.index = int(p);
    pi.id = ids[p];
    pi.name = platform_string(ids[p], CL_PLATFORM_NAME);
    pi.vendor = platform_string(ids[p], CL_PLATFORM_VENDOR);
    pi.version = platform_string(ids[p], CL_PLATFORM_VERSION);

    // A platform whose devices cannot be listed (a broken or half-installed vendor driver) must not hide
    // the others: it is skipped and the reason kept for `stex info`.
    cl_uint n = 0;
    err = clGetDeviceIDs(ids[p], CL_DEVICE_TYPE_ALL, 0, nullptr, &n);
    std::vector<cl_device_id> dev_ids;
    if (err == CL_SUCCESS && n > 0) {
      dev_ids.resize(n);
      err = clGetDeviceIDs(ids[p], CL_DEVICE_TYPE_ALL, n, dev_ids.data(), nullptr);
    }
    if (err != CL_SUCCESS) {
      if (err != CL_DEVICE_NOT_FOUND)
        pi.error =
            OpenCLError("clGetDeviceIDs", err, "listing the devices of platform '" + pi.name + "'").what();
      dev_ids.clear();
    }
    for (cl_device_id d : dev_ids) {
      DeviceInfo info = query_device(d);
      info.index = int(devices->size());
      pi.devices.push_back(info.index);
      devices->push_back(std::move(info));
    }
    platforms->push_back(std::move(pi));
  }
}

}  // namespace

DeviceInfo query_device(cl_device_id id) {
  DeviceInfo info;
  info.id = id;
  info.platform = device_value<cl_platform_id>(id, CL_DEVICE_PLATFORM);
  info.name = trim(device_string(id, CL_DEVICE_NAME));
  info.vendor = trim(device_string(id, CL_DEVICE_VENDOR));
  info.version = trim(device_string(id, CL_DEVICE_VERSION));
  info.driver_version = trim(device_string(id, CL_DRIVER_VERSION));
  info.opencl_c_version = trim(device_string(id, CL_DEVICE_OPENCL_C_VERSION));
  info.platform_name = trim(platform_string(info.platform, CL_PLATFORM_NAME));
  info.platform_version = trim(platform_string(info.platform, CL_PLATFORM_VERSION));
  info.type = device_value<cl_device_type>(id, CL_DEVICE_TYPE);
  info.type_name = type_name(info.type);
  info.compute_units = device_value<cl_uint>(id, CL_DEVICE_MAX_COMPUTE_UNITS);
  info.native_float_width = device_value<cl_uint>(id, CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT);
  info.global_mem = device_value<cl_ulong>(id, CL_DEVICE_GLOBAL_MEM_SIZE);
  info.max_alloc = device_value<cl_ulong>(id, CL_DEVICE_MAX_MEM_ALLOC_SIZE);
  info.local_mem = device_value<cl_ulong>(id, CL_DEVICE_LOCAL_MEM_SIZE);
  info.max_work_group_size = device_value<std::size_t>(id, CL_DEVICE_MAX_WORK_GROUP_SIZE);
  {
    // CL_DEVICE_MAX_WORK_ITEM_SIZES has CL_DEVICE_MAX_WORK_ITEM_DIMENSIONS (>= 3) entries.
    const cl_uint dims = device_value<cl_uint>(id, CL_DEVICE_MAX_WORK_ITEM_DIMENSIONS);
    std::vector<std::size_t> sizes(std::max<cl_uint>(dims, 3), 0);
    if (clGetDeviceInfo(id, CL_DEVICE_MAX_WORK_ITEM_SIZES, sizes.size() * sizeof(std::size_t), sizes.data(),
                        nullptr) == CL_SUCCESS)
      for (std::size_t d = 0; d < 3; ++d) info.max_work_item_sizes[d] = sizes[d];
  }
  // CL_DEVICE_DOUBLE_FP_CONFIG is non-zero exactly when the device supports double (OpenCL 1.2 §4.2).
  info.fp64 = device_value<cl_device_fp_config>(id, CL_DEVICE_DOUBLE_FP_CONFIG) != 0;
  info.image_support = device_value<cl_bool>(id, CL_DEVICE_IMAGE_SUPPORT) != CL_FALSE;
  return info;
}

std::vector<PlatformInfo> list_platforms() {
  std::vector<PlatformInfo> platforms;
  std::vector<DeviceInfo> devices;
  enumerate(&platforms, &devices);
  return platforms;
}

std::vector<DeviceInfo> list_devices() {
  std::vector<PlatformInfo> platforms;
  std::vector<DeviceInfo> devices;
  enumerate(&platforms, &devices);
  if (devices.empty()) {
    std::ostringstream os;
    os << "no OpenCL device found: " << platforms.size() << " platform(s) (";
    for (std::size_t i = 0; i < platforms.size(); ++i)
      os << (i ? ", " : "") << "'" << platforms[i].name << "'";
    os << ") expose no device";
    for (const PlatformInfo& p : platforms)
      if (!p.error.empty()) os << "; " << p.error;
    throw Error(ErrorKind::Device, os.str());
  }
  return devices;
}

int default_device_index(const std::vector<DeviceInfo>& devices) {
  for (std::size_t i = 0; i < devices.size(); ++i)
    if (devices[i].type & CL_DEVICE_TYPE_GPU) return int(i);
  for (std::size_t i = 0; i < devices.size(); ++i)
    if (devices[i].type & CL_DEVICE_TYPE_CPU) return int(i);
  return 0;
}

std::string describe_devices(const std::vector<DeviceInfo>& devices) {
  std::ostringstream os;
  for (std::size_t i = 0; i < devices.size(); ++i) {
    const DeviceInfo& d = devices[i];
    os << "  [" << i << "] " << d.type_name << " " << d.name << " (" << d.platform_name << ")";
    if (i + 1 < devices.size()) os << "\n";
  }
  return os.str();
}

DeviceInfo select_device(const std::string& spec) { return select_device(spec, list_devices()); }

DeviceInfo select_device(const std::string& spec_in, const std::vector<DeviceInfo>& devices) {
  if (devices.empty()) throw Error(ErrorKind::Device, "no OpenCL device found");
  // Positions in `devices` are the indices users see (describe_devices, stex info).
  auto pick = [&](std::size_t i) {
    DeviceInfo d = devices[i];
    d.index = int(i);
    return d;
  };
  const std::string spec = lower(trim(spec_in));
  auto no_match = [&](const std::string& why) {
    return Error(ErrorKind::Device, "no OpenCL device matches --device/STEX_DEVICE '" + spec_in + "' (" +
                                        why + "); available devices:\n" + describe_devices(devices));
  };
  if (spec.empty()) return pick(std::size_t(default_device_index(devices)));
  if (spec == "gpu" || spec == "cpu" || spec == "accelerator") {
    cl_device_type want = spec == "gpu"   ? CL_DEVICE_TYPE_GPU
                          : spec == "cpu" ? CL_DEVICE_TYPE_CPU
                                          : CL_DEVICE_TYPE_ACCELERATOR;
    for (std::size_t i = 0; i < devices.size(); ++i)
      if (devices[i].type & want) return pick(i);
    throw no_match("there is no " +
                   std::string(spec == "accelerator" ? "accelerator"
                               : spec == "gpu"       ? "GPU"
                                                     : "CPU") +
                   " device");
  }
  if (std::all_of(spec.begin(), spec.end(), [](unsigned char c) { return std::isdigit(c); })) {
    // An index; longer than 9 digits cannot be valid and would overflow stoul on 32-bit longs.
    if (spec.size() > 9) throw no_match("index out of range");
    std::size_t i = std::stoul(spec);
    if (i >= devices.size())
      throw no_match("index " + spec + " is out of range: " + std::to_string(devices.size()) + " device(s)");
    return pick(i);
  }
  for (std::size_t i = 0; i < devices.size(); ++i)
    if (lower(devices[i].name).find(spec) != std::string::npos) return pick(i);
  for (std::size_t i = 0; i < devices.size(); ++i)
    if (lower(devices[i].platform_name).find(spec) != std::string::npos) return pick(i);
  throw no_match("not a type (cpu, gpu), an index, or a substring of a device or platform name");
}

void configure_kernel_cache() {
  static std::once_flag once;
  std::call_once(once, [] {
    const char* existing = std::getenv("POCL_CACHE_DIR");
    if (existing && *existing) return;
    std::filesystem::path dir;
    const char* xdg = std::getenv("XDG_CACHE_HOME");
    const char* home = std::getenv("HOME");
    if (xdg && *xdg)
      dir = std::filesystem::path(xdg) / "stex" / "pocl";
    else if (home && *home)
      dir = std::filesystem::path(home) / ".cache" / "stex" / "pocl";
    else
      return;  // nowhere sensible: leave PoCL's own default
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) return;  // an unwritable cache only costs compile time; PoCL falls back to its default
    setenv("POCL_CACHE_DIR", dir.c_str(), 0);
  });
}

}  // namespace stex
