// Runs the stex executable (STEX_CLI_PATH) as a subprocess for the CLI end-to-end tests of the test areas:
// stdout and stderr go to files in a scratch directory under STEX_TEST_TMP_DIR and are read back.
#pragma once
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace stex::test {

struct CliRun {
  int code = -1;  // exit code; 128 + the signal's number when the process was killed by one
  std::string out, err;
  double seconds = 0.0;  // wall time of the run
};

inline std::string slurp_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

// An empty directory under STEX_TEST_TMP_DIR (removed first if it exists).
inline std::filesystem::path fresh_test_dir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(STEX_TEST_TMP_DIR) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// Runs `<prefix> '<program>' <args>` through the shell: `args` are shell words; `prefix` is a command the
// program runs under (`env A=1 -u B`, `taskset -c 0`; empty: none); with `cwd`, in that directory (relative
// paths in `args` are relative to it). stdout and stderr go to the files o and e of `scratch` (a directory
// under STEX_TEST_TMP_DIR) and are read back.
inline CliRun run_program(const std::string& program, const std::string& args, const std::string& scratch,
                          const std::string& cwd = "", const std::string& prefix = "") {
  const std::filesystem::path dir = std::filesystem::path(STEX_TEST_TMP_DIR) / scratch;
  std::filesystem::create_directories(dir);
  const std::string cd = cwd.empty() ? "" : "cd '" + cwd + "' && ";
  const std::string cmd = cd + (prefix.empty() ? "" : prefix + " ") + "'" + program + "' " + args + " >'" +
                          (dir / "o").string() + "' 2>'" + (dir / "e").string() + "'";
  const auto t0 = std::chrono::steady_clock::now();
  const int st = std::system(cmd.c_str());
  CliRun r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
  r.out = slurp_file(dir / "o");
  r.err = slurp_file(dir / "e");
  return r;
}

// The stex executable (STEX_CLI_PATH), as run_program.
inline CliRun run_stex_cli(const std::string& args, const std::string& scratch, const std::string& cwd = "",
                           const std::string& prefix = "") {
  return run_program(STEX_CLI_PATH, args, scratch, cwd, prefix);
}

}  // namespace stex::test
