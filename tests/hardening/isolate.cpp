// Forked, time- and memory-bounded batches for the hardening tests (see isolate.h).
#include "hardening/isolate.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <exception>
#include <sstream>

namespace stex::test {
namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool k_asan = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool k_asan = true;
#else
constexpr bool k_asan = false;
#endif
#else
constexpr bool k_asan = false;
#endif

void write_all(int fd, const std::string& s) {
  const char* p = s.data();
  std::size_t left = s.size();
  while (left > 0) {
    ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return;
    }
    p += n;
    left -= std::size_t(n);
  }
}

}  // namespace

bool memory_cap_active() { return !k_asan; }

BatchResult run_isolated_batch(
    const std::vector<std::uint64_t>& ids,
    const std::function<void(std::uint64_t, const std::function<void(const std::string&)>&)>& body,
    const IsolatedLimits& limits) {
  BatchResult result;
  int fds[2];
  if (::pipe(fds) != 0) {
    result.failures.push_back(std::string("pipe: ") + std::strerror(errno));
    return result;
  }
  std::fflush(nullptr);
  pid_t pid = ::fork();
  if (pid < 0) {
    result.failures.push_back(std::string("fork: ") + std::strerror(errno));
    return result;
  }
  if (pid == 0) {
    ::close(fds[0]);
    if (!k_asan && limits.address_space > 0) {
      rlimit rl{limits.address_space, limits.address_space};
      ::setrlimit(RLIMIT_AS, &rl);
    }
    // Third-party readers print their own diagnostics (libpng, libtiff): keep the test log readable.
    if (int null_fd = ::open("/dev/null", O_WRONLY); null_fd >= 0) ::dup2(null_fd, 2);
    // Each input gets per_input_seconds, but never more than what is left of the batch's bound: a hang
    // of one input is caught after its own bound, and the batch as a whole stays bounded.
    const std::time_t batch_start = std::time(nullptr);
    int code = 0;
    for (std::uint64_t id : ids) {
      const long left = long(limits.seconds) - long(std::time(nullptr) - batch_start);
      ::alarm(unsigned(std::max(1L, std::min(long(limits.per_input_seconds), left))));
      write_all(fds[1], "S " + std::to_string(id) + "\n");
      auto fail = [&](const std::string& what) {
        std::string line = what;
        for (char& c : line)
          if (c == '\n') c = ' ';
        write_all(fds[1], "F " + std::to_string(id) + " " + line + "\n");
        code = 3;
      };
      try {
        body(id, fail);
      } catch (const std::exception& e) {
        fail(std::string("unexpected exception: ") + e.what());
      } catch (...) {
        fail("unexpected non-std exception");
      }
    }
    write_all(fds[1], "D\n");
    ::close(fds[1]);
    std::fflush(nullptr);
    ::_exit(code);
  }
  ::close(fds[1]);
  std::string text;
  char buf[4096];
  for (;;) {
    ssize_t n = ::read(fds[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    text.append(buf, std::size_t(n));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }

  std::istringstream lines(text);
  std::string line, in_flight = "(none)";
  bool done = false;
  while (std::getline(lines, line)) {
    if (line.rfind("S ", 0) == 0) {
      in_flight = line.substr(2);
      ++result.inputs_done;
    } else if (line.rfind("F ", 0) == 0) {
      auto sp = line.find(' ', 2);
      result.failures.push_back("input " + line.substr(2, sp - 2) + ": " +
                                (sp == std::string::npos ? std::string() : line.substr(sp + 1)));
    } else if (line == "D") {
      done = true;
    }
  }
  if (WIFSIGNALED(status)) {
    int sig = WTERMSIG(status);
    result.failures.push_back("input " + in_flight + ": child killed by signal " + std::to_string(sig) +
                              (sig == SIGALRM ? " (hang: time bound exceeded)" : " (crash)"));
  } else if (WIFEXITED(status) && WEXITSTATUS(status) != 0 && WEXITSTATUS(status) != 3) {
    result.failures.push_back("input " + in_flight + ": child exited with code " +
                              std::to_string(WEXITSTATUS(status)) + " (crash caught by a sanitizer, or exit())");
  } else if (!done) {
    result.failures.push_back("input " + in_flight + ": child ended before finishing its batch");
  }
  return result;
}

}  // namespace stex::test
