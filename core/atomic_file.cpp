// Unique temp file + fsync + rename: the one atomic writer (core/atomic_file.h).
#include "core/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "core/error.h"

namespace stex {

namespace {

std::string dir_of(const std::string& path) {
  std::size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

std::string base_of(const std::string& path) {
  std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string extension_of(const std::string& base) {
  std::size_t dot = base.find_last_of('.');
  if (dot == std::string::npos || dot == 0) return "";
  return base.substr(dot);
}

std::string sys_error(int err) { return std::strerror(err); }

// STEX_FARM_FAULT_FSYNC=N: the N-th commit of this process fails as if fsync returned ENOSPC.
bool injected_fsync_fault() {
  static std::atomic<long> commits{0};
  static const long fail_at = [] {
    const char* v = std::getenv("STEX_FARM_FAULT_FSYNC");
    return v ? std::strtol(v, nullptr, 10) : 0L;
  }();
  long n = ++commits;
  return fail_at > 0 && n == fail_at;
}

}  // namespace

void make_parent_dirs(const std::string& path) {
  std::string dir = dir_of(path);
  if (dir == "." || dir == "/") return;
  std::string partial;
  std::size_t pos = 0;
  while (pos != std::string::npos) {
    pos = dir.find('/', pos + 1);
    partial = dir.substr(0, pos);
    if (partial.empty()) continue;
    if (::mkdir(partial.c_str(), 0777) != 0 && errno != EEXIST) {
      throw Error(ErrorKind::Output, "cannot create directory '" + partial + "': " + sys_error(errno));
    }
  }
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw Error(ErrorKind::Output, "'" + dir + "' is not a directory");
}

TempOutput::TempOutput(const std::string& target, bool fault_hook) : target_(target), fault_hook_(fault_hook) {
  std::string base = base_of(target);
  if (base.empty())
    throw Error(ErrorKind::Usage, "output path '" + target + "' names a directory, not a file");
  std::string ext = extension_of(base);
  std::string dir = dir_of(target);
  std::string templ = (dir == "." && target.find('/') == std::string::npos ? std::string() : dir + "/") +
                      "." + base + ".stex-tmp-XXXXXX" + ext;
  std::vector<char> buf(templ.begin(), templ.end());
  buf.push_back('\0');
  int fd = ::mkstemps(buf.data(), int(ext.size()));
  if (fd < 0) {
    throw Error(ErrorKind::Output,
                "cannot write '" + target + "': cannot create a temp file in '" + dir + "': " + sys_error(errno));
  }
  ::close(fd);
  path_ = buf.data();
}

TempOutput::~TempOutput() { discard(); }

void TempOutput::discard() {
  if (!done_) {
    ::unlink(path_.c_str());
    done_ = true;
  }
}

void TempOutput::commit() {
  if (done_) throw Error(ErrorKind::Internal, "commit of a finished temp file for '" + target_ + "'");
  auto fail = [&](const std::string& what, int err) {
    discard();
    throw Error(ErrorKind::Output, "cannot write '" + target_ + "': " + what + ": " + sys_error(err));
  };
  int fd = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail("reopening the temp file", errno);
  ::fchmod(fd, 0644);  // mkstemps creates 0600; outputs are ordinary files (best effort)
  if (fault_hook_ && injected_fsync_fault()) {
    ::close(fd);
    fail("fsync (injected by STEX_FARM_FAULT_FSYNC)", ENOSPC);
  }
  if (::fsync(fd) != 0) {
    int err = errno;
    ::close(fd);
    fail("fsync", err);
  }
  if (::close(fd) != 0) fail("close", errno);
  if (::rename(path_.c_str(), target_.c_str()) != 0) fail("rename", errno);
  done_ = true;
  int dfd = ::open(dir_of(target_).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {  // make the rename durable; best effort (some filesystems refuse directory fsync)
    ::fsync(dfd);
    ::close(dfd);
  }
}

std::string write_failure_cause(const std::string& target, int saved_errno) {
  if (saved_errno == ENOSPC || saved_errno == EDQUOT || saved_errno == EIO || saved_errno == EROFS ||
      saved_errno == EFBIG)
    return sys_error(saved_errno);
  struct statvfs vfs {};
  std::string dir = dir_of(target);
  if (::statvfs(dir.c_str(), &vfs) == 0) {
    unsigned long long free_bytes = static_cast<unsigned long long>(vfs.f_bavail) * vfs.f_frsize;
    if (free_bytes < (1ULL << 20))
      return sys_error(ENOSPC) + " (" + std::to_string(free_bytes) + " bytes free in '" + dir + "')";
  }
  return "";
}

void write_file_atomic(const std::string& target, const void* data, std::size_t size) {
  TempOutput tmp(target);
  const int fd = ::open(tmp.path().c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  if (fd < 0) throw Error(ErrorKind::Output, "cannot write '" + target + "': " + sys_error(errno));
  const char* p = static_cast<const char*>(data);
  std::size_t left = size;
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : EIO;
      ::close(fd);
      throw Error(ErrorKind::Output, "cannot write '" + target + "': " + sys_error(err));
    }
    p += n;
    left -= std::size_t(n);
  }
  if (::close(fd) != 0) throw Error(ErrorKind::Output, "cannot write '" + target + "': close: " + sys_error(errno));
  tmp.commit();
}

bool is_temp_name(const std::string& filename) {
  return !filename.empty() && filename[0] == '.' && filename.find(".stex-tmp-") != std::string::npos;
}

}  // namespace stex
