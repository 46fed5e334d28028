// Helpers of the farm tests: fresh temp directories, running subprocesses (exit code, signal, captured
// output, peak RSS through wait4), and checks on output directories (no temp files, valid outputs).
#pragma once
#include <dirent.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/atomic_file.h"

namespace stex::farm::test {

inline std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// A fresh, empty directory under STEX_TEST_TMP_DIR named after the running test.
inline std::string fresh_dir(const std::string& suffix = "") {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string dir =
      std::string(STEX_TEST_TMP_DIR) + "/" + info->test_suite_name() + "." + info->name() + suffix;
  std::string cmd = "rm -rf '" + dir + "' && mkdir -p '" + dir + "'";
  if (std::system(cmd.c_str()) != 0) ADD_FAILURE() << "cannot create " << dir;
  return dir;
}

inline std::vector<std::string> list_dir(const std::string& dir) {
  std::vector<std::string> out;
  if (DIR* d = ::opendir(dir.c_str())) {
    while (dirent* e = ::readdir(d)) {
      std::string n = e->d_name;
      if (n != "." && n != "..") out.push_back(n);
    }
    ::closedir(d);
  }
  return out;
}

inline int count_temp_files(const std::string& dir) {
  int n = 0;
  for (const auto& name : list_dir(dir)) n += is_temp_name(name) ? 1 : 0;
  return n;
}

inline bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

inline ino_t inode_of(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? st.st_ino : 0;
}

// In-process farm::run reads the scheduler variables: clear them so that the tests select their own tiles.
inline void clear_scheduler_env() {
  ::unsetenv("SLURM_ARRAY_TASK_ID");
  ::unsetenv("JOB_COMPLETION_INDEX");
}

struct ProcessResult {
  int exit_code = -1;  // -1 when killed by a signal
  int signal = 0;
  long max_rss_kb = 0;
  std::string out, err;
};

// Starts argv[0] with argv; stdout/stderr go to files (returned paths). `env` entries "K=V" are added.
inline pid_t spawn(const std::vector<std::string>& argv, const std::string& out_path,
                   const std::string& err_path, const std::vector<std::string>& env = {}) {
  pid_t pid = ::fork();
  if (pid == 0) {
    int fo = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    int fe = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fo, 1);
    ::dup2(fe, 2);
    ::unsetenv("SLURM_ARRAY_TASK_ID");  // the test's own scheduler must not select the child's tiles
    ::unsetenv("JOB_COMPLETION_INDEX");
    for (const auto& kv : env) ::putenv(const_cast<char*>(kv.c_str()));
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  return pid;
}

inline ProcessResult wait_process(pid_t pid, const std::string& out_path, const std::string& err_path) {
  ProcessResult r;
  int status = 0;
  struct rusage ru {};
  while (::wait4(pid, &status, 0, &ru) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  r.max_rss_kb = ru.ru_maxrss;
  r.out = slurp(out_path);
  r.err = slurp(err_path);
  return r;
}

// Runs a command to completion. Output is captured in files beside `scratch_prefix`.
inline ProcessResult run_process(const std::vector<std::string>& argv, const std::string& scratch_prefix,
                                 const std::vector<std::string>& env = {}) {
  std::string o = scratch_prefix + ".stdout", e = scratch_prefix + ".stderr";
  pid_t pid = spawn(argv, o, e, env);
  return wait_process(pid, o, e);
}

}  // namespace stex::farm::test
