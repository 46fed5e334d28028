// The C API's error side (include/stex/stex.h "Errors"): status names, the thread-local last-error text the
// firewall (capi/api_internal.h) records, the mapping from internal error kinds, and the version queries.
#include <new>
#include <string>

#include "capi/api_internal.h"

namespace stex::capi {
namespace {

// The last error of this thread. `ok` is false when recording the message itself ran out of memory.
struct LastError {
  std::string text;
  bool ok = true;
};

LastError& last_error() {
  thread_local LastError e;
  return e;
}

}  // namespace

stex_status status_of(ErrorKind kind) noexcept {
  switch (kind) {
    case ErrorKind::Internal:
      return STEX_INTERNAL;
    case ErrorKind::Usage:
      return STEX_USAGE;
    case ErrorKind::Input:
      return STEX_INPUT;
    case ErrorKind::Device:
      return STEX_DEVICE;
    case ErrorKind::Limit:
      return STEX_LIMIT;
    case ErrorKind::Output:
      return STEX_OUTPUT;
    case ErrorKind::Retryable:
      return STEX_RETRYABLE;
    case ErrorKind::Interrupted:
      return STEX_INTERRUPTED;
  }
  return STEX_INTERNAL;
}

void begin_call() noexcept {
  LastError& e = last_error();
  e.text.clear();  // keeps the capacity: never allocates
  e.ok = true;
}

stex_status fail(const char* function, stex_status status, const char* message) noexcept {
  LastError& e = last_error();
  try {
    e.text = std::string(function) + ": " + message;
    e.ok = true;
  } catch (...) {
    e.text.clear();
    e.ok = false;
  }
  return status;
}

}  // namespace stex::capi

extern "C" {

STEX_API const char* stex_status_name(stex_status status) {
  switch (status) {
    case STEX_OK:
      return "STEX_OK";
    case STEX_INTERNAL:
      return "STEX_INTERNAL";
    case STEX_USAGE:
      return "STEX_USAGE";
    case STEX_INPUT:
      return "STEX_INPUT";
    case STEX_DEVICE:
      return "STEX_DEVICE";
    case STEX_LIMIT:
      return "STEX_LIMIT";
    case STEX_OUTPUT:
      return "STEX_OUTPUT";
    case STEX_INVALID_ARGUMENT:
      return "STEX_INVALID_ARGUMENT";
    case STEX_CANCELLED:
      return "STEX_CANCELLED";
    case STEX_UNAVAILABLE:
      return "STEX_UNAVAILABLE";
    case STEX_RETRYABLE:
      return "STEX_RETRYABLE";
    case STEX_INTERRUPTED:
      return "STEX_INTERRUPTED";
  }
  return "STEX_UNKNOWN_STATUS";
}

STEX_API const char* stex_last_error(void) {
  const auto& e = stex::capi::last_error();
  return e.ok ? e.text.c_str() : "out of host memory (while recording an error message)";
}

STEX_API const char* stex_version_string(void) { return STEX_VERSION_STRING; }

STEX_API int stex_abi_version(void) { return STEX_ABI_VERSION; }

}  // extern "C"
