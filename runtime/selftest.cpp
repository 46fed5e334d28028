// The known-answer self-test: rows, the check, hashes, the per-device cache and the gate (selftest.h).
#include "runtime/selftest.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "runtime/cl_error.h"
#include "runtime/kernel_sources.h"
#include "runtime/program.h"
#include "runtime/selftest_cases.h"
#include "runtime/texton_renderer.h"

namespace stex {

namespace {

using json = nlohmann::json;

std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t h = 0xcbf29ce484222325ull) {
  const unsigned char* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    h ^= p[i];
    h *= 0x100000001b3ull;
  }
  return h;
}

std::string hex16(std::uint64_t v) {
  char s[17];
  std::snprintf(s, sizeof s, "%016" PRIx64, v);
  return s;
}

// A row's file name: kind and path with spaces as '-' ("texton_gather-local-order-3.json").
std::string row_file_name(const SelftestRow& row) {
  std::string s = row.kind + "_" + row.path + ".json";
  for (char& c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')) c = '-';
  return s;
}

// Writes `text` to `target` atomically (core/atomic_file.h); false when it cannot (the cache is best effort).
bool write_atomic(const std::filesystem::path& target, const std::string& text) {
  try {
    write_file_atomic(target.string(), text.data(), text.size());
    return true;
  } catch (const Error&) {
    return false;
  }
}

json result_json(const SelftestResult& r) {
  return json{{"kind", r.row.kind},         {"path", r.row.path},   {"pass", r.pass},
              {"ms", r.ms},                 {"expected", r.expected}, {"actual", r.actual},
              {"values", r.values},         {"differing", r.differing}, {"error", r.error},
              {"note", r.note},             {"refused", r.refused},
              {"time", std::int64_t(std::time(nullptr))}};
}

std::string device_text(const DeviceInfo& d) {
  return "device '" + d.name + "' (platform '" + d.platform_name + "', driver version '" + d.driver_version + "')";
}

}  // namespace

std::string texton_selftest_strategy(const std::string& strategy, const DeviceInfo& device) {
  const TextonStrategy asked = parse_texton_strategy(strategy);
  TextonStrategy s = resolve_texton_strategy(asked, device.type);
  if (s == TextonStrategy::GatherLocal && device.local_mem == 0) s = TextonStrategy::Gather;
  return texton_strategy_name(s);
}

SelftestRow filtered_selftest_row(bool mapped) { return {"texton", mapped ? "mapped" : "filtered"}; }

SelftestRow texton_selftest_row(const std::string& strategy, int order) {
  return {"texton", order == 1 ? strategy : strategy + " order " + std::to_string(order)};
}

std::vector<SelftestRow> selftest_rows(const DeviceInfo& device) {
  const std::string auto_strategy = texton_selftest_strategy("auto", device);
  return {{"texton", "splat"},
          {"texton", "gather"},
          {"texton", "gather-local"},
          {"texton", "filtered"},
          {"texton", "mapped"},
          texton_selftest_row(auto_strategy, 3),
          {"lrp", "gather"},
          {"gabor", "gather"},
          {"gabor", "filtered"},
          {"mix", "gather"},
          {"mix", "filtered"},
          {"cs-spot", "lattice"},
          {"cs-spot", "general"},
          {"cs-rpn", "random-phase"},
          {"cs-rpn", "gabor"},
          {"cs-rpn", "phasor"},
          {"cs-rpn", "fourier"},
          {"tb", "aligned"},
          {"tb", "scaled"},
          {"cs-tb", "aligned"},
          {"cs-tb", "sub-pixel"},
          {"cs-tb", "scaled"},
          {"surface", "points"}};
}

std::string selftest_result_json(const SelftestResult& result) { return result_json(result).dump(); }

SelftestResult selftest_result_from_json(const std::string& text) {
  try {
    const json j = json::parse(text);
    SelftestResult r;
    r.row = {j.at("kind").get<std::string>(), j.at("path").get<std::string>()};
    r.pass = j.at("pass").get<bool>();
    r.ms = j.value("ms", 0.0);
    r.expected = j.value("expected", "");
    r.actual = j.value("actual", "");
    r.values = j.value("values", std::size_t(0));
    r.differing = j.value("differing", std::size_t(0));
    r.error = j.value("error", "");
    r.note = j.value("note", "");
    r.refused = j.value("refused", "");
    return r;
  } catch (const std::exception& e) {
    throw Error(ErrorKind::Internal, std::string("malformed self-test result: ") + e.what());
  }
}

