// stex serve and the known-answer self-test (runtime/selftest.h): /api/health reports the self-test of the
// service's device (rows checked by this process, rows found in the cache from earlier runs, untested rows),
// and with a device whose RNG has one bit flipped (test builds) a tile is refused with 500 and the message,
// and health says which row failed with both hashes. Each server uses its own cache (STEX_SELFTEST_CACHE).
#include <gtest/gtest.h>

#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>

#include "model/codecs.h"
#include "kernels/test_texton_common.h"
#include "runtime/selftest.h"
#include "serve/serve_test_util.h"

namespace stex {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;
using test::fresh_dir;
using test::ServeProcess;

// Sets an environment variable for the lifetime of the object (the server and CLI children inherit it).
struct ScopedEnv {
  std::string name;
  ScopedEnv(const std::string& n, const std::string& v) : name(n) { ::setenv(n.c_str(), v.c_str(), 1); }
  ~ScopedEnv() { ::unsetenv(name.c_str()); }
};

fs::path texton_models(const fs::path& dir) {
  const fs::path models = dir / "models";
  fs::create_directories(models);
  TextonModel m = test::synthetic_model(3, 12, 1, 17);
  m.stex_version = "test";
  save_model(m, (models / "t.stex").string());
  return models;
}

json get_json(httplib::Client& c, const std::string& path, int* status) {
  auto res = c.Get(path.c_str());
  *status = res ? res->status : -1;
  return res ? json::parse(res->body) : json();
}

const json* find_row(const json& selftest, const std::string& kind, const std::string& path) {
  for (const json& r : selftest.at("rows"))
    if (r.at("kind") == kind && r.at("path") == path) return &r;
  return nullptr;
}

TEST(ServeSelftest, HealthReportsTheDevicesSelftest) {
  const fs::path dir = fresh_dir("serve_selftest");
  ScopedEnv cache("STEX_SELFTEST_CACHE", (dir / "cache").string());
  ServeProcess serve(texton_models(dir), {}, dir);  // warm-up renders t (texton, and filtered)
  ASSERT_TRUE(serve.running()) << serve.log();
  auto c = serve.client();
  int status = 0;
  json h = get_json(c, "/api/health", &status);
  ASSERT_EQ(status, 200);
  EXPECT_EQ(h.at("status"), "ok");  // the existing fields stay
  EXPECT_FALSE(h.at("version").get<std::string>().empty());
  EXPECT_FALSE(h.at("device").get<std::string>().empty());
  EXPECT_TRUE(h.at("uptime_s").is_number());
  const json& st = h.at("selftest");
  EXPECT_EQ(st.at("status"), "partial") << st.dump();
  EXPECT_EQ(st.at("failed"), 0);
  EXPECT_GE(st.at("rows").size(), 22u);
  const json* filtered = find_row(st, "texton", "filtered");
  ASSERT_NE(filtered, nullptr);
  EXPECT_EQ(filtered->at("state"), "pass");
  EXPECT_EQ(filtered->at("source"), "this process");
  EXPECT_EQ(filtered->at("expected"), filtered->at("actual"));
  const json* tb = find_row(st, "tb", "scaled");
  ASSERT_NE(tb, nullptr);
  EXPECT_EQ(tb->at("state"), "untested");
  const int untested = st.at("untested").get<int>();

  // `stex selftest` on the same device and cache fills in rows: health reads them from the cache.
  const auto r = test::run_cli("selftest --only tb");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  h = get_json(c, "/api/health", &status);
  for (const char* path : {"aligned", "scaled"}) {
    const json* row = find_row(h.at("selftest"), "tb", path);
    EXPECT_EQ(row->at("state"), "pass") << row->dump();
    EXPECT_EQ(row->at("source"), "cache") << row->dump();
  }
  EXPECT_EQ(h.at("selftest").at("untested").get<int>(), untested - 2);
}

TEST(ServeSelftest, AFaultyDeviceGetsNoTilesAndHealthSaysWhy) {
  if (!test_kernel_defines_supported()) GTEST_SKIP() << "built without STEX_TESTING";
  const fs::path dir = fresh_dir("serve_selftest_fault");
  ScopedEnv cache("STEX_SELFTEST_CACHE", (dir / "cache").string());
  ScopedEnv fault("STEX_TEST_KERNEL_DEFINES", "-DSTEX_FAULT_FLIP_RNG_BIT");
  ServeProcess serve(texton_models(dir), {"--time-limit", "60000"}, dir);
  ASSERT_TRUE(serve.running()) << serve.log();
  auto c = serve.client();
  auto res = c.Get("/api/tiles/t/0/0/0.png");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 500);
  EXPECT_NE(res->body.find("device self-test failed: texton "), std::string::npos) << res->body;
  EXPECT_NE(res->body.find("expected hash"), std::string::npos) << res->body;
  int status = 0;
  const json h = get_json(c, "/api/health", &status);
  ASSERT_EQ(status, 200);
  const json& st = h.at("selftest");
  EXPECT_EQ(st.at("status"), "fail") << st.dump(2);
  int failed = 0;
  for (const json& r : st.at("rows"))
    if (r.at("state") == "fail") {
      ++failed;
      EXPECT_EQ(r.at("kind"), "texton");
      EXPECT_NE(r.at("expected"), r.at("actual"));
      EXPECT_NE(r.at("error").get<std::string>().find("differ from the C++ reference"), std::string::npos);
    }
  EXPECT_GE(failed, 1);
}

}  // namespace
}  // namespace stex
