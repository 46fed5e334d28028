// Device capabilities come from queries, never from assumptions (issue 27, docs/portability.md): each test
// limits one capability in a copy of the test device's DeviceInfo (what the renderers read through
// Context::info()), renders on a Context made from it, and compares the bits with the unlimited device.
//  - local memory 0 (Mesa's llvmpipe): no local-memory kernel is built, gather-local falls back to gather;
//  - small work-groups: every launch shape shrinks to fit (Kernel::fit_local), same bits;
//  - a small largest allocation: the render is chunked, same bits;
//  - no fp64: no kernel source uses `double` or an unsuffixed floating literal (a double constant on devices
//    with fp64, a float one on devices without: a different rounding of the same expression), and every
//    program builds with `double` poisoned.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/tb_model.h"
#include "core/error.h"
#include "runtime/context.h"
#include "runtime/device.h"
#include "runtime/kernel_sources.h"
#include "runtime/loop_watchdog.h"
#include "runtime/program.h"
#include "runtime/tb.h"
#include "runtime/texton_renderer.h"
#include "test_device.h"
#include "tests/cs/cs_synthetic.h"
#include "tests/kernels/test_texton_common.h"

namespace stex::test {
namespace {

DeviceInfo full_device() { return select_device(test_device_spec()); }

const TextonModel& colour_model() {
  static const TextonModel m = synthetic_model(3, 16, 1, 11);
  return m;
}

std::vector<float> texton_render(Context& ctx, TextonStrategy strategy, TextonRenderStats* stats,
                                 std::size_t max_chunk_pixels = 0) {
  TextonRenderer r(ctx, colour_model());
  TextonRenderOptions o;
  o.strategy = strategy;
  o.max_chunk_pixels = max_chunk_pixels;
  RenderParams p;
  p.seed = 5;
  const int w = 150, h = 70;
  std::vector<float> out(std::size_t(w) * h * 3);
  *stats = r.render(p, 1000003, -77, w, h, out.data(), o);
  return out;
}

const TbModel& tb_model() {
  static const TbModel m = [] {
    TbParams p;
    p.tile = 20.0;
    return tb_from_container(to_container(tb_from_exemplar(make_stationary(96, 80, 3, 2, 5), p)));
  }();
  return m;
}

std::vector<float> tb_render(Context& ctx, int* launches) {
  TbNoise n(ctx, tb_model());
  RenderParams p;
  p.seed = 3;
  const int w = 150, h = 70;
  std::vector<float> out(std::size_t(w) * h * std::size_t(n.channels()));
  const NoiseRenderStats s = n.render(p, -400000, 123, w, h, out.data());
  if (launches) *launches = s.launches;
  return out;
}

bool built(Context& ctx, const std::string& source) {
  const std::vector<std::string> names = ctx.built_programs();
  return std::find(names.begin(), names.end(), source) != names.end();
}

TEST(DeviceCapabilities, NoLocalMemoryBuildsNoLocalMemoryKernel) {
  DeviceInfo limited = full_device();
  limited.local_mem = 0;
  Context none(limited);
  TextonRenderStats s;
  const std::vector<float> got = texton_render(none, TextonStrategy::GatherLocal, &s);
  EXPECT_EQ(s.strategy, TextonStrategy::Gather) << "gather-local without local memory must run the plain gather";
  EXPECT_FALSE(built(none, "texton_gather_local.cl")) << "a local-memory kernel was built for a device without any";
  Context full(full_device());
  TextonRenderStats g;
  EXPECT_EQ(count_bit_differences(got, texton_render(full, TextonStrategy::Gather, &g)), 0u);
}

TEST(DeviceCapabilities, SmallWorkGroupsGiveTheSameBits) {
  const DeviceInfo info = full_device();
  DeviceInfo limited = info;
  limited.max_work_group_size = 2;
  limited.max_work_item_sizes = {2, 2, 1};
  Context small(limited), full(info);
  std::vector<TextonStrategy> strategies{TextonStrategy::Gather};
  strategies.push_back(TextonStrategy::Splat);
  if (info.local_mem > 0) strategies.push_back(TextonStrategy::GatherLocal);
  for (TextonStrategy strategy : strategies) {
    TextonRenderStats a, b;
    const std::vector<float> got = texton_render(small, strategy, &a);
    const std::vector<float> want = texton_render(full, strategy, &b);
    SCOPED_TRACE(texton_strategy_name(strategy));
    EXPECT_LE(a.local_size[0] * a.local_size[1], 2u) << a.local_size[0] << "x" << a.local_size[1];
    EXPECT_LE(a.local_size[0], 2u);
    EXPECT_LE(a.local_size[1], 2u);
    // gather-local with a 2-item work-group: its impulses still fit, or the plain gather ran; same bits.
    EXPECT_EQ(count_bit_differences(got, want), 0u);
  }
  EXPECT_EQ(count_bit_differences(tb_render(small, nullptr), tb_render(full, nullptr)), 0u) << "tb";
}

// The loop watchdog (docs/portability.md, runtime/loop_watchdog.h). The canary itself: a loop of n passes
// sets the flag exactly when the driver cut it short. On Mesa's llvmpipe (65535 loop iterations per kernel
// invocation) 200000 passes are cut and must trip it; 1000 passes are not cut anywhere.
TEST(LoopWatchdog, CanaryTripsExactlyWhenTheDriverCutsALoop) {
  Context ctx(full_device());
  Kernel k(ctx.program("watchdog_test.cl"), "watchdog_probe");
  LoopWatchdog watchdog(ctx);
  Buffer<cl_int> passes(ctx, 4, CL_MEM_READ_WRITE, "passes");
  for (const int n : {1000, 200000}) {
    SCOPED_TRACE(n);
    k.set_arg(0, cl_int(n));
    k.set_arg(1, passes);
    watchdog.bind(k, 2);
    k.launch(ctx, NDRange(1), NDRange(1));
    const bool tripped = watchdog.tripped();
    const std::vector<cl_int> got = passes.read();
    EXPECT_EQ(tripped, got[0] != n) << "passes " << got[0];
    if (n == 1000) {
      EXPECT_FALSE(tripped);
    }
    if (test_device().platform == "rusticl" && n == 200000) {
      EXPECT_TRUE(tripped) << "llvmpipe's cap not met?";
    }
  }
}

// A splat launch that trips is re-run with half the block until it passes: same bits as the gather, the
// retries and the smaller block reported (trips injected, so this runs on every device).
TEST(LoopWatchdog, TrippedSplatIsRerunWithSmallerBlocks) {
  Context ctx(full_device());
  TextonRenderStats gather, splat;
  const std::vector<float> want = texton_render(ctx, TextonStrategy::Gather, &gather);
  inject_loop_watchdog_trips(3);
  const std::vector<float> got = texton_render(ctx, TextonStrategy::Splat, &splat);
  inject_loop_watchdog_trips(0);
  EXPECT_EQ(splat.strategy, TextonStrategy::Splat);
  EXPECT_EQ(splat.launches, splat.chunks + splat.watchdog_retries);
  if (test_device().platform == "rusticl") {  // llvmpipe's own cap trips it further (real trips)
    EXPECT_GE(splat.watchdog_retries, 3);
    EXPECT_LE(splat.splat_block[0], 32);
  } else {
    EXPECT_EQ(splat.watchdog_retries, 3);
    EXPECT_EQ(splat.splat_block[0], 32) << "the strip is halved first: 256 -> 128 -> 64 -> 32";
    EXPECT_EQ(splat.splat_block[1], 16);
  }
  EXPECT_EQ(count_bit_differences(got, want), 0u);
}

// Where one work-item per work-group still trips, the render is refused: Error(Device) naming the device and
// the kernel, never a wrong image. A gather trips twice (its shape, then 1 x 1); a single trip is absorbed.
TEST(LoopWatchdog, GatherThatStillTripsIsRefused) {
  const DeviceInfo info = full_device();
  Context ctx(info);
  TextonRenderStats ref, s;
  const std::vector<float> want = texton_render(ctx, TextonStrategy::Gather, &ref);
  inject_loop_watchdog_trips(1);
  EXPECT_EQ(count_bit_differences(texton_render(ctx, TextonStrategy::Gather, &s), want), 0u);
  EXPECT_EQ(s.watchdog_retries, 1);
  EXPECT_EQ(s.local_size[0] * s.local_size[1], 1u);
  inject_loop_watchdog_trips(2);
  try {
    texton_render(ctx, TextonStrategy::Gather, &s);
    ADD_FAILURE() << "a render whose loops were cut returned";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Device);
    EXPECT_NE(std::string(e.what()).find(info.name), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("texton_gather"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("portability"), std::string::npos) << e.what();
  }
  inject_loop_watchdog_trips(0);
  // The chunked gathers of the other kinds (runtime/chunked_gather.cpp) take the same path.
  int launches = 0;
  const std::vector<float> tb_want = tb_render(ctx, nullptr);
  inject_loop_watchdog_trips(1);
  EXPECT_EQ(count_bit_differences(tb_render(ctx, &launches), tb_want), 0u);
  inject_loop_watchdog_trips(2);
  EXPECT_THROW(tb_render(ctx, nullptr), Error);
  inject_loop_watchdog_trips(0);
}

TEST(DeviceCapabilities, FitLocalHonoursTheKernelAndDeviceLimits) {
  DeviceInfo limited = full_device();
  limited.max_work_group_size = 48;
  limited.max_work_item_sizes = {16, 8, 1};
  Context ctx(limited);
  Kernel k(ctx.program("texton_gather.cl"), "texton_gather");
  const std::size_t cap = std::min<std::size_t>(48, k.max_work_group(ctx));
  for (const std::array<std::size_t, 2>& want :
       {std::array<std::size_t, 2>{16, 4}, {64, 64}, {3, 100}, {1, 1}, {0, 7}}) {
    const std::array<std::size_t, 2> got = k.fit_local(ctx, want);
    EXPECT_GE(got[0], 1u);
    EXPECT_GE(got[1], 1u);
    EXPECT_LE(got[0], 16u);
    EXPECT_LE(got[1], 8u);
    EXPECT_LE(got[0] * got[1], cap) << want[0] << "x" << want[1] << " -> " << got[0] << "x" << got[1];
  }
  const std::array<std::size_t, 2> kept = k.fit_local(ctx, {8, 4});
  if (cap >= 32) {
    EXPECT_EQ(kept[0], 8u) << "a shape that fits is kept";
    EXPECT_EQ(kept[1], 4u);
  }
}

TEST(DeviceCapabilities, SmallAllocationChunksTheRender) {
  const DeviceInfo info = full_device();
  DeviceInfo limited = info;
  limited.max_alloc = 16 * 1024;  // 1365 RGB pixels: a 150 x 70 render needs 8 chunks
  Context small(limited), full(info);
  for (TextonStrategy strategy : {TextonStrategy::Splat, TextonStrategy::Gather}) {
    SCOPED_TRACE(texton_strategy_name(strategy));
    TextonRenderStats a, b;
    const std::vector<float> got = texton_render(small, strategy, &a);
    EXPECT_GT(a.chunks, 1) << "the allocation limit did not set the chunking";
    EXPECT_EQ(count_bit_differences(got, texton_render(full, strategy, &b)), 0u);
  }
  // tb uploads its 92 KiB exemplar whole: a device with 100 KiB allocations renders 150 x 70 x 3 floats
  // (123 KiB) in two chunks.
  DeviceInfo tb_limited = info;
  tb_limited.max_alloc = 100 * 1024;
  Context tb_small_ctx(tb_limited);
  int launches = 0;
  const std::vector<float> tb_small = tb_render(tb_small_ctx, &launches);
  EXPECT_GT(launches, 1) << "tb: the allocation limit did not set the chunking";
  EXPECT_EQ(count_bit_differences(tb_small, tb_render(full, nullptr)), 0u) << "tb";
}

// Source text without comments (block and line), string literals kept.
std::string strip_comments(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size();) {
    if (s.compare(i, 2, "/*") == 0) {
      const std::size_t e = s.find("*/", i + 2);
      i = e == std::string::npos ? s.size() : e + 2;
      out += ' ';
    } else if (s.compare(i, 2, "//") == 0) {
      while (i < s.size() && s[i] != '\n') ++i;
    } else {
      out += s[i++];
    }
  }
  return out;
}

// Floating literals without an f suffix (1.0, .5, 2e3, 1.5e-3), outside identifiers and hex numbers.
std::vector<std::string> double_literals(const std::string& code) {
  static const std::regex lit(R"((^|[^\w.])((\d+\.\d*|\.\d+)([eE][-+]?\d+)?|\d+[eE][-+]?\d+)(?![\w.]))");
  std::vector<std::string> found;
  for (auto it = std::sregex_iterator(code.begin(), code.end(), lit); it != std::sregex_iterator(); ++it)
    found.push_back((*it)[2].str());
  return found;
}

TEST(DeviceCapabilities, NoKernelSourceUsesDouble) {
  // The scan can fail: a double literal and the `double` type are found in a sample.
  EXPECT_EQ(double_literals("x = 0.5f * y + 1.0 + 2e3f + 3e-2; z = 0x1e5; w = a1.5;").size(), 1u + 1u);
  std::size_t count = 0;
  const EmbeddedSource* sources = embedded_sources(&count);
  ASSERT_GT(count, 10u);
  for (std::size_t i = 0; i < count; ++i) {
    const std::string code = strip_comments(sources[i].text);
    SCOPED_TRACE(sources[i].name);
    EXPECT_EQ(std::regex_search(code, std::regex(R"(\bdouble\b)")), false) << "uses the type double";
    const std::vector<std::string> lits = double_literals(code);
    EXPECT_TRUE(lits.empty()) << "unsuffixed floating literal (a double on fp64 devices): " << lits.front();
  }
}

TEST(DeviceCapabilities, EveryProgramBuildsWithDoublePoisoned) {
  // Every kernel file with the build options the renderers use (and the variants of tb.cl's #if branches),
  // `double` defined away: a kernel that used it would not build on a device without fp64.
  const std::string poison = "#define double stex_double_is_not_portable\n";
  const std::vector<std::pair<std::string, std::string>> builds{
      {"texton_splat.cl", "-DSTEX_SPLAT_CHANNELS=3"},
      {"texton_gather.cl", ""},
      {"texton_gather_local.cl", ""},
      {"texton_filtered.cl", ""},
      {"lrp.cl", ""},
      {"gabor_gather.cl", ""},
      {"mix_gather.cl", ""},
      {"cs_spot.cl", "-DSTEX_CS_CH=3"},
      {"cs_rpn.cl", ""},
      {"surface_points.cl", ""},
      {"rng_test.cl", ""},
      {"tb.cl", "-DSTEX_TB_CH=1 -DSTEX_TB_CS=0 -DSTEX_TB_ALIGNED=1 -DSTEX_TB_UNIT=1"},
      {"tb.cl", "-DSTEX_TB_CH=3 -DSTEX_TB_CS=1 -DSTEX_TB_ALIGNED=0 -DSTEX_TB_UNIT=0 -DSTEX_TB_LANES=16"},
      {"bench_s1_baseline.cl", "-DS1_CHANNELS=3"},
      {"bench_adsn.cl", ""},
      {"bench_fma_peak.cl", ""}};
  std::unique_ptr<Context> ctx = Context::create(test_device_spec());
  for (const auto& [name, options] : builds) {
    SCOPED_TRACE(name + " " + options);
    EXPECT_NO_THROW(Program(*ctx, poison + resolve_kernel_source(name), options, name));
  }
  // The poison works: a kernel using double does not build.
  EXPECT_THROW(Program(*ctx, poison + "__kernel void k(__global float* o) { double d = o[0]; o[0] = (float)d; }", "",
                       "uses-double"),
               Error);
}

// The struct types of the kernel dialect (`typedef struct { ... } NAME;`).
std::vector<std::string> struct_names(const std::string& code) {
  static const std::regex def(R"(typedef\s+struct[^{]*\{[^}]*\}\s*(\w+)\s*;)");
  std::vector<std::string> names;
  for (auto it = std::sregex_iterator(code.begin(), code.end(), def); it != std::sregex_iterator(); ++it)
    names.push_back((*it)[1].str());
  return names;
}

// A parameter list split at commas, each parameter into its words.
std::vector<std::vector<std::string>> parameters(const std::string& list) {
  std::vector<std::vector<std::string>> out;
  std::stringstream all(list);
  std::string one;
  while (std::getline(all, one, ',')) {
    std::stringstream words(one);
    std::vector<std::string> w;
    for (std::string word; words >> word;) w.push_back(word);
    out.push_back(w);
  }
  return out;
}

// Function parameters `STRUCT name` without const: a write to them would reach the caller on rusticl
// (docs/portability.md, root cause 1).
std::vector<std::string> mutable_struct_params(const std::string& code, const std::vector<std::string>& structs) {
  static const std::regex fn(R"((\w+)\s*\(([^;{}()]*)\)\s*\{)");
  std::vector<std::string> bad;
  for (auto it = std::sregex_iterator(code.begin(), code.end(), fn); it != std::sregex_iterator(); ++it) {
    for (const std::vector<std::string>& words : parameters((*it)[2].str()))
      if (words.size() == 2 && std::find(structs.begin(), structs.end(), words[0]) != structs.end())
        bad.push_back((*it)[1].str() + "(" + words[0] + " " + words[1] + ")");
  }
  return bad;
}

// Kernel struct arguments not copied to a private variable at entry (root cause 2): each must be
// `const STRUCT NAME_arg` with `const STRUCT NAME = NAME_arg;` among the kernel's first statements.
std::vector<std::string> uncopied_kernel_structs(const std::string& code, const std::vector<std::string>& structs) {
  static const std::regex kernel(R"(__kernel\s+void\s+(\w+)\s*\(([^{]*)\)\s*\{)");
  std::vector<std::string> bad;
  for (auto it = std::sregex_iterator(code.begin(), code.end(), kernel); it != std::sregex_iterator(); ++it) {
    const std::string body = code.substr(std::size_t(it->position() + it->length()), 400);
    for (const std::vector<std::string>& words : parameters((*it)[2].str())) {
      if (words.size() < 2) continue;
      const std::string type = words[words.size() - 2], name = words.back();
      if (std::find(structs.begin(), structs.end(), type) == structs.end()) continue;
      const bool named = name.size() > 4 && name.compare(name.size() - 4, 4, "_arg") == 0;
      const std::string base = named ? name.substr(0, name.size() - 4) : name;
      if (!named || body.find("const " + type + " " + base + " = " + name + ";") == std::string::npos)
        bad.push_back((*it)[1].str() + "(" + type + " " + name + ")");
    }
  }
  return bad;
}

// Every kernel source: the embedded kernels/ tree and the C API's entry points (capi/device_kernels.cpp, an
// OpenCL C string inside C++, read from the source tree).
std::string all_kernel_code() {
  std::size_t count = 0;
  const EmbeddedSource* sources = embedded_sources(&count);
  std::string all;
  for (std::size_t i = 0; i < count; ++i) all += strip_comments(sources[i].text) + "\n";
  std::ifstream capi(std::string(STEX_SOURCE_DIR) + "/capi/device_kernels.cpp");
  std::stringstream text;
  text << capi.rdbuf();
  EXPECT_NE(text.str().find("__kernel void stex_capi_region"), std::string::npos) << "capi/device_kernels.cpp not read";
  all += strip_comments(text.str()) + "\n";
  return all;
}

// Kernels without the loop watchdog's arguments (root cause 9), minus those that need none.
std::vector<std::string> unwatched_kernels(const std::string& code, const std::vector<std::string>& exempt) {
  static const std::regex kernel(R"(__kernel\s+void\s+(\w+)\s*\(([^{]*)\)\s*\{)");
  std::vector<std::string> bad;
  for (auto it = std::sregex_iterator(code.begin(), code.end(), kernel); it != std::sregex_iterator(); ++it) {
    const std::string name = (*it)[1].str();
    if (std::find(exempt.begin(), exempt.end(), name) != exempt.end()) continue;
    const std::string args = (*it)[2].str();
    const std::size_t body_at = std::size_t(it->position() + it->length());
    const std::size_t end = code.find("\n}", body_at);
    const std::string body = code.substr(body_at, end == std::string::npos ? std::string::npos : end - body_at);
    if (args.find("STEX_WATCHDOG_ARGS") == std::string::npos || body.find("STEX_WATCHDOG_CHECK()") == std::string::npos)
      bad.push_back(name);
  }
  return bad;
}

TEST(DeviceCapabilities, StructParametersAreConst) {
  const std::vector<std::string> sample_structs{"stex_uvec4"};
  EXPECT_EQ(mutable_struct_params("STEX_FN int f(stex_uvec4 v, int k) { return 0; }", sample_structs).size(), 1u)
      << "the scan must catch a mutable struct parameter";
  EXPECT_TRUE(mutable_struct_params("STEX_FN int f(const stex_uvec4 v) { return 0; }", sample_structs).empty());
  const std::string code = all_kernel_code();
  const std::vector<std::string> structs = struct_names(code);
  EXPECT_GE(structs.size(), 10u);
  const std::vector<std::string> bad = mutable_struct_params(code, structs);
  EXPECT_TRUE(bad.empty()) << "by-value struct parameter without const (docs/portability.md): " << bad.front();
}

TEST(DeviceCapabilities, KernelStructArgumentsAreCopied) {
  const std::vector<std::string> sample_structs{"P"};
  EXPECT_EQ(uncopied_kernel_structs("__kernel void k(const P p, __global float* o) { o[0] = p.f[1]; }", sample_structs)
                .size(),
            1u)
      << "the scan must catch an uncopied struct argument";
  EXPECT_TRUE(uncopied_kernel_structs("__kernel void k(const P p_arg) {\n  const P p = p_arg;\n}", sample_structs).empty());
  const std::string code = all_kernel_code();
  const std::vector<std::string> bad = uncopied_kernel_structs(code, struct_names(code));
  EXPECT_TRUE(bad.empty()) << "kernel struct argument not copied at entry (docs/portability.md): " << bad.front();
}

// Every render kernel takes the loop watchdog's arguments and ends with its check (root cause 9): a driver
// that cuts loops short is then caught on every launch. Exempt: kernels that write no render output (the
// benchmarks' kernels, the RNG's test kernels) and cs_spot_weights (one draw per node, no loop).
TEST(DeviceCapabilities, RenderKernelsCarryTheLoopWatchdog) {
  EXPECT_EQ(unwatched_kernels("__kernel void k(__global float* o) {\n  o[0] = 1.0f;\n}", {}).size(), 1u)
      << "the scan must catch a kernel without the canary";
  EXPECT_TRUE(
      unwatched_kernels("__kernel void k(__global float* o, STEX_WATCHDOG_ARGS) {\n  STEX_WATCHDOG_CHECK();\n}", {})
          .empty());
  const std::vector<std::string> exempt{"bench_adsn_noise", "bench_adsn_multiply", "bench_adsn_finish",
                                        "bench_peak",       "bench_s1_baseline",   "rng_cell_keys",
                                        "rng_draws",        "poisson_lookup",      "poisson_cells",
                                        "rng_image",        "cs_spot_weights"};
  const std::vector<std::string> bad = unwatched_kernels(all_kernel_code(), exempt);
  EXPECT_TRUE(bad.empty()) << "kernel without STEX_WATCHDOG_ARGS / STEX_WATCHDOG_CHECK() (docs/portability.md, "
                              "root cause 9): "
                           << bad.front();
}

}  // namespace
}  // namespace stex::test
