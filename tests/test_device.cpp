// The test device (test_device.h): STEX_TEST_DEVICE resolved by runtime/device's select_device.
#include "test_device.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <sstream>

#include "runtime/device.h"

namespace stex::test {
namespace {

const char* k_pocl_platform = "Portable Computing Language";

bool write_all(int fd, const std::string& s) {
  std::size_t done = 0;
  while (done < s.size()) {
    const ssize_t n = ::write(fd, s.data() + done, s.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += std::size_t(n);
  }
  return true;
}

// Fields are separated by '\n'; device and platform names hold none.
TestDevice probe(const std::string& spec) {
  TestDevice d;
  d.spec = spec;
  int fds[2];
  if (::pipe(fds) != 0) {
    d.error = std::string("pipe: ") + std::strerror(errno);
    return d;
  }
  std::fflush(nullptr);  // the child must not flush the parent's buffered output a second time
  const pid_t pid = ::fork();
  if (pid < 0) {
    d.error = std::string("fork: ") + std::strerror(errno);
    ::close(fds[0]);
    ::close(fds[1]);
    return d;
  }
  if (pid == 0) {
    ::close(fds[0]);
    std::string msg;
    try {
      const DeviceInfo info = select_device(spec);
      msg = "ok\n" + std::to_string(info.index) + "\n" + info.name + "\n" + info.platform_name + "\n";
    } catch (const std::exception& e) {
      msg = std::string("error\n") + e.what();
    }
    _exit(write_all(fds[1], msg) ? 0 : 3);
  }
  ::close(fds[1]);
  std::string out;
  char buf[4096];
  for (;;) {
    const ssize_t n = ::read(fds[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    out.append(buf, std::size_t(n));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    d.error = "the device probe (select_device in a child process) " +
              (WIFSIGNALED(status) ? "died of signal " + std::to_string(WTERMSIG(status))
                                   : "exited with status " + std::to_string(WEXITSTATUS(status)));
    return d;
  }
  std::istringstream in(out);
  std::string tag, index;
  std::getline(in, tag);
  if (tag == "ok" && std::getline(in, index) && std::getline(in, d.name) && std::getline(in, d.platform)) {
    d.index = std::atoi(index.c_str());
    return d;
  }
  d.name.clear();
  d.platform.clear();
  d.error = tag == "error" ? out.substr(6) : "unreadable answer from the device probe: '" + out + "'";
  return d;
}

}  // namespace

std::string test_device_spec() {
  const char* s = std::getenv("STEX_TEST_DEVICE");
  return s ? s : "";
}

const TestDevice& test_device() {
  static const TestDevice d = probe(test_device_spec());
  return d;
}

std::string describe_test_device() {
  const TestDevice& d = test_device();
  if (!d.error.empty()) return "none (" + d.error + ")";
  return "[" + std::to_string(d.index) + "] " + d.name + " (" + d.platform + ")";
}

bool test_device_is_pocl() { return test_device().platform == k_pocl_platform; }

void test_device_cl(cl_platform_id* platform, cl_device_id* device) {
  const DeviceInfo info = select_device(test_device_spec());
  if (platform) *platform = info.platform;
  if (device) *device = info.id;
}

bool init_test_device() {
  const std::string spec = test_device_spec();
  const TestDevice& d = test_device();
  if (!d.error.empty() && !spec.empty()) {
    std::fprintf(stderr, "stex tests: STEX_TEST_DEVICE='%s' selects no device: %s\n", spec.c_str(),
                 d.error.c_str());
    return false;
  }
  std::printf("stex tests: device %s\n", describe_test_device().c_str());
  std::fflush(stdout);
  // The `stex` subprocesses of the CLI tests pick their device from STEX_DEVICE (the spec, not the index:
  // tests that set POCL_DEVICES change the device list).
  ::setenv("STEX_DEVICE", spec.c_str(), 1);
  return true;
}

}  // namespace stex::test