std::string selftest_hash(const std::vector<float>& values) {
  return hex16(fnv1a64(values.data(), values.size() * sizeof(float)));
}

SelftestResult run_selftest_row(Context& ctx, const SelftestRow& row) {
  const auto t0 = std::chrono::steady_clock::now();
  SelftestResult r;
  r.row = row;
  KnownAnswer ka;
  try {
    ka = selftest_known_answer(ctx, row);
  } catch (const OpenCLError&) {
    throw;
  } catch (const Error& e) {
    if (e.kind() != ErrorKind::Device) throw;
    r.refused = e.what();  // the renderer refuses the path on this device before running it
    r.error = "refused by stex on this device: " + r.refused;
    return r;
  }
  r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  r.expected = selftest_hash(ka.reference);
  r.actual = selftest_hash(ka.device);
  r.note = ka.note;
  r.values = ka.reference.size();
  if (ka.device.size() != ka.reference.size()) {
    r.differing = std::max(ka.device.size(), ka.reference.size());
    r.error = "the device returned " + std::to_string(ka.device.size()) + " values, the reference " +
              std::to_string(ka.reference.size());
    return r;
  }
  for (std::size_t i = 0; i < ka.device.size(); ++i)
    if (std::memcmp(&ka.device[i], &ka.reference[i], sizeof(float)) != 0) ++r.differing;
  r.pass = r.differing == 0;
  if (!r.pass)
    r.error = std::to_string(r.differing) + " of " + std::to_string(r.values) +
              " values differ from the C++ reference (expected hash " + r.expected + ", actual " + r.actual + ")";
  return r;
}

std::string SelftestKey::id() const {
  const std::string all = device + '\n' + device_version + '\n' + driver + '\n' + platform + '\n' +
                          platform_version + '\n' + version + '\n' + kernels + '\n' + defines;
  return hex16(fnv1a64(all.data(), all.size()));
}

std::string kernel_sources_hash() {
  static const std::string hash = [] {
    std::size_t count = 0;
    const EmbeddedSource* sources = embedded_sources(&count);
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (std::size_t i = 0; i < count; ++i) {
      const std::string name = sources[i].name;
      if (name.size() < 3 || name.compare(name.size() - 3, 3, ".cl") != 0) continue;
      std::string text;
      try {
        text = resolve_kernel_source(name);  // STEX_KERNEL_DIR: the files there
      } catch (const Error& e) {
        text = std::string("unresolved: ") + e.what();
      }
      h = fnv1a64(name.data(), name.size() + 1, h);
      h = fnv1a64(text.data(), text.size(), h);
    }
    return hex16(h);
  }();
  return hash;
}

SelftestKey selftest_key(const DeviceInfo& device) {
  SelftestKey k;
  k.device = device.name;
  k.device_version = device.version;
  k.driver = device.driver_version;
  k.platform = device.platform_name;
  k.platform_version = device.platform_version;
  k.version = STEX_VERSION_STRING;
  k.kernels = kernel_sources_hash();
  k.defines = test_kernel_defines();
  return k;
}

std::string selftest_cache_dir() {
  const char* own = std::getenv("STEX_SELFTEST_CACHE");
  if (own && *own) return own;
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  const char* home = std::getenv("HOME");
  if (xdg && *xdg) return (std::filesystem::path(xdg) / "stex" / "selftest").string();
  if (home && *home) return (std::filesystem::path(home) / ".cache" / "stex" / "selftest").string();
  return "";
}

std::optional<SelftestResult> read_selftest_cache(const SelftestKey& key, const SelftestRow& row) {
  const std::string dir = selftest_cache_dir();
  if (dir.empty()) return std::nullopt;
  const std::filesystem::path file = std::filesystem::path(dir) / key.id() / row_file_name(row);
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream text;
  text << in.rdbuf();
  try {
    SelftestResult r = selftest_result_from_json(text.str());
    if (!(r.row == row)) return std::nullopt;
    r.cached = true;
    r.file = file.string();
    return r;
  } catch (const std::exception&) {
    return std::nullopt;  // damaged: run the row again
  }
}

