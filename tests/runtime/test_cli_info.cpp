// `stex info` and `stex demo-rng` run as subprocesses (the real binary, STEX_CLI_PATH): exit codes and
// messages without an OpenCL platform, the JSON listing and the default device, selection among several
// devices (PoCL's POCL_DEVICES gives two CPU devices), the default kernel cache directory, and the demo image
// against the C++ reference of the RNG on two devices.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "kernels/shared/rng.h"
#include "runtime/device.h"
#include "test_device.h"
#include "cli_run.h"

namespace stex {
namespace {

namespace fs = std::filesystem;

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

fs::path tmp_dir(const std::string& name) {
  const fs::path dir = fs::path(STEX_TEST_TMP_DIR) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Runs `env <env_args> stex <args>` through the shell; env_args are `env` operands (`-u VAR`, `VAR=value`).
RunResult run_stex(const std::string& env_args, const std::string& args) {
  const stex::test::CliRun c = stex::test::run_stex_cli(args, "subprocess", "", "env " + env_args);
  return {c.code, c.out, c.err};
}

TEST(CliInfo, NoPlatformIsADeviceErrorWithAClearMessage) {
  const fs::path empty = tmp_dir("empty_icd_vendors");
  for (const char* args : {"info", "info --json", "demo-rng -o x.png"}) {
    SCOPED_TRACE(args);
    RunResult r = run_stex("OCL_ICD_VENDORS='" + empty.string() + "'", args);
    EXPECT_EQ(r.exit_code, 4) << r.err;  // ErrorKind::Device, not a crash (a signal gives 128 + n)
    EXPECT_NE(r.err.find("no OpenCL platform found"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("pocl-opencl-icd"), std::string::npos) << "says how to fix it: " << r.err;
    EXPECT_EQ(r.out, "");
  }
}

TEST(CliInfo, JsonListsDevicesAndTheDefault) {
  RunResult r = run_stex("-u STEX_DEVICE", "info --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json j = nlohmann::json::parse(r.out);  // throws (fails the test) if it is not JSON
  const std::vector<DeviceInfo> devices = list_devices();
  ASSERT_EQ(j.at("devices").size(), devices.size());
  EXPECT_EQ(j.at("default_device").get<int>(), default_device_index(devices));
  EXPECT_EQ(j.at("selected_device").get<int>(), default_device_index(devices));
  EXPECT_TRUE(j.at("device_spec").is_null());
  ASSERT_GE(j.at("platforms").size(), 1u);
  for (std::size_t i = 0; i < devices.size(); ++i) {
    const auto& d = j.at("devices")[i];
    EXPECT_EQ(d.at("index").get<int>(), int(i));
    EXPECT_EQ(d.at("name").get<std::string>(), devices[i].name);
    EXPECT_EQ(d.at("type").get<std::string>(), devices[i].type_name);
    EXPECT_EQ(d.at("compute_units").get<unsigned>(), devices[i].compute_units);
    EXPECT_EQ(d.at("global_mem_bytes").get<std::uint64_t>(), devices[i].global_mem);
    EXPECT_EQ(d.at("max_alloc_bytes").get<std::uint64_t>(), devices[i].max_alloc);
    EXPECT_EQ(d.at("opencl_c_version").get<std::string>(), devices[i].opencl_c_version);
    EXPECT_EQ(d.at("fp64").get<bool>(), devices[i].fp64);
    EXPECT_EQ(d.at("image_support").get<bool>(), devices[i].image_support);
  }

  RunResult text = run_stex("-u STEX_DEVICE", "info");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  const int def = default_device_index(devices);
  EXPECT_NE(text.out.find("default device: [" + std::to_string(def) + "] " + devices[def].name),
            std::string::npos)
      << text.out;
  EXPECT_NE(text.out.find("compute units"), std::string::npos);
  EXPECT_NE(text.out.find("max allocation"), std::string::npos);
  EXPECT_NE(text.out.find(devices[def].opencl_c_version), std::string::npos);
}

TEST(CliInfo, SelectionAmongTwoDevicesAndBadSelection) {
  // PoCL exposes one device per entry of POCL_DEVICES: a "pthread" and a "basic" CPU device. The device list
  // must be PoCL's alone (another implementation, e.g. rusticl under RUSTICL_ENABLE, adds its devices).
  STEX_SKIP_UNLESS_POCL("selection among exactly PoCL's two POCL_DEVICES devices");
  const std::string two = "-u STEX_DEVICE POCL_DEVICES='pthread basic'";
  RunResult all = run_stex(two, "info --json");
  ASSERT_EQ(all.exit_code, 0) << all.err;
  nlohmann::json j = nlohmann::json::parse(all.out);
  ASSERT_EQ(j.at("devices").size(), 2u);
  int pthread_index = -1;
  for (const auto& d : j.at("devices"))
    if (d.at("name").get<std::string>().find("pthread") != std::string::npos)
      pthread_index = d.at("index").get<int>();
  ASSERT_GE(pthread_index, 0);

  for (const std::string& spec : {std::string("PTHREAD"), std::to_string(pthread_index)}) {
    RunResult by_flag = run_stex(two, "--device " + spec + " info --json");
    ASSERT_EQ(by_flag.exit_code, 0) << by_flag.err;
    nlohmann::json s = nlohmann::json::parse(by_flag.out);
    EXPECT_EQ(s.at("selected_device").get<int>(), pthread_index) << spec;
    EXPECT_EQ(s.at("device_spec").get<std::string>(), spec);
    EXPECT_EQ(s.at("default_device").get<int>(), 0) << "no GPU: the first CPU device";
  }
  // STEX_DEVICE works like --device.
  RunResult by_env =
      run_stex("POCL_DEVICES='pthread basic' STEX_DEVICE=" + std::to_string(pthread_index), "info");
  ASSERT_EQ(by_env.exit_code, 0) << by_env.err;
  EXPECT_NE(by_env.out.find("selected device (--device/STEX_DEVICE '" + std::to_string(pthread_index) +
                            "'): [" + std::to_string(pthread_index) + "]"),
            std::string::npos)
      << by_env.out;

  for (const char* bad : {"nosuchdevice", "gpu", "7"}) {
    RunResult r = run_stex(two, std::string("--device ") + bad + " info");
    EXPECT_EQ(r.exit_code, 4) << bad;
    EXPECT_NE(r.err.find("no OpenCL device matches"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("[0] CPU"), std::string::npos) << "lists the devices: " << r.err;
    EXPECT_NE(r.err.find("[1] CPU"), std::string::npos) << "lists the devices: " << r.err;
  }
}

TEST(CliInfo, KernelCacheDefaultsToTheUserCacheDirectory) {
  const fs::path xdg = tmp_dir("xdg_cache");
  RunResult r = run_stex("-u POCL_CACHE_DIR XDG_CACHE_HOME='" + xdg.string() + "'", "info --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path expected = xdg / "stex" / "pocl";
  EXPECT_EQ(nlohmann::json::parse(r.out).at("kernel_cache_dir").get<std::string>(), expected.string());
  EXPECT_TRUE(fs::is_directory(expected));

  const fs::path home = tmp_dir("home");
  r = run_stex("-u POCL_CACHE_DIR -u XDG_CACHE_HOME HOME='" + home.string() + "'", "info --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out).at("kernel_cache_dir").get<std::string>(),
            (home / ".cache" / "stex" / "pocl").string());
  EXPECT_TRUE(fs::is_directory(home / ".cache" / "stex" / "pocl"));

  // An explicit POCL_CACHE_DIR wins.
  r = run_stex("POCL_CACHE_DIR='" + (xdg / "mine").string() + "'", "info --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out).at("kernel_cache_dir").get<std::string>(), (xdg / "mine").string());
}

// The RGB8 picture rng_image draws: the top bytes of draw 0 (STEX_DOMAIN_TEST) of the pixel's cell.
std::vector<unsigned char> reference_rng_image(std::int64_t x0, std::int64_t y0, int w, int h,
                                               std::int64_t cell, std::uint64_t seed) {
  std::vector<unsigned char> rgb(std::size_t(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const stex_uvec4 v = stex_draw(stex_cell_key(stex_floordiv(x0 + x, cell), stex_floordiv(y0 + y, cell)),
                                     std::uint32_t(seed), std::uint32_t(seed >> 32), 0u, STEX_DOMAIN_TEST);
      unsigned char* p = &rgb[(std::size_t(y) * w + x) * 3];
      p[0] = (unsigned char)(v.x >> 24);
      p[1] = (unsigned char)(v.y >> 24);
      p[2] = (unsigned char)(v.z >> 24);
    }
  return rgb;
}

std::vector<unsigned char> read_png(const fs::path& path, int* w, int* h) {
  auto in = OIIO::ImageInput::open(path.string());
  if (!in) {
    ADD_FAILURE() << "cannot open " << path << ": " << OIIO::geterror();
    return {};
  }
  const OIIO::ImageSpec& spec = in->spec();
  *w = spec.width;
  *h = spec.height;
  EXPECT_EQ(spec.nchannels, 3);
  EXPECT_EQ(spec.format, OIIO::TypeDesc::UINT8);
  std::vector<unsigned char> px(std::size_t(spec.width) * spec.height * spec.nchannels);
  EXPECT_TRUE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, px.data())) << in->geterror();
  in->close();
  return px;
}

TEST(CliDemoRng, ImageEqualsTheReferenceOnEveryDevice) {
  const fs::path dir = tmp_dir("demo_rng");
  const std::int64_t x0 = -1000000000000ll - 37, y0 = 5;
  const std::uint64_t seed = 0xfeedfacecafebeefull;
  const std::vector<unsigned char> ref = reference_rng_image(x0, y0, 96, 64, 4, seed);
  for (int device : {0, 1}) {
    SCOPED_TRACE("device " + std::to_string(device));
    const fs::path out = dir / ("rng" + std::to_string(device) + ".png");
    RunResult r = run_stex("POCL_DEVICES='pthread basic'",
                           "--device " + std::to_string(device) + " demo-rng -o '" + out.string() +
                               "' --size 96x64 --cell 4 --seed " + std::to_string(seed) +
                               " --origin=" + std::to_string(x0) + "," + std::to_string(y0));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("wrote"), std::string::npos) << r.out;
    int w = 0, h = 0;
    const std::vector<unsigned char> px = read_png(out, &w, &h);
    ASSERT_EQ(w, 96);
    ASSERT_EQ(h, 64);
    EXPECT_TRUE(px == ref) << "the device image differs from the C++ reference";
  }
  // Only the two outputs: no temporary file is left behind.
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 2u);
}

TEST(CliDemoRng, BadArgumentsAndOutputs) {
  const fs::path dir = tmp_dir("demo_rng_bad");
  const std::string out = "-o '" + (dir / "x.png").string() + "'";
  for (const char* size : {"0x5", "12", "axb", "100000x100000"}) {
    RunResult r = run_stex("", "demo-rng " + out + " --size " + size);
    EXPECT_EQ(r.exit_code, std::string(size) == "100000x100000" ? 5 : 2) << size << ": " << r.err;
    EXPECT_NE(r.err.find("--size"), std::string::npos) << r.err;
  }
  RunResult overflow = run_stex("", "demo-rng " + out + " --size 16x16 --origin=9223372036854775800,0");
  EXPECT_EQ(overflow.exit_code, 2) << overflow.err;
  EXPECT_NE(overflow.err.find("overflows"), std::string::npos) << overflow.err;
  RunResult no_dir = run_stex("", "demo-rng -o '" + (dir / "missing" / "x.png").string() + "' --size 8x8");
  EXPECT_EQ(no_dir.exit_code, 6) << no_dir.err;
  RunResult bad_ext = run_stex("", "demo-rng -o '" + (dir / "x.notaformat").string() + "' --size 8x8");
  EXPECT_EQ(bad_ext.exit_code, 6) << bad_ext.err;
  EXPECT_TRUE(fs::is_empty(dir)) << "nothing written, no temporary left";
}

}  // namespace
}  // namespace stex
