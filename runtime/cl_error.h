// OpenCL failures as exceptions that name the call and the error code by name (CL_OUT_OF_RESOURCES, ...).
#pragma once
#include <CL/cl.h>

#include <string>

#include "core/error.h"

namespace stex {

// "CL_INVALID_VALUE" etc.; "CL_UNKNOWN_ERROR(<code>)" for codes it does not know (returns a static or
// thread-local buffer; copy it).
std::string cl_error_name(cl_int code);

// The ErrorKind an OpenCL error code maps to: out-of-resources / allocation failures / device-lost style
// codes are Retryable (the task may succeed on retry or elsewhere), CL_PLATFORM_NOT_FOUND_KHR (-1001),
// CL_DEVICE_NOT_FOUND, CL_COMPILER_NOT_AVAILABLE and the build/compile/link failures are Device, the rest
// Internal.
ErrorKind cl_error_kind(cl_int code);

class OpenCLError : public Error {
 public:
  // what(): "<call> failed: <CL_NAME> (<code>)[: detail]"
  OpenCLError(const std::string& call, cl_int code, const std::string& detail = "");
  cl_int code() const noexcept { return code_; }
  const std::string& call() const noexcept { return call_; }

 private:
  std::string call_;
  cl_int code_;
};

// Throws OpenCLError when code != CL_SUCCESS.
void cl_check(cl_int code, const char* call);

}  // namespace stex
