// stex serve (service/, cli/serve.cpp) as a subprocess on loopback: tiles and regions byte-identical to
// `stex render` with the same parameters (every kind through the registry; zoomed-out texton tiles through
// the S1 §5 filter), 400/404 with messages, reload on change, bounded queue (503 + Retry-After), the time
// limit, the cache's memory cap, health/metrics, clean shutdown on SIGTERM. The load test (wrk) and the
// viewer test (headless Chromium) are in test_serve_load.cpp / test_serve_viewer.cpp (own ctest entries).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <cmath>
#include <map>
#include <mutex>

#include "analysis/cs_rpn_model.h"
#include "analysis/gabor_model.h"
#include "analysis/image_io.h"
#include "model/codecs.h"
#include "kernels/test_texton_common.h"
#include "runtime/gabor_params.h"
#include "serve/serve_test_util.h"

namespace stex {
namespace {

using json = nlohmann::json;
using test::fresh_dir;
using test::read_file;
using test::run_cli;
using test::ServeProcess;
namespace fs = std::filesystem;

void save_texton(const fs::path& p, int channels, int order, std::uint64_t seed, bool linear = false) {
  TextonModel m = test::synthetic_model(channels, 16, order, seed, 0.01f);
  m.linear = linear;
  m.exemplar_name = "none.png";
  m.stex_version = STEX_VERSION_STRING;
  save_model(m, p.string());
}

void save_gabor(const fs::path& p) {
  GaborModel m;
  m.bandwidth = 0.08;
  GaborComponent a, b;
  a.frequency = 0.1;
  a.orientation = 0.0;
  a.weight = 1.0;
  b.frequency = 0.2;
  b.orientation = 1.2;
  b.spread = 0.3;
  b.weight = 0.5;
  m.components = {a, b};
  save_container(to_container(m), p.string());
}

// A cs-rpn model of the phasor variant: the one kind here whose minified views do not filter (docs/filtering.md).
void save_phasor(const fs::path& p) {
  CsRpnModel m;
  m.variant = CsRpnVariant::Phasor;
  cs_rpn_load_spectra(m, json{{"grid", {1, 1}}, {"size", 64}, {"spectra", {"bilobe:0.1,0,0.01"}}});
  save_container(to_container(m), p.string());
}

// One models directory for the tests that do not change it.
fs::path models_dir() {
  static const fs::path dir = [] {
    const fs::path d = fresh_dir("models");
    save_texton(d / "tex.stex", 3, 1, 61);
    save_texton(d / "lin.stex", 1, 1, 62, true);
    save_texton(d / "cubic.stex", 3, 3, 63);
    save_gabor(d / "gab.stex");
    save_phasor(d / "phasor.stex");
    return d;
  }();
  return dir;
}

// The server shared by the read-only tests (started once; the device, programs and renderers stay warm).
ServeProcess& shared_server() {
  static ServeProcess p(models_dir(), {"--queue", "64", "--cache-mb", "32"}, fresh_dir("shared"));
  return p;
}

std::string query_get(httplib::Client& c, const std::string& path, int* status,
                      httplib::Headers* headers = nullptr) {
  auto res = c.Get(path.c_str());
  if (!res) {
    *status = -1;
    return "";
  }
  *status = res->status;
  if (headers) *headers = res->headers;
  return res->body;
}

std::string cli_render(const fs::path& model, const fs::path& out, const std::string& args) {
  const auto r = run_cli("render '" + model.string() + "' -o '" + out.string() + "' " + args);
  EXPECT_EQ(r.code, 0) << r.err;
  return read_file(out);
}

// OpenEXR files carry the time of writing (OIIO's writer adds DateTime, stored as the EXR attribute
// capDate): two `stex render` runs of the same EXR differ there and nowhere else. Blanks that one value.
std::string without_exr_datetime(std::string b) {
  static const std::string tag("capDate\0string\0", 15);
  const auto at = b.find(tag);
  if (at == std::string::npos || at + tag.size() + 4 > b.size()) return b;
  std::uint32_t n = 0;
  std::memcpy(&n, b.data() + at + tag.size(), 4);  // little-endian, as OpenEXR stores it
  const std::size_t v = at + tag.size() + 4;
  if (v + n <= b.size()) std::fill(b.begin() + long(v), b.begin() + long(v + n), '\0');
  return b;
}

// PNG: byte for byte. EXR: byte for byte but for the DateTime value.
bool same_file_bytes(const std::string& served, const std::string& cli, const std::string& format) {
  if (format == "png") return served == cli;
  return served.size() == cli.size() && without_exr_datetime(served) == without_exr_datetime(cli);
}

std::string fmt_scale(int z) {
  char b[64];
  std::snprintf(b, sizeof b, "%.17g", std::ldexp(1.0, z));
  return b;
}

TEST(Serve, TilesEqualCliRendersByteForByte) {
  ServeProcess& s = shared_server();
  ASSERT_TRUE(s.running()) << s.log();
  auto c = s.client();
  const fs::path dir = fresh_dir("bits");
  struct Case {
    std::string model;
    int z;
    std::int64_t tx, ty;
    std::string format, extra_query;
    bool filter;  // the CLI equivalent adds --filter (and with filter=off, --no-filter: the CLI filters by default)
  };
  const std::vector<Case> cases = {
      {"tex", 0, 0, 0, "png", "", false},
      {"tex", 0, -3, 7, "exr", "", false},
      {"tex", 2, 5, -1, "png", "&bits=16", false},
      {"tex", -2, -1, 2, "png", "", true},   // zoomed out: S1 §5 filtering
      {"tex", -3, 4, 4, "exr", "", true},
      {"tex", -1, 0, 0, "png", "&filter=off", false},
      {"lin", 0, 1, 1, "png", "", false},    // linear model: sRGB-encoded PNG
      {"lin", 0, 1, 1, "exr", "&bits=16", false},
      {"cubic", -1, 2, 3, "png", "", false},  // order 3: zoomed out, the box prefilter by default (CLI too)
      {"gab", 0, 10, -10, "exr", "", false},
      {"gab", 1, -2, 0, "png", "", false},
      {"gab", -2, 3, 3, "png", "", false},   // zoomed out: the kernels filtered by default (CLI too)
      {"gab", -2, 3, 3, "png", "&filter=off", false},
  };
  for (const Case& k : cases) {
    const std::uint64_t seed = 12345678901ull + std::uint64_t(k.z + 20);
    const std::string path = "/api/tiles/" + k.model + "/" + std::to_string(k.z) + "/" + std::to_string(k.tx) + "/" +
                             std::to_string(k.ty) + "." + k.format + "?seed=" + std::to_string(seed) + "&mni=17.5" +
                             k.extra_query;
    int status = 0;
    httplib::Headers h;
    const std::string body = query_get(c, path, &status, &h);
    ASSERT_EQ(status, 200) << path << ": " << body;
    std::string bits;
    if (k.extra_query.find("bits=16") != std::string::npos) bits = " --bits 16";
    const std::string cli =
        cli_render(models_dir() / (k.model + ".stex"), dir / ("cli." + k.format),
                   "--size 256x256 --origin " + std::to_string(k.tx * 256) + "," + std::to_string(k.ty * 256) +
                       " --scale " + fmt_scale(k.z) + " --seed " + std::to_string(seed) + " --mni 17.5" + bits +
                       (k.filter ? " --filter" : k.extra_query.find("filter=off") != std::string::npos ? " --no-filter" : ""));
    ASSERT_FALSE(cli.empty());
    EXPECT_EQ(body.size(), cli.size()) << path;
    EXPECT_TRUE(same_file_bytes(body, cli, k.format)) << path << ": the tile's bytes differ from stex render's";
    if (k.format == "exr") {
      EXPECT_NE(without_exr_datetime(body), body);  // the attribute was found
    }
    // The second request is a cache hit with the same bytes.
    const std::string again = query_get(c, path, &status, &h);
    EXPECT_EQ(status, 200);
    EXPECT_TRUE(again == body);
    auto it = h.find("X-Stex-Cache");
    ASSERT_NE(it, h.end());
    EXPECT_EQ(it->second, "hit");
  }
  // A region at an arbitrary origin and scale, far from the origin.
  int status = 0;
  const std::string region =
      query_get(c, "/api/region/tex.exr?x=-1000000000000&y=12&w=70&h=45&scale=1.5&seed=987654321&mni=20&cell=0.7",
                &status);
  ASSERT_EQ(status, 200) << region;
  const std::string cli = cli_render(models_dir() / "tex.stex", dir / "region.exr",
                                     "--size 70x45 --origin -1000000000000,12 --scale 1.5 --mni 20 --seed 987654321 "
                                     "--cell 0.7");
  EXPECT_TRUE(same_file_bytes(region, cli, "exr")) << "region bytes differ from stex render's";
  // A zoomed-out region is filtered exactly when the CLI's --filter is.
  const std::string zr = query_get(c, "/api/region/tex.png?x=5&y=-9&w=64&h=48&scale=0.3&seed=4", &status);
  ASSERT_EQ(status, 200) << zr;
  EXPECT_TRUE(zr == cli_render(models_dir() / "tex.stex", dir / "zr.png",
                               "--size 64x48 --origin 5,-9 --scale 0.3 --seed 4 --filter"));
}

TEST(Serve, BadParametersAre400UnknownModelsAre404) {
  ServeProcess& s = shared_server();
  ASSERT_TRUE(s.running()) << s.log();
  auto c = s.client();
  struct Case {
    std::string path;
    int status;
    std::string message;  // a substring of the error
  };
  const std::vector<Case> cases = {
      {"/api/tiles/nope/0/0/0.png", 404, "unknown model 'nope'"},
      {"/api/models/nope", 404, "unknown model"},
      {"/api/region/nope.png?w=4&h=4", 404, "unknown model"},
      {"/api/tiles/a%20b/0/0/0.png", 400, "invalid model name"},
      {"/api/tiles/tex/11/0/0.png", 400, "zoom level must be in [-10, 10]"},
      {"/api/tiles/tex/zz/0/0.png", 400, "zoom level must be a 64-bit integer"},
      {"/api/tiles/tex/0/1.5/0.png", 400, "tile x"},
      {"/api/tiles/tex/0/0/0.jpg", 400, "format must be png or exr"},
      {"/api/tiles/tex/0/0/0", 400, "format extension"},
      {"/api/tiles/tex/0/0/0.png?seed=-1", 400, "seed must be an unsigned"},
      {"/api/tiles/tex/0/0/0.png?mni=abc", 400, "mni must be a finite number"},
      {"/api/tiles/tex/0/0/0.png?mni=0", 400, "mni"},
      {"/api/tiles/tex/0/0/0.png?mni=1e9", 400, "mni"},
      {"/api/tiles/tex/0/0/0.png?cell=5", 400, "cell"},
      {"/api/tiles/tex/0/0/0.png?colour=red", 400, "unknown parameter 'colour'"},
      {"/api/tiles/tex/0/0/0.png?seed=1&seed=2", 400, "more than once"},
      {"/api/tiles/tex/0/0/0.png?bits=32", 400, "bits must be 8 or 16 for png"},
      {"/api/tiles/tex/0/0/0.exr?bits=8", 400, "bits must be 16 (half) or 32 for exr"},
      {"/api/tiles/tex/0/0/0.png?filter=maybe", 400, "filter must be auto, on or off"},
      {"/api/tiles/phasor/-1/0/0.png?filter=on", 400, "filter=on applies to texton, gabor, lrp"},
      {"/api/tiles/tex/0/999999999999/0.png", 400, "beyond the coordinate range"},
      {"/api/region/tex.png?w=10", 400, "needs w and h"},
      {"/api/region/tex.png?w=0&h=10", 400, "at least 1"},
      {"/api/region/tex.png?w=4096&h=4096", 400, "above the limit"},
      {"/api/region/tex.png?w=4&h=4&scale=5000", 400, "scale"},
      {"/api/region/tex.png?w=4&h=4&x=70368744177664", 400, ""},
      {"/api/nothing", 404, "no such endpoint"},
      {"/nothing.html", 404, "no such page"},
  };
  for (const Case& k : cases) {
    int status = 0;
    const std::string body = query_get(c, k.path, &status);
    EXPECT_EQ(status, k.status) << k.path << ": " << body;
    const json j = json::parse(body, nullptr, false);
    ASSERT_TRUE(j.is_object()) << k.path << ": " << body;
    EXPECT_NE(j.value("error", "").find(k.message), std::string::npos) << k.path << ": " << body;
  }
  // The server is unharmed.
  int status = 0;
  query_get(c, "/api/tiles/tex/0/0/0.png", &status);
  EXPECT_EQ(status, 200);
}

TEST(Serve, HealthModelsInfoMetricsAndViewerPages) {
  ServeProcess& s = shared_server();
  ASSERT_TRUE(s.running()) << s.log();
  auto c = s.client();
  int status = 0;
  json h = json::parse(query_get(c, "/api/health", &status));
  EXPECT_EQ(status, 200);
  EXPECT_EQ(h["status"], "ok");
  EXPECT_FALSE(h["device"].get<std::string>().empty());

  json m = json::parse(query_get(c, "/api/models", &status));
  ASSERT_EQ(status, 200);
  std::vector<std::string> names;
  for (const auto& e : m["models"]) names.push_back(e["name"]);
  EXPECT_EQ(names, (std::vector<std::string>{"cubic", "gab", "lin", "phasor", "tex"}));

  json info = json::parse(query_get(c, "/api/models/tex", &status));
  ASSERT_EQ(status, 200);
  EXPECT_EQ(info["kind"], "texton");
  EXPECT_EQ(info["channels"], 3);
  EXPECT_EQ(info["order"], 1);
  EXPECT_EQ(info["filterable"], true);
  EXPECT_EQ(info["sha256"], sha256_file_hex((models_dir() / "tex.stex").string()));
  json g = json::parse(query_get(c, "/api/models/gab", &status));
  ASSERT_EQ(status, 200);
  EXPECT_EQ(g["kind"], "gabor");
  EXPECT_EQ(g["channels"], 1);
  EXPECT_EQ(g["filterable"], true);  // minified views: the kernels filtered (docs/filtering.md)

  query_get(c, "/api/tiles/tex/0/100/100.png", &status);
  ASSERT_EQ(status, 200);
  json mt = json::parse(query_get(c, "/api/metrics", &status));
  ASSERT_EQ(status, 200);
  EXPECT_GE(mt["requests"].get<int>(), 4);
  EXPECT_GE(mt["device"]["renders"].get<int>(), 1);
  EXPECT_GT(mt["device"]["time_ms_total"].get<double>(), 0.0);
  EXPECT_GE(mt["render_latency"]["count"].get<int>(), 1);
  EXPECT_GE(mt["render_latency"]["p99_ms"].get<double>(), mt["render_latency"]["p50_ms"].get<double>());
  EXPECT_EQ(mt["queue"]["capacity"], 64);
  EXPECT_LE(mt["cache"]["bytes"].get<std::size_t>(), mt["cache"]["cap_bytes"].get<std::size_t>());

  httplib::Headers hd;
  const std::string page = query_get(c, "/", &status, &hd);
  EXPECT_EQ(status, 200);
  EXPECT_NE(page.find("<canvas id=\"view\">"), std::string::npos);
  EXPECT_NE(hd.find("Content-Type")->second.find("text/html"), std::string::npos);
  const std::string js = query_get(c, "/viewer.js", &status);
  EXPECT_EQ(status, 200);
  EXPECT_NE(js.find("/api/tiles/"), std::string::npos);
}

TEST(Serve, ReloadsAModelWhenItsFileChanges) {
  const fs::path work = fresh_dir("reload");
  const fs::path dir = work / "models";
  fs::create_directories(dir);
  save_texton(work / "a.stex", 3, 1, 101);
  save_texton(work / "b.stex", 1, 1, 202);
  fs::copy_file(work / "a.stex", dir / "m.stex");
  ServeProcess s(dir, {}, work);
  ASSERT_TRUE(s.running()) << s.log();
  auto c = s.client();
  int status = 0;
  const std::string t1 = query_get(c, "/api/tiles/m/0/0/0.exr?seed=5", &status);
  ASSERT_EQ(status, 200);
  // Replace it the way stex analyze writes: a new file renamed over the old one.
  fs::copy_file(work / "b.stex", dir / ".m.tmp");
  fs::rename(dir / ".m.tmp", dir / "m.stex");
  const std::string t2 = query_get(c, "/api/tiles/m/0/0/0.exr?seed=5", &status);
  ASSERT_EQ(status, 200);
  EXPECT_TRUE(t1 != t2);
  EXPECT_TRUE(same_file_bytes(t2, cli_render(dir / "m.stex", work / "b.exr", "--size 256x256 --seed 5"), "exr"));
  json info = json::parse(query_get(c, "/api/models/m", &status));
  EXPECT_EQ(info["channels"], 1);
  EXPECT_EQ(info["generation"], 2);
  json mt = json::parse(query_get(c, "/api/metrics", &status));
  EXPECT_EQ(mt["models"]["reloads"], 1);
  // Removed: 404; a corrupt file: 500 naming the problem, and the server keeps serving the others.
  save_texton(dir / "other.stex", 3, 1, 7);
  fs::remove(dir / "m.stex");
  query_get(c, "/api/tiles/m/0/0/0.png", &status);
  EXPECT_EQ(status, 404);
  test::write_file(dir / "m.stex", "not a model");
  const std::string bad = query_get(c, "/api/tiles/m/0/0/0.png", &status);
  EXPECT_EQ(status, 500);
  EXPECT_NE(bad.find("cannot be loaded"), std::string::npos) << bad;
  query_get(c, "/api/tiles/other/0/0/0.png", &status);
  EXPECT_EQ(status, 200);
  EXPECT_EQ(s.stop(), 0) << s.log();
}

// Concurrent requests beyond the queue: every answer is 200 or 503 with Retry-After; never anything else.
TEST(Serve, OverloadGets503WithRetryAfterNotACrash) {
  const fs::path work = fresh_dir("overload");
  ServeProcess s(models_dir(), {"--queue", "1", "--threads", "24", "--cache-mb", "0"}, work);
  ASSERT_TRUE(s.running()) << s.log();
  {
    auto c = s.client();
    int status = 0;
    query_get(c, "/api/region/tex.png?w=16&h=16", &status);  // warm: kernels built
    ASSERT_EQ(status, 200);
  }
  std::mutex mu;
  std::map<int, int> statuses;
  int retry_after_missing = 0;
  std::vector<std::thread> threads;
  for (int i = 0; i < 16; ++i)
    threads.emplace_back([&, i] {
      auto c = s.client();
      auto res = c.Get(("/api/region/tex.exr?w=512&h=512&seed=" + std::to_string(1000 + i)).c_str());
      std::lock_guard<std::mutex> lock(mu);
      const int st = res ? res->status : -1;
      ++statuses[st];
      if (st == 503 && !res->has_header("Retry-After")) ++retry_after_missing;
    });
  for (auto& t : threads) t.join();
  std::string summary;
  for (const auto& kv : statuses) summary += std::to_string(kv.first) + ":" + std::to_string(kv.second) + " ";
  EXPECT_GE(statuses[200], 2) << summary;  // the running job and the one waiting at least
  EXPECT_GE(statuses[503], 1) << summary;  // 16 at once into a queue of 1
  EXPECT_EQ(statuses[200] + statuses[503], 16) << summary;
  EXPECT_EQ(retry_after_missing, 0);
  auto c = s.client();
  int status = 0;
  json mt = json::parse(query_get(c, "/api/metrics", &status));
  EXPECT_EQ(mt["queue"]["rejected"].get<int>() + mt["queue"]["timed_out"].get<int>(), statuses[503]);
  EXPECT_LE(mt["queue"]["max_depth"].get<int>(), 1);
  query_get(c, "/api/health", &status);
  EXPECT_EQ(status, 200);
  EXPECT_EQ(s.stop(), 0) << s.log();
}

TEST(Serve, TimeLimitGives503) {
  const fs::path work = fresh_dir("timelimit");
  ServeProcess s(models_dir(), {"--time-limit", "1", "--cache-mb", "0"}, work);
  ASSERT_TRUE(s.running()) << s.log();
  auto c = s.client();
  int status = 0;
  httplib::Headers h;
  // 1024x512 pixels of 3-channel texton noise take far more than 1 ms on any device. The render runs to its
  // end after the 503 (a device job is not interrupted) and stop() waits for it: on a slower test device
  // (llvmpipe: 15 min of CPU for this one) a region of 256x128 still takes far more than 1 ms.
  const std::string region = test::test_device_is_pocl() ? "w=1024&h=512" : "w=256&h=128";
  const std::string body = query_get(c, "/api/region/tex.exr?" + region + "&mni=200", &status, &h);
  EXPECT_EQ(status, 503) << body;
  EXPECT_NE(body.find("time limit of 1 ms"), std::string::npos) << body;
  EXPECT_NE(h.find("Retry-After"), h.end());
  EXPECT_EQ(s.stop(), 0) << s.log();
}

TEST(Serve, CacheStaysUnderItsCapAndEvicts) {
  const fs::path work = fresh_dir("cache");
  ServeProcess s(models_dir(), {"--cache-mb", "1"}, work);
  ASSERT_TRUE(s.running()) << s.log();
  auto c = s.client();
  std::size_t served = 0;
  int status = 0;
  for (int i = 0; i < 24; ++i) {
    served += query_get(c, "/api/tiles/tex/0/" + std::to_string(i) + "/0.png", &status).size();
    ASSERT_EQ(status, 200);
  }
  ASSERT_GT(served, std::size_t(2) << 20);  // more than twice the cap went through the cache
  json mt = json::parse(query_get(c, "/api/metrics", &status));
  EXPECT_LE(mt["cache"]["bytes"].get<std::size_t>(), std::size_t(1) << 20);
  EXPECT_EQ(mt["cache"]["cap_bytes"], std::size_t(1) << 20);
  EXPECT_GT(mt["cache"]["evictions"].get<int>(), 0);
  // The most recent tile is still cached; the first was evicted (LRU).
  httplib::Headers h;
  query_get(c, "/api/tiles/tex/0/23/0.png", &status, &h);
  EXPECT_EQ(h.find("X-Stex-Cache")->second, "hit");
  query_get(c, "/api/tiles/tex/0/0/0.png", &status, &h);
  EXPECT_EQ(h.find("X-Stex-Cache")->second, "miss");
  EXPECT_EQ(s.stop(), 0) << s.log();
}

TEST(Serve, CommandLineErrors) {
  const fs::path work = fresh_dir("cli_errors");
  auto r = run_cli("serve --models '" + (work / "missing").string() + "' --port 0");
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("is not a directory"), std::string::npos) << r.err;
  r = run_cli("serve --models '" + work.string() + "' --port 70000");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--port must be in [0, 65535]"), std::string::npos) << r.err;
  r = run_cli("serve --models '" + work.string() + "' --queue 0");
  EXPECT_EQ(r.code, 2);
  // A port in use.
  ServeProcess& s = shared_server();
  ASSERT_TRUE(s.running());
  r = run_cli("serve --models '" + work.string() + "' --port " + std::to_string(s.port()));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("cannot listen on 127.0.0.1"), std::string::npos) << r.err;
}

TEST(Serve, SigintAndSigtermStopCleanly) {
  const fs::path work = fresh_dir("signals");
  for (int sig : {SIGINT, SIGTERM}) {
    ServeProcess s(models_dir(), {}, work);
    ASSERT_TRUE(s.running()) << s.log();
    auto c = s.client();
    int status = 0;
    query_get(c, "/api/tiles/tex/0/0/0.png", &status);
    EXPECT_EQ(status, 200);
    EXPECT_EQ(s.stop(sig), 0) << s.log();
    EXPECT_NE(s.log().find("stopped (" + std::string(sig == SIGINT ? "SIGINT" : "SIGTERM") + ")"),
              std::string::npos)
        << s.log();
  }
}

}  // namespace
}  // namespace stex
