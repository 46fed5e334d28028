// Tests of runtime/context, program and buffer on the default device (PoCL here): buffer round trips through
// a kernel, the program cache, build failures carrying the build log, include resolution of the embedded
// sources, the STEX_KERNEL_DIR override, size checks before allocation, borrowed contexts, launch timing.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "core/error.h"
#include "runtime/buffer.h"
#include "runtime/cl_error.h"
#include "runtime/context.h"
#include "runtime/program.h"
#include "test_device.h"

namespace stex {
namespace {

// One context for the whole binary: creating contexts is cheap, but each one rebuilds its programs.
Context& shared_context() {
  static std::unique_ptr<Context> ctx = Context::create(stex::test::test_device_spec());
  return *ctx;
}

const char* k_axpb_source = R"(
__kernel void axpb(__global const float* x, __global float* y, float a, float b) {
  size_t i = get_global_id(0);
  y[i] = a * x[i] + b;
}
)";

TEST(Buffer, RoundTripThroughHost) {
  Context& ctx = shared_context();
  std::vector<std::uint32_t> host(1000);
  for (std::size_t i = 0; i < host.size(); ++i) host[i] = std::uint32_t(i * 2654435761u);
  Buffer<std::uint32_t> buf(ctx, host, CL_MEM_READ_WRITE);
  EXPECT_EQ(buf.size(), host.size());
  EXPECT_EQ(buf.bytes(), host.size() * 4);
  EXPECT_EQ(buf.read(), host);

  // Partial write and read with offsets.
  std::vector<std::uint32_t> part{7, 8, 9};
  buf.write(part.data(), part.size(), 500);
  std::vector<std::uint32_t> back(5);
  buf.read(back.data(), back.size(), 499);
  EXPECT_EQ(back, (std::vector<std::uint32_t>{host[499], 7, 8, 9, host[503]}));
  EXPECT_THROW(buf.read(back.data(), 5, 998), Error);
}

TEST(Buffer, RoundTripThroughKernelWithPositiveDeviceTime) {
  Context& ctx = shared_context();
  Program program(ctx, k_axpb_source, "", "axpb");
  Kernel kernel(program, "axpb");
  const std::size_t n = 1 << 16;
  std::vector<float> x(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = float(i) * 0.25f - 100.0f;
  Buffer<float> xb(ctx, x);
  Buffer<float> yb(ctx, n);
  kernel.set_arg(0, xb);
  kernel.set_arg(1, yb);
  kernel.set_arg(2, 3.0f);
  kernel.set_arg(3, -1.5f);
  double ms = kernel.launch(ctx, NDRange(n));
  EXPECT_GT(ms, 0.0);
  std::vector<float> y = yb.read();
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(y[i], 3.0f * x[i] + -1.5f) << "at " << i;
  EXPECT_GE(program.build_seconds(), 0.0);
}

// A device whose per-allocation limit exceeds its global memory (possible on drivers that report a max
// allocation without capping it by the memory; not on PoCL, where max_alloc <= global_mem): the global
// memory check must still refuse, naming CL_DEVICE_GLOBAL_MEM_SIZE.
TEST(Buffer, RequestAboveGlobalMemoryIsALimitError) {
  DeviceInfo dev;
  dev.name = "fake device";
  dev.max_alloc = std::uint64_t(8) << 30;
  dev.global_mem = std::uint64_t(2) << 30;
  EXPECT_EQ(checked_buffer_bytes(dev, std::size_t(1) << 28, 8, "fits"), std::size_t(2) << 30);
  try {
    checked_buffer_bytes(dev, (std::size_t(1) << 28) + 1, 8, "big image");
    FAIL() << "expected a Limit error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Limit);
    const std::string msg = e.what();
    EXPECT_NE(msg.find("big image"), std::string::npos) << msg;
    EXPECT_NE(msg.find("fake device"), std::string::npos) << msg;
    EXPECT_NE(msg.find("CL_DEVICE_GLOBAL_MEM_SIZE"), std::string::npos) << msg;
    EXPECT_EQ(msg.find("CL_DEVICE_MAX_MEM_ALLOC_SIZE"), std::string::npos) << msg;
  }
}

TEST(Buffer, OversizeIsALimitErrorBeforeAnyOpenCLCall) {
  Context& ctx = shared_context();
  const std::uint64_t max_alloc = ctx.info().max_alloc;
  ASSERT_GT(max_alloc, 0u);
  // One element past CL_DEVICE_MAX_MEM_ALLOC_SIZE.
  const std::size_t count = std::size_t(max_alloc / 4 + 1);
  try {
    Buffer<float> too_big(ctx, count, CL_MEM_READ_WRITE, "test image");
    FAIL() << "expected a Limit error";
  } catch (const OpenCLError& e) {
    FAIL() << "the size check must come before OpenCL: " << e.what();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Limit);
    const std::string msg = e.what();
    EXPECT_NE(msg.find("test image"), std::string::npos) << msg;
    EXPECT_NE(msg.find(std::to_string(max_alloc) + " bytes"), std::string::npos) << msg;
    EXPECT_NE(msg.find(std::to_string(std::uint64_t(count) * 4) + " bytes"), std::string::npos) << msg;
    EXPECT_NE(msg.find("CL_DEVICE_MAX_MEM_ALLOC_SIZE"), std::string::npos) << msg;
  }
  // count * elem_size overflowing size_t.
  try {
    checked_buffer_bytes(ctx, std::numeric_limits<std::size_t>::max() / 2, 16, "overflowing");
    FAIL() << "expected a Limit error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Limit);
    EXPECT_NE(std::string(e.what()).find("overflow"), std::string::npos) << e.what();
  }
  // The largest allowed request passes the check (without allocating it) and 0 is allowed.
  EXPECT_EQ(checked_buffer_bytes(ctx, std::size_t(max_alloc / 4), 4, "max"), std::size_t(max_alloc / 4) * 4);
  EXPECT_EQ(checked_buffer_bytes(ctx, 0, 4, "empty"), 0u);
  Buffer<float> empty(ctx, 0);
  EXPECT_TRUE(empty.read().empty());
  Buffer<float> unbound;  // default-constructed: no context, nothing to transfer
  EXPECT_NO_THROW(unbound.write(nullptr, 0));
  EXPECT_TRUE(unbound.read().empty());
  EXPECT_THROW(unbound.read(nullptr, 1), Error);
}

TEST(Program, BuildFailureCarriesTheBuildLog) {
  Context& ctx = shared_context();
  const char* broken = R"(
__kernel void broken(__global float* x) {
  x[get_global_id(0)] = stex_undeclared_identifier_42 * 2.0f;
}
)";
  try {
    Program program(ctx, broken, "", "broken.cl");
    FAIL() << "expected a build failure";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Device);
    const std::string msg = e.what();
    EXPECT_NE(msg.find("CL_BUILD_PROGRAM_FAILURE"), std::string::npos) << msg;
    EXPECT_NE(msg.find("broken.cl"), std::string::npos) << msg;
    EXPECT_NE(msg.find("build log"), std::string::npos) << msg;
    // The identifier appears only in the compiler's diagnostic (the source itself is not in the message).
    EXPECT_NE(msg.find("stex_undeclared_identifier_42"), std::string::npos) << msg;
  }
}

