// Helpers of the stex serve tests: the real binary as a subprocess on a free loopback port (--port 0
// --port-file), an HTTP client, the CLI as a subprocess, files and images.
#pragma once
#include <fcntl.h>
#include <signal.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <httplib.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "test_device.h"

namespace stex::test {

namespace fs = std::filesystem;

inline std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

inline void write_file(const fs::path& p, const std::string& s) {
  std::ofstream out(p, std::ios::binary);
  out << s;
}

inline fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::path(STEX_TEST_TMP_DIR) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

struct CliResult {
  int code = -1;
  std::string out, err;
};

inline CliResult run_cli(const std::string& args) {
  const fs::path dir = fs::path(STEX_TEST_TMP_DIR) / "cli_subprocess";
  fs::create_directories(dir);
  const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  // Bounded: a `stex serve` that should have failed must not hang the test.
  const std::string cmd =
      "timeout -s TERM 300 '" + std::string(STEX_CLI_PATH) + "' " + args + " >'" + out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  r.out = read_file(out);
  r.err = read_file(err);
  return r;
}

// `stex serve` in a child process; the destructor stops it with SIGTERM.
//
// On a test device other than PoCL (STEX_TEST_DEVICE=llvmpipe: rusticl keeps no compiled kernels on disk, so
// its warm-up builds and self-tests every model's kernels, 2 minutes and more on 2 cores, and a request's
// first use of a path compiles for seconds) the service gets a per-request time limit of 300 s unless the
// test sets its own, and start-up may take 600 s: the tests check answers, not the device's compile speed.
// On PoCL the default limit (10 s) and a 60 s start-up bound stay.
class ServeProcess {
 public:
  ServeProcess(const fs::path& models, const std::vector<std::string>& extra, const fs::path& work) {
    port_file_ = work / "port";
    log_ = work / "serve.log";
    fs::remove(port_file_);
    std::vector<std::string> args = {STEX_CLI_PATH, "serve", "--models", models.string(), "--port", "0",
                                     "--port-file", port_file_.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const bool slow_device = !test_device_is_pocl();
    if (slow_device && std::find(extra.begin(), extra.end(), "--time-limit") == extra.end())
      args.insert(args.end(), {"--time-limit", "300000"});
    pid_ = ::fork();
    if (pid_ == 0) {
      const int fd = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) {
        ::dup2(fd, 1);
        ::dup2(fd, 2);
      }
      std::vector<char*> argv;
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(slow_device ? 600 : 60);
    while (std::chrono::steady_clock::now() < until) {
      std::ifstream in(port_file_);
      if (in >> port_) break;
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  ~ServeProcess() { stop(); }
  bool running() const { return pid_ > 0 && port_ > 0; }
  int port() const { return port_; }
  pid_t pid() const { return pid_; }
  std::string log() const { return read_file(log_); }
  // Sends `sig` and waits: the exit status (0 on a clean shutdown).
  int stop(int sig = SIGTERM) {
    if (pid_ <= 0) return -1;
    ::kill(pid_, sig);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  httplib::Client client() const {
    httplib::Client c("127.0.0.1", port_);
    c.set_read_timeout(test_device_is_pocl() ? 60 : 400);
    c.set_connection_timeout(5);
    return c;
  }
  // Resident set size of the server (kB), from /proc.
  long rss_kb() const {
    std::ifstream in("/proc/" + std::to_string(pid_) + "/status");
    std::string line;
    while (std::getline(in, line))
      if (line.rfind("VmRSS:", 0) == 0) return std::strtol(line.c_str() + 6, nullptr, 10);
    return -1;
  }

 private:
  pid_t pid_ = -1;
  int port_ = 0;
  fs::path port_file_, log_;
};

struct Decoded {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;
};

inline Decoded decode(const fs::path& p) {
  Decoded d;
  auto in = OIIO::ImageInput::open(p.string());
  if (!in) return d;
  d.width = in->spec().width;
  d.height = in->spec().height;
  d.channels = in->spec().nchannels;
  d.pixels.resize(std::size_t(d.width) * d.height * d.channels);
  if (!in->read_image(0, 0, 0, d.channels, OIIO::TypeDesc::FLOAT, d.pixels.data())) d.pixels.clear();
  return d;
}

}  // namespace stex::test
