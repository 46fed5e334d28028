// Errors raised inside stex, and the process exit code each kind maps to (documented in README.md).
// Every error names what failed; OpenCL errors also name the call and the error code (runtime/cl_error.h).
#pragma once
#include <stdexcept>
#include <string>

namespace stex {

// Process exit codes of the `stex` CLI, one per error kind. Stable: scripts and schedulers rely on them.
enum class ErrorKind : int {
  Internal = 1,    // a bug or an unexpected condition
  Usage = 2,       // bad command line or parameter values
  Input = 3,       // missing, unreadable, corrupt, foreign or unsupported input file
  Device = 4,      // no OpenCL platform or device, no device matches the selection, build failure
  Limit = 5,       // a size or resource limit: pixel budget, allocation larger than the device allows
  Output = 6,      // cannot write an output file
  Retryable = 75,  // transient device failure mid-run (EX_TEMPFAIL): the task may be retried
  Interrupted = 130,  // stopped by SIGINT/SIGTERM at a tile boundary (128 + SIGINT); temp files removed
};

class Error : public std::runtime_error {
 public:
  Error(ErrorKind kind, const std::string& what) : std::runtime_error(what), kind_(kind) {}
  ErrorKind kind() const noexcept { return kind_; }
  int exit_code() const noexcept { return static_cast<int>(kind_); }

 private:
  ErrorKind kind_;
};

}  // namespace stex