TEST(Program, UnknownKernelNameIsNamed) {
  Context& ctx = shared_context();
  Program program(ctx, k_axpb_source, "", "axpb");
  try {
    Kernel k(program, "no_such_kernel");
    FAIL();
  } catch (const OpenCLError& e) {
    EXPECT_EQ(e.code(), CL_INVALID_KERNEL_NAME);
    EXPECT_NE(std::string(e.what()).find("no_such_kernel"), std::string::npos) << e.what();
  }
}

TEST(Program, CacheReturnsTheSameProgramPerSourceAndOptions) {
  Context& ctx = shared_context();
  Program& a = ctx.program("rng_test.cl");
  Program& b = ctx.program("rng_test.cl");
  EXPECT_EQ(&a, &b);
  EXPECT_EQ(a.label(), "rng_test.cl");
  Program& c = ctx.program("rng_test.cl", "-DSTEX_TEST_OPTION=1");
  EXPECT_NE(&a, &c);
  EXPECT_EQ(&c, &ctx.program("rng_test.cl", "-DSTEX_TEST_OPTION=1"));
  // A cached program is usable.
  Kernel k(a, "rng_cell_keys");
  EXPECT_EQ(k.name(), "rng_cell_keys");
}

TEST(Program, CacheIsThreadSafe) {
  // A fresh context, so the threads race to build: each (source, options) must be built exactly once.
  std::unique_ptr<Context> ctx = Context::create(stex::test::test_device_spec());
  constexpr int k_threads = 6;
  std::vector<Program*> got(k_threads, nullptr);
  std::vector<std::string> errors(k_threads);
  std::vector<std::thread> threads;
  for (int i = 0; i < k_threads; ++i)
    threads.emplace_back([&, i] {
      try {
        got[i] = &ctx->program("rng_test.cl", i % 2 ? "-DSTEX_TEST_OPTION=2" : "");
      } catch (const std::exception& e) {
        errors[i] = e.what();
      }
    });
  for (std::thread& t : threads) t.join();
  for (int i = 0; i < k_threads; ++i) {
    EXPECT_EQ(errors[i], "") << "thread " << i;
    EXPECT_EQ(got[i], got[i % 2]) << "thread " << i;
  }
  EXPECT_NE(got[0], got[1]);
}

