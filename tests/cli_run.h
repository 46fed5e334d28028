// Runs the stex executable (STEX_CLI_PATH) as a subprocess for the CLI end-to-end tests of the test areas:
// stdout and stderr go to files in a scratch directory under STEX_TEST_TMP_DIR and are read back.
#pragma once
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace stex::test {

struct CliRun {
  int code = -1;  // exit code (128 when the process did not exit normally)
  std::string out, err;
};

inline std::string slurp_file(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

// `args` is appended to the quoted executable path as shell words; `scratch` names the directory (under
// STEX_TEST_TMP_DIR) that holds the captured output. With `cwd`, the command runs in that directory (relative
// paths in `args` are relative to it).
inline CliRun run_stex_cli(const std::string& args, const std::string& scratch, const std::string& cwd = "") {
  const std::filesystem::path dir = std::filesystem::path(STEX_TEST_TMP_DIR) / scratch;
  std::filesystem::create_directories(dir);
  const std::string cd = cwd.empty() ? "" : "cd '" + cwd + "' && ";
  const std::string cmd = cd + "'" + std::string(STEX_CLI_PATH) + "' " + args + " >'" + (dir / "o").string() +
                          "' 2>'" + (dir / "e").string() + "'";
  const int st = std::system(cmd.c_str());
  CliRun r;
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : 128;
  r.out = slurp_file(dir / "o");
  r.err = slurp_file(dir / "e");
  return r;
}

}  // namespace stex::test
