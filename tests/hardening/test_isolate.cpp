// The isolation harness itself: a crash, a hang and a contract violation in a child are reported with the
// input in flight, and the inputs after a failure in the same batch are not silently counted as done.
#include <gtest/gtest.h>

#include <unistd.h>

#include <csignal>
#include <ctime>
#include <vector>

#include "hardening/isolate.h"

using stex::test::run_isolated_batch;

TEST(Isolate, ReportsCrashWithInputInFlight) {
  auto r = run_isolated_batch({1, 2, 3}, [](std::uint64_t id, const std::function<void(const std::string&)>&) {
    if (id == 2) std::raise(SIGSEGV);
  });
  ASSERT_EQ(r.failures.size(), 1u);
  EXPECT_NE(r.failures[0].find("input 2"), std::string::npos) << r.failures[0];
  EXPECT_NE(r.failures[0].find("crash"), std::string::npos) << r.failures[0];
  EXPECT_EQ(r.inputs_done, 2);
}

TEST(Isolate, ReportsHangAsTimeBound) {
  stex::test::IsolatedLimits limits;
  limits.seconds = 1;
  auto r = run_isolated_batch({7}, [](std::uint64_t, const std::function<void(const std::string&)>&) {
    for (;;) ::pause();
  }, limits);
  ASSERT_EQ(r.failures.size(), 1u);
  EXPECT_NE(r.failures[0].find("input 7"), std::string::npos) << r.failures[0];
  EXPECT_NE(r.failures[0].find("hang"), std::string::npos) << r.failures[0];
}

// The bound is per input: a hang in the second input is caught after that input's own bound, not the
// batch's, and the first input's time does not count against it.
TEST(Isolate, TimeBoundIsPerInput) {
  stex::test::IsolatedLimits limits;
  limits.seconds = 600;
  limits.per_input_seconds = 2;
  const std::time_t start = std::time(nullptr);
  auto r = run_isolated_batch({1, 2, 3}, [](std::uint64_t id, const std::function<void(const std::string&)>&) {
    if (id == 1) ::sleep(1);  // within its own bound
    if (id == 2)
      for (;;) ::pause();
  }, limits);
  const double seconds = double(std::time(nullptr) - start);
  ASSERT_EQ(r.failures.size(), 1u);
  EXPECT_NE(r.failures[0].find("input 2"), std::string::npos) << r.failures[0];
  EXPECT_NE(r.failures[0].find("hang"), std::string::npos) << r.failures[0];
  EXPECT_EQ(r.inputs_done, 2);
  EXPECT_LT(seconds, 60.0) << "the batch bound (600 s) was used instead of the per-input one (2 s)";
}

TEST(Isolate, ReportsContractViolationsAndExceptions) {
  auto r = run_isolated_batch({4, 5, 6}, [](std::uint64_t id, const std::function<void(const std::string&)>& fail) {
    if (id == 4) fail("bad value");
    if (id == 6) throw std::runtime_error("boom");
  });
  ASSERT_EQ(r.failures.size(), 2u);
  EXPECT_EQ(r.failures[0], "input 4: bad value");
  EXPECT_NE(r.failures[1].find("input 6: unexpected exception: boom"), std::string::npos) << r.failures[1];
  EXPECT_EQ(r.inputs_done, 3);
}

TEST(Isolate, MemoryCapContainsRunawayAllocation) {
  if (!stex::test::memory_cap_active()) GTEST_SKIP() << "no RLIMIT_AS under AddressSanitizer";
  stex::test::IsolatedLimits limits;
  limits.address_space = std::uint64_t(512) << 20;
  auto r = run_isolated_batch({9}, [](std::uint64_t, const std::function<void(const std::string&)>& fail) {
    try {
      std::vector<char> big(std::size_t(2) << 30);
      big[big.size() - 1] = 1;
      fail("a 2 GiB allocation succeeded under a 512 MiB cap");
    } catch (const std::bad_alloc&) {
    }
  }, limits);
  EXPECT_TRUE(r.failures.empty()) << r.failures.front();
}
