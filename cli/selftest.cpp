// `stex selftest [--device D] [--json] [--only KIND|"KIND PATH"]... [--timeout S]`: the known-answer self-test
// (runtime/selftest.h) of every kind and path on one device, one row per child process, so that a driver
// crash fails its row instead of the run. Exit 0 when every row passes, else 4 (the Device exit code).
//
// Each row re-executes this binary (/proc/self/exe) as the hidden subcommand `selftest-row KIND PATH`, which
// prints its result as one JSON line and exits 0 (pass) or 4 (the device's bits differ). The parent records
// every result in the self-test cache (passes, mismatches, and crashes: a later `stex render` refuses the
// path instead of crashing), except errors and time-outs, which say nothing about the bits.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli/commands.h"
#include "core/error.h"
#include "runtime/context.h"
#include "runtime/device.h"
#include "runtime/selftest.h"

namespace stex::cli {
namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

struct SelftestOptions {
  bool json = false;
  double timeout_s = 600.0;
  std::vector<std::string> only;  // kinds or "kind path" names; empty: every row
};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

std::string last_line(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  const auto nl = s.rfind('\n');
  return nl == std::string::npos ? s : s.substr(nl + 1);
}

std::string signal_text(int sig) {
  const char* name = sig == SIGSEGV ? "SIGSEGV" : sig == SIGABRT ? "SIGABRT" : sig == SIGBUS ? "SIGBUS"
                     : sig == SIGFPE ? "SIGFPE" : sig == SIGILL ? "SIGILL" : sig == SIGKILL ? "SIGKILL" : nullptr;
  return "crashed: signal " + std::to_string(sig) + (name ? std::string(" (") + name + ")" : "");
}

// Runs `exe --device INDEX selftest-row KIND PATH` with stdout and stderr in files of `dir`. Returns the result:
// the child's JSON line, or a failed row saying how the child ended (crash, error, time-out). `record` tells
// the caller whether the result belongs in the cache (not for errors and time-outs).
SelftestResult run_child(const std::string& exe, int device_index, const SelftestRow& row, const std::string& dir,
                         double timeout_s, bool* record) {
  const std::string out = dir + "/out", err = dir + "/err";
  const std::string index = std::to_string(device_index);
  const auto t0 = Clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) throw Error(ErrorKind::Internal, std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    const int o = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int e = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (o < 0 || e < 0 || ::dup2(o, 1) < 0 || ::dup2(e, 2) < 0) ::_exit(127);
    const char* argv[] = {exe.c_str(), "--device", index.c_str(), "selftest-row", row.kind.c_str(), row.path.c_str(),
                          nullptr};
    ::execv(exe.c_str(), const_cast<char* const*>(argv));
    ::_exit(127);
  }
  int status = 0;
  bool timed_out = false;
  for (;;) {
    const pid_t w = ::waitpid(pid, &status, WNOHANG);
    if (w == pid) break;
    if (w < 0 && errno != EINTR) throw Error(ErrorKind::Internal, std::string("waitpid: ") + std::strerror(errno));
    if (std::chrono::duration<double>(Clock::now() - t0).count() > timeout_s) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      timed_out = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  SelftestResult r;
  r.row = row;
  *record = false;
  const std::string line = last_line(slurp(out));
  if (!timed_out && WIFEXITED(status) && (WEXITSTATUS(status) == 0 || WEXITSTATUS(status) == 4) && !line.empty() &&
      line[0] == '{') {
    r = selftest_result_from_json(line);
    *record = r.refused.empty();  // a refusal is stex's decision, not a result about the bits
  } else if (timed_out) {
    r.error = "timed out after " + std::to_string(int(timeout_s)) + " s";
  } else if (WIFSIGNALED(status)) {
    r.error = signal_text(WTERMSIG(status));
    *record = true;  // a crash refuses the path from now on (stex render exits 4 instead of crashing)
  } else {
    const std::string why = last_line(slurp(err));
    r.error = "exit " + std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + (why.empty() ? "" : ": " + why);
  }
  r.ms = ms;
  return r;
}

bool selected(const SelftestOptions& o, const SelftestRow& row) {
  if (o.only.empty()) return true;
  for (const std::string& s : o.only)
    if (s == row.kind || s == row.name()) return true;
  return false;
}

std::string self_exe() {
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw Error(ErrorKind::Internal, "cannot find the stex executable (/proc/self/exe): " + ec.message());
  return p.string();
}

// "pass", "fail", or "refused" (stex refuses the path on this device up front: no failure of the bits).
const char* state(const SelftestResult& r) { return r.pass ? "pass" : r.refused.empty() ? "fail" : "refused"; }

json report_json(const DeviceInfo& d, const SelftestKey& key, const std::vector<SelftestResult>& rows, bool pass) {
  json list = json::array();
  for (const SelftestResult& r : rows)
    list.push_back({{"kind", r.row.kind},     {"path", r.row.path},   {"pass", r.pass},
                    {"state", state(r)},      {"ms", r.ms},           {"expected", r.expected},
                    {"actual", r.actual},     {"error", r.error},     {"note", r.note},
                    {"refused", r.refused},   {"values", r.values},   {"differing", r.differing}});
  return json{{"device", d.name},          {"platform", d.platform_name}, {"driver", d.driver_version},
              {"device_version", d.version}, {"type", d.type_name},       {"stex_version", STEX_VERSION_STRING},
              {"kernels", key.kernels},    {"defines", key.defines},      {"cache", selftest_cache_dir()},
              {"pass", pass},              {"rows", list}};
}

void run_selftest(const SelftestOptions& o, const GlobalOptions& global) {
  const DeviceInfo device = select_device(global.device);
  const SelftestKey key = selftest_key(device);
  std::vector<SelftestRow> rows;
  for (const SelftestRow& r : selftest_rows(device))
    if (selected(o, r)) rows.push_back(r);
  if (rows.empty()) throw Error(ErrorKind::Usage, "--only selects no row (see `stex selftest --help` for the rows)");
  const std::string exe = self_exe();
  char tmpl[] = "/tmp/stex-selftest-XXXXXX";
  if (!::mkdtemp(tmpl)) throw Error(ErrorKind::Output, "cannot create a temporary directory for the self-test");
  const std::string dir = tmpl;
  const bool quiet = global.quiet || o.json;
  if (!quiet)
    std::printf("stex selftest: device '%s' (platform '%s', driver version '%s', %s)\n", device.name.c_str(),
                device.platform_name.c_str(), device.driver_version.c_str(), device.version.c_str());
  std::vector<SelftestResult> results;
  std::size_t passed = 0, refused = 0;
  const auto t0 = Clock::now();
  for (const SelftestRow& row : rows) {
    bool record = false;
    SelftestResult r = run_child(exe, device.index, row, dir, o.timeout_s, &record);
    if (record) write_selftest_cache(key, r);
    passed += r.pass ? 1 : 0;
    refused += r.refused.empty() ? 0 : 1;
    if (!quiet) {
      std::printf("  %-7s %-28s %8.0f ms", r.pass ? "PASS" : r.refused.empty() ? "FAIL" : "REFUSED", row.name().c_str(),
                  r.ms);
      if (!r.error.empty()) std::printf("  %s", r.error.c_str());
      if (!r.note.empty()) std::printf("  [%s]", r.note.c_str());
      std::printf("\n");
      std::fflush(stdout);
    }
    results.push_back(std::move(r));
  }
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  const bool pass = passed + refused == results.size();
  if (o.json) std::printf("%s\n", report_json(device, key, results, pass).dump(2).c_str());
  else if (!quiet)
    std::printf("%zu of %zu rows passed%s (%.1f s)\n", passed, results.size(),
                refused ? (", " + std::to_string(refused) + " refused by stex on this device").c_str() : "",
                std::chrono::duration<double>(Clock::now() - t0).count());
  std::fflush(stdout);
  if (!pass)
    throw Error(ErrorKind::Device, "device self-test: " + std::to_string(results.size() - passed - refused) + " of " +
                                       std::to_string(results.size()) + " rows failed on device '" + device.name +
                                       "' (platform '" + device.platform_name + "', driver version '" +
                                       device.driver_version + "')");
}

// The child: one row, uncached; its result as one JSON line on stdout; exit 4 when the bits differ.
void run_row(const std::string& kind, const std::string& path, const GlobalOptions& global) {
  std::unique_ptr<Context> ctx = Context::create(global.device);
  // Test builds (STEX_TESTING): STEX_TEST_SELFTEST_CRASH="KIND PATH" crashes that row's process, as a driver
  // might, so that the tests see the parent report it.
  const char* crash = std::getenv("STEX_TEST_SELFTEST_CRASH");
  if (test_kernel_defines_supported() && crash && SelftestRow{kind, path}.name() == crash) {
    ::signal(SIGSEGV, SIG_DFL);  // the OpenCL runtime may have installed its own handler
    ::raise(SIGSEGV);
  }
  const SelftestResult r = run_selftest_row(*ctx, SelftestRow{kind, path});
  std::printf("%s\n", selftest_result_json(r).c_str());
  std::fflush(stdout);
  if (!r.pass) throw Error(ErrorKind::Device, selftest_failure_message(ctx->info(), r));
}

const char* k_help =
    "Known-answer self-test of the OpenCL device: for every model kind and evaluation path (texton splat, "
    "gather, gather-local, filtered, mapped, the order-3 texton with the device's default strategy; lrp; gabor; "
    "mix; cs-spot lattice and general; cs-rpn random-phase, gabor, phasor, fourier; tb aligned and scaled; cs-tb "
    "aligned, sub-pixel and scaled; surface points) it renders a small synthetic model built into stex on the "
    "device and with the C++ reference, and compares the bits (hashes reported). A path stex refuses on the "
    "device up front (e.g. the texton splat on rusticl) is listed as REFUSED with the reason, not as a failure. "
    "Each row runs in its own "
    "process: a driver crash fails that row ('crashed: signal 11'). Results are cached per device, driver and "
    "kernel sources (~/.cache/stex/selftest or $XDG_CACHE_HOME/stex/selftest), where every `stex render` "
    "looks before its first render on a device: it checks the path it is about to use, and refuses it with "
    "exit 4 if the bits differ. Run it as a render farm's prolog or a GPU node's admission check.";

}  // namespace

void add_selftest(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<SelftestOptions>();
  auto* sub = app.add_subcommand("selftest", k_help);
  sub->add_flag("--json", o->json,
                "Print a JSON report: device, platform, driver, pass, rows [{kind, path, pass, ms, expected, actual, "
                "error, note}]");
  sub->add_option("--only", o->only, "Run only these rows: a kind (texton) or a row (\"texton splat\"); repeatable");
  sub->add_option("--timeout", o->timeout_s, "Seconds a row may take before it is killed and fails (default 600)");
  sub->footer(
      "Exit codes: 0 every row passed; 4 a row failed (its bits differ, it crashed, errored or timed out), or no "
      "device matches --device; 2 bad options.");
  sub->callback([o, &global] { run_selftest(*o, global); });

  // The child process of one row (hidden).
  auto row = std::make_shared<std::pair<std::string, std::string>>();
  auto* child = app.add_subcommand("selftest-row", "One self-test row (internal: stex selftest runs it)");
  child->group("");
  child->add_option("kind", row->first)->required();
  child->add_option("path", row->second)->required();
  child->callback([row, &global] { run_row(row->first, row->second, global); });
}

}  // namespace stex::cli
