// Atomic file creation (see atomic_file.h): mkstemps beside the target, fsync, rename, directory fsync.
#include "analysis/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "runtime/error.h"

namespace stex {
namespace {

std::string directory_of(const std::string& path) {
  auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? std::string("/") : path.substr(0, slash);
}

}  // namespace

std::string create_temp_beside(const std::string& target, const std::string& suffix) {
  auto slash = target.find_last_of('/');
  std::string base = slash == std::string::npos ? target : target.substr(slash + 1);
  std::string dir = directory_of(target);
  std::string tmpl = (dir == "/" ? std::string() : dir) + "/." + base + ".tmp-XXXXXX" + suffix;
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  int fd = ::mkstemps(name.data(), int(suffix.size()));
  if (fd < 0) {
    throw Error(ErrorKind::Output, "cannot write '" + target + "': cannot create a temporary file in '" +
                                       dir + "': " + std::strerror(errno));
  }
  ::close(fd);
  return std::string(name.data());
}

void commit_temp(const std::string& tmp, const std::string& target) {
  auto fail = [&](const std::string& what, int err) {
    ::unlink(tmp.c_str());
    throw Error(ErrorKind::Output, "cannot write '" + target + "': " + what + ": " + std::strerror(err));
  };
  ::chmod(tmp.c_str(), 0644);  // mkstemps creates 0600; outputs are ordinary user files
  int fd = ::open(tmp.c_str(), O_RDONLY);
  if (fd < 0) fail("cannot reopen the temporary file", errno);
  int rc = ::fsync(fd);
  int err = errno;
  ::close(fd);
  if (rc != 0) fail("fsync failed", err);
  if (::rename(tmp.c_str(), target.c_str()) != 0) fail("rename failed", errno);
  int dir_fd = ::open(directory_of(target).c_str(), O_RDONLY | O_DIRECTORY);
  if (dir_fd >= 0) {  // makes the rename durable; best effort (not every file system allows it)
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
}

void write_file_atomic(const std::string& target, const void* data, std::size_t size) {
  std::string tmp = create_temp_beside(target);
  int fd = ::open(tmp.c_str(), O_WRONLY | O_TRUNC);
  if (fd < 0) {
    int err = errno;
    ::unlink(tmp.c_str());
    throw Error(ErrorKind::Output, "cannot write '" + target + "': " + std::strerror(err));
  }
  const char* p = static_cast<const char*>(data);
  std::size_t left = size;
  while (left > 0) {
    ssize_t n = ::write(fd, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      int err = n < 0 ? errno : EIO;
      ::close(fd);
      ::unlink(tmp.c_str());
      throw Error(ErrorKind::Output, "cannot write '" + target + "': " + std::strerror(err));
    }
    p += n;
    left -= std::size_t(n);
  }
  if (::close(fd) != 0) {
    int err = errno;
    ::unlink(tmp.c_str());
    throw Error(ErrorKind::Output, "cannot write '" + target + "': close failed: " + std::strerror(err));
  }
  commit_temp(tmp, target);
}

}  // namespace stex