std::string write_selftest_cache(const SelftestKey& key, const SelftestResult& result) {
  const std::string root = selftest_cache_dir();
  if (root.empty()) return "";
  const std::filesystem::path dir = std::filesystem::path(root) / key.id();
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return "";
  if (!std::filesystem::exists(dir / "key.json", ec)) {
    const json k{{"device", key.device},     {"device_version", key.device_version},
                 {"driver", key.driver},     {"platform", key.platform},
                 {"platform_version", key.platform_version}, {"stex_version", key.version},
                 {"kernels", key.kernels},   {"defines", key.defines}};
    write_atomic(dir / "key.json", k.dump(2) + "\n");
  }
  const std::filesystem::path file = dir / row_file_name(result.row);
  return write_atomic(file, selftest_result_json(result) + "\n") ? file.string() : "";
}

std::string selftest_failure_message(const DeviceInfo& device, const SelftestResult& r) {
  std::string m = "device self-test failed: " + r.row.name() + " on " + device_text(device) + ": ";
  m += r.error.empty() ? "the device's output differs from the C++ reference" : r.error;
  if (!r.expected.empty() && r.error.find(r.expected) == std::string::npos)
    m += " (expected hash " + r.expected + ", actual " + r.actual + ")";
  m += ". stex refuses this device for " + r.row.name() + "; `stex selftest --device ...` checks every kind";
  if (r.cached && !r.file.empty()) m += " (cached result " + r.file + "; delete it to check again)";
  return m;
}

namespace {
std::mutex g_seen_mutex;
std::vector<std::pair<std::string, SelftestResult>> g_seen;  // (key id, result), first meeting only

void record_seen(const std::string& id, const SelftestResult& r) {
  std::lock_guard<std::mutex> lock(g_seen_mutex);
  for (const auto& e : g_seen)
    if (e.first == id && e.second.row == r.row) return;
  g_seen.emplace_back(id, r);
}
}  // namespace

std::vector<SelftestResult> selftest_seen(const DeviceInfo& device) {
  const std::string id = selftest_key(device).id();
  std::lock_guard<std::mutex> lock(g_seen_mutex);
  std::vector<SelftestResult> out;
  for (const auto& e : g_seen)
    if (e.first == id) out.push_back(e.second);
  return out;
}

std::vector<SelftestResult> ensure_selftest(Context& ctx, const std::vector<SelftestRow>& rows) {
  static std::mutex mutex;
  static std::set<std::string> passed;  // key id + row name, this process
  std::vector<SelftestResult> ran;
  if (rows.empty()) return ran;
  const SelftestKey key = selftest_key(ctx.info());
  const std::string id = key.id();
  for (const SelftestRow& row : rows) {
    const std::string memo = id + '\n' + row.name();
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (passed.count(memo)) continue;
    }
    SelftestResult r;
    if (auto cached = read_selftest_cache(key, row)) {
      r = *cached;
    } else {
      r = run_selftest_row(ctx, row);  // device errors propagate, uncached
      if (r.refused.empty()) r.file = write_selftest_cache(key, r);
      ran.push_back(r);
    }
    record_seen(id, r);
    if (!r.refused.empty()) throw Error(ErrorKind::Device, r.refused);  // as the render would
    if (!r.pass) throw Error(ErrorKind::Device, selftest_failure_message(ctx.info(), r));
    std::lock_guard<std::mutex> lock(mutex);
    passed.insert(memo);
  }
  return ran;
}

bool test_kernel_defines_supported() {
#ifdef STEX_TESTING
  return true;
#else
  return false;
#endif
}

std::string test_kernel_defines() {
  if (!test_kernel_defines_supported()) return "";
  const char* v = std::getenv("STEX_TEST_KERNEL_DEFINES");
  if (!v || !*v) return "";
  std::istringstream in(v);
  std::string word, out;
  while (in >> word)
    if (word.size() > 2 && word.compare(0, 2, "-D") == 0) out += (out.empty() ? "" : " ") + word;
  return out;
}

}  // namespace stex
