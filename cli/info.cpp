// `stex info [--json]`: the OpenCL platforms and devices stex can see, their limits, the device stex picks by
// default (first GPU, else first CPU), and the one --device / STEX_DEVICE selects when given. A thin client
// of runtime/device. Without any platform it fails with ErrorKind::Device (exit code 4) and a clear message.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "core/error.h"
#include "runtime/device.h"

namespace stex::cli {

namespace {

std::string human_bytes(std::uint64_t bytes) {
  char buf[64];
  const double mib = double(bytes) / (1024.0 * 1024.0);
  if (mib >= 1024.0)
    std::snprintf(buf, sizeof buf, "%.1f GiB", mib / 1024.0);
  else if (mib >= 1.0)
    std::snprintf(buf, sizeof buf, "%.1f MiB", mib);
  else  // local memory: 32 KiB printed as "0.0 MiB" read as none (docs/portability.md, root cause 4)
    std::snprintf(buf, sizeof buf, "%.1f KiB", double(bytes) / 1024.0);
  return buf;
}

nlohmann::ordered_json device_json(const DeviceInfo& d, int platform_index) {
  return {{"index", d.index},
          {"platform", platform_index},
          {"name", d.name},
          {"vendor", d.vendor},
          {"type", d.type_name},
          {"version", d.version},
          {"driver_version", d.driver_version},
          {"opencl_c_version", d.opencl_c_version},
          {"compute_units", d.compute_units},
          {"global_mem_bytes", d.global_mem},
          {"max_alloc_bytes", d.max_alloc},
          {"local_mem_bytes", d.local_mem},
          {"max_work_group_size", d.max_work_group_size},
          {"fp64", d.fp64},
          {"image_support", d.image_support}};
}

void run_info(const GlobalOptions& global, bool json) {
  // Platforms first: with none, this throws the "no OpenCL platform" Device error.
  const std::vector<PlatformInfo> platforms = list_platforms();
  const std::vector<DeviceInfo> devices = list_devices();
  const int default_index = default_device_index(devices);
  const bool has_spec = !global.device.empty();
  // Throws a Device error listing the devices when the spec matches none.
  const DeviceInfo selected = select_device(global.device, devices);
  const char* cache = std::getenv("POCL_CACHE_DIR");

  std::vector<int> platform_of(devices.size(), -1);
  for (const PlatformInfo& p : platforms)
    for (int i : p.devices) platform_of[std::size_t(i)] = p.index;

  if (json) {
    nlohmann::ordered_json out;
    out["platforms"] = nlohmann::ordered_json::array();
    for (const PlatformInfo& p : platforms)
      out["platforms"].push_back(
          {{"index", p.index},
           {"name", p.name},
           {"vendor", p.vendor},
           {"version", p.version},
           {"devices", p.devices},
           {"error", p.error.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(p.error)}});
    out["devices"] = nlohmann::ordered_json::array();
    for (const DeviceInfo& d : devices)
      out["devices"].push_back(device_json(d, platform_of[std::size_t(d.index)]));
    out["default_device"] = default_index;
    out["device_spec"] = has_spec ? nlohmann::ordered_json(global.device) : nlohmann::ordered_json(nullptr);
    out["selected_device"] = selected.index;
    out["kernel_cache_dir"] = cache ? nlohmann::ordered_json(cache) : nlohmann::ordered_json(nullptr);
    std::cout << out.dump(2) << "\n";
    return;
  }

  std::cout << "OpenCL platforms: " << platforms.size() << "\n";
  for (const PlatformInfo& p : platforms) {
    std::cout << "platform " << p.index << ": " << p.name << " (" << p.vendor << ", " << p.version << ")\n";
    if (!p.error.empty())
      std::cout << "  (skipped: " << p.error << ")\n";
    else if (p.devices.empty())
      std::cout << "  (no devices)\n";
    for (int i : p.devices) {
      const DeviceInfo& d = devices[std::size_t(i)];
      std::cout << "  [" << d.index << "] " << d.type_name << " " << d.name;
      if (d.index == default_index) std::cout << "  (default)";
      if (has_spec && d.index == selected.index)
        std::cout << "  (selected by --device " << global.device << ")";
      std::cout << "\n"
                << "      vendor " << d.vendor << ", " << d.version << ", driver " << d.driver_version << ", "
                << d.opencl_c_version << "\n"
                << "      compute units " << d.compute_units << ", global memory "
                << human_bytes(d.global_mem) << ", max allocation " << human_bytes(d.max_alloc)
                << ", local memory " << human_bytes(d.local_mem) << ", max work-group "
                << d.max_work_group_size << "\n"
                << "      fp64 " << (d.fp64 ? "yes" : "no") << ", images " << (d.image_support ? "yes" : "no")
                << "\n";
    }
  }
  const DeviceInfo& def = devices[std::size_t(default_index)];
  std::cout << "default device: [" << def.index << "] " << def.name << "\n";
  if (has_spec)
    std::cout << "selected device (--device/STEX_DEVICE '" << global.device << "'): [" << selected.index
              << "] " << selected.name << "\n";
  std::cout << "kernel cache: " << (cache ? cache : "(PoCL default)") << "\n";
}

}  // namespace

void add_info(CLI::App& app, GlobalOptions& global) {
  auto* sub = app.add_subcommand("info", "List OpenCL platforms and devices and the device stex uses");
  auto json = std::make_shared<bool>(false);
  sub->add_flag("--json", *json, "Print machine-readable JSON");
  sub->callback([&global, json] { run_info(global, *json); });
}

}  // namespace stex::cli