TEST(Program, EmbeddedIncludesAreInlinedOnceEach) {
  const std::string src = resolve_kernel_source("rng_test.cl");
  auto count = [&](const std::string& needle) {
    std::size_t n = 0;
    for (std::size_t p = src.find(needle); p != std::string::npos; p = src.find(needle, p + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("#define STEX_PLATFORM_H"), 1u);  // included by both poisson.h and rng.h
  EXPECT_EQ(count("#define STEX_RNG_H"), 1u);
  EXPECT_EQ(count("#define STEX_POISSON_H"), 1u);
  EXPECT_EQ(count("#include \""), 0u);
  EXPECT_EQ(count("__kernel void rng_draws"), 1u);
  // The compiler's messages point at the original files.
  EXPECT_EQ(count("#line 1 \"shared/rng.h\""), 1u);
  EXPECT_EQ(count("#line 1 \"shared/stex_platform.h\""), 1u);
  try {
    resolve_kernel_source("no_such_file.cl");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Internal);
    EXPECT_NE(std::string(e.what()).find("no_such_file.cl"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("rng_test.cl"), std::string::npos) << "lists what exists";
  }
}

TEST(Program, KernelDirOverrideLoadsFilesFromDisk) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(STEX_TEST_TMP_DIR) / "kernel_dir_override";
  fs::create_directories(dir / "shared");
  std::ofstream(dir / "main.cl")
      << "#include \"shared/a.h\"\n__kernel void k(__global int* x) { x[0] = A; }\n";
  std::ofstream(dir / "shared" / "a.h") << "#include \"b.h\"\n#define A (B + 1)\n";
  std::ofstream(dir / "shared" / "b.h") << "#define B 41\n";
  ASSERT_EQ(setenv("STEX_KERNEL_DIR", dir.c_str(), 1), 0);
  std::string src;
  try {
    src = resolve_kernel_source("main.cl");
    EXPECT_THROW(resolve_kernel_source("rng_test.cl"), Error) << "only files in the directory are visible";
  } catch (...) {
    unsetenv("STEX_KERNEL_DIR");
    throw;
  }
  // Build and run the overridden program through the context's cache.
  Context& ctx = shared_context();
  Program& program = ctx.program("main.cl");
  unsetenv("STEX_KERNEL_DIR");
  EXPECT_NE(src.find("#define B 41"), std::string::npos);
  EXPECT_LT(src.find("#define B 41"), src.find("#define A (B + 1)"));
  Kernel k(program, "k");
  Buffer<int> out(ctx, 1);
  k.set_arg(0, out);
  k.launch(ctx, NDRange(1));
  EXPECT_EQ(out.read()[0], 42);
}

// OpenCL reference counts are "immediately stale": an implementation may drop the references that finished
// commands and released objects hold from a driver thread, later (rusticl does, by several). The count of an
// idle context once it has not changed for 50 ms (bounded: 2 s).
cl_uint settled_context_refs(Context& ctx) {
  ctx.finish();
  cl_uint last = 0;
  EXPECT_EQ(clGetContextInfo(ctx.context(), CL_CONTEXT_REFERENCE_COUNT, sizeof last, &last, nullptr), CL_SUCCESS);
  for (int stable = 0, i = 0; stable < 10 && i < 400; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    cl_uint now = 0;
    clGetContextInfo(ctx.context(), CL_CONTEXT_REFERENCE_COUNT, sizeof now, &now, nullptr);
    stable = now == last ? stable + 1 : 0;
    last = now;
  }
  return last;
}

TEST(Context, BorrowedObjectsAreRetainedAndReleased) {
  Context& owner = shared_context();
  cl_uint during = 0;
  const cl_uint before = settled_context_refs(owner);
  {
    Context borrowed(owner.context(), owner.device(), owner.queue());
    ASSERT_EQ(clGetContextInfo(owner.context(), CL_CONTEXT_REFERENCE_COUNT, sizeof during, &during, nullptr),
              CL_SUCCESS);
    EXPECT_GT(during, before);
    EXPECT_EQ(borrowed.info().name, owner.info().name);
    // Works like an owned context: build, launch, read.
    Program program(borrowed, k_axpb_source, "", "axpb");
    Kernel kernel(program, "axpb");
    Buffer<float> x(borrowed, std::vector<float>{1.0f, 2.0f});
    Buffer<float> y(borrowed, 2);
    kernel.set_arg(0, x);
    kernel.set_arg(1, y);
    kernel.set_arg(2, 2.0f);
    kernel.set_arg(3, 0.5f);
    EXPECT_GT(kernel.launch(borrowed, NDRange(2)), 0.0);
    EXPECT_EQ(y.read(), (std::vector<float>{2.5f, 4.5f}));
  }
  EXPECT_EQ(settled_context_refs(owner), before);
  EXPECT_THROW(Context(nullptr, owner.device(), owner.queue()), Error);
}

TEST(Kernel, LaunchRejectsMismatchedRanges) {
  Context& ctx = shared_context();
  Program program(ctx, k_axpb_source, "", "axpb");
  Kernel kernel(program, "axpb");
  EXPECT_THROW(kernel.launch(ctx, NDRange()), Error);
  EXPECT_THROW(kernel.launch(ctx, NDRange(64), NDRange(8, 8)), Error);
  EXPECT_EQ(kernel.launch(ctx, NDRange(0)), 0.0);  // empty: nothing is enqueued
  // Missing arguments: an OpenCL error naming the call and the kernel.
  try {
    kernel.launch(ctx, NDRange(4));
    FAIL();
  } catch (const OpenCLError& e) {
    EXPECT_EQ(e.call(), "clEnqueueNDRangeKernel");
    EXPECT_NE(std::string(e.what()).find("axpb"), std::string::npos);
  }
  Kernel moved(std::move(kernel));
  EXPECT_EQ(moved.name(), "axpb");
  EXPECT_NE(moved.get(), nullptr);
}

}  // namespace
}  // namespace stex
