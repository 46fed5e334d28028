// OpenCL error codes by name, the ErrorKind each maps to, and the OpenCLError exception (cl_error.h).
// Names cover every error code of OpenCL 1.2, the few later core codes (2.0-3.0) a newer driver may return,
// and CL_PLATFORM_NOT_FOUND_KHR (-1001, cl_khr_icd: the ICD loader found no platform). Codes are matched by
// value, not by the CL/cl.h macros, so the table does not depend on CL_TARGET_OPENCL_VERSION.
#include "runtime/cl_error.h"

#include <string>

namespace stex {

namespace {

// One code per line reads as a table.
// clang-format off
const char* known_cl_error_name(cl_int code) {
  switch (code) {
    case 0: return "CL_SUCCESS";
    case -1: return "CL_DEVICE_NOT_FOUND";
    case -2: return "CL_DEVICE_NOT_AVAILABLE";
    case -3: return "CL_COMPILER_NOT_AVAILABLE";
    case -4: return "CL_MEM_OBJECT_ALLOCATION_FAILURE";
    case -5: return "CL_OUT_OF_RESOURCES";
    case -6: return "CL_OUT_OF_HOST_MEMORY";
    case -7: return "CL_PROFILING_INFO_NOT_AVAILABLE";
    case -8: return "CL_MEM_COPY_OVERLAP";
    case -9: return "CL_IMAGE_FORMAT_MISMATCH";
    case -10: return "CL_IMAGE_FORMAT_NOT_SUPPORTED";
    case -11: return "CL_BUILD_PROGRAM_FAILURE";
    case -12: return "CL_MAP_FAILURE";
    case -13: return "CL_MISALIGNED_SUB_BUFFER_OFFSET";
    case -14: return "CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST";
    case -15: return "CL_COMPILE_PROGRAM_FAILURE";
    case -16: return "CL_LINKER_NOT_AVAILABLE";
    case -17: return "CL_LINK_PROGRAM_FAILURE";
    case -18: return "CL_DEVICE_PARTITION_FAILED";
    case -19: return "CL_KERNEL_ARG_INFO_NOT_AVAILABLE";
    case -30: return "CL_INVALID_VALUE";
    case -31: return "CL_INVALID_DEVICE_TYPE";
    case -32: return "CL_INVALID_PLATFORM";
    case -33: return "CL_INVALID_DEVICE";
    case -34: return "CL_INVALID_CONTEXT";
    case -35: return "CL_INVALID_QUEUE_PROPERTIES";
    case -36: return "CL_INVALID_COMMAND_QUEUE";
    case -37: return "CL_INVALID_HOST_PTR";
    case -38: return "CL_INVALID_MEM_OBJECT";
    case -39: return "CL_INVALID_IMAGE_FORMAT_DESCRIPTOR";
    case -40: return "CL_INVALID_IMAGE_SIZE";
    case -41: return "CL_INVALID_SAMPLER";
    case -42: return "CL_INVALID_BINARY";
    case -43: return "CL_INVALID_BUILD_OPTIONS";
    case -44: return "CL_INVALID_PROGRAM";
    case -45: return "CL_INVALID_PROGRAM_EXECUTABLE";
    case -46: return "CL_INVALID_KERNEL_NAME";
    case -47: return "CL_INVALID_KERNEL_DEFINITION";
    case -48: return "CL_INVALID_KERNEL";
    case -49: return "CL_INVALID_ARG_INDEX";
    case -50: return "CL_INVALID_ARG_VALUE";
    case -51: return "CL_INVALID_ARG_SIZE";
    case -52: return "CL_INVALID_KERNEL_ARGS";
    case -53: return "CL_INVALID_WORK_DIMENSION";
    case -54: return "CL_INVALID_WORK_GROUP_SIZE";
    case -55: return "CL_INVALID_WORK_ITEM_SIZE";
    case -56: return "CL_INVALID_GLOBAL_OFFSET";
    case -57: return "CL_INVALID_EVENT_WAIT_LIST";
    case -58: return "CL_INVALID_EVENT";
    case -59: return "CL_INVALID_OPERATION";
    case -60: return "CL_INVALID_GL_OBJECT";
    case -61: return "CL_INVALID_BUFFER_SIZE";
    case -62: return "CL_INVALID_MIP_LEVEL";
    case -63: return "CL_INVALID_GLOBAL_WORK_SIZE";
    case -64: return "CL_INVALID_PROPERTY";
    case -65: return "CL_INVALID_IMAGE_DESCRIPTOR";
    case -66: return "CL_INVALID_COMPILER_OPTIONS";
    case -67: return "CL_INVALID_LINKER_OPTIONS";
    case -68: return "CL_INVALID_DEVICE_PARTITION_COUNT";
    case -69: return "CL_INVALID_PIPE_SIZE";
    case -70: return "CL_INVALID_DEVICE_QUEUE";
    case -71: return "CL_INVALID_SPEC_ID";
    case -72: return "CL_MAX_SIZE_RESTRICTION_EXCEEDED";
    case -1001: return "CL_PLATFORM_NOT_FOUND_KHR";
    default: return nullptr;
  }
}
// clang-format on

std::string format_message(const std::string& call, cl_int code, const std::string& detail) {
  std::string msg = call + " failed: " + cl_error_name(code) + " (" + std::to_string(code) + ")";
  if (!detail.empty()) msg += ": " + detail;
  return msg;
}

}  // namespace

std::string cl_error_name(cl_int code) {
  if (const char* name = known_cl_error_name(code)) return name;
  return "CL_UNKNOWN_ERROR(" + std::to_string(code) + ")";
}

ErrorKind cl_error_kind(cl_int code) {
  switch (code) {
    // Transient or resource failures: the same work may succeed on a retry or on another node.
    case -2:   // CL_DEVICE_NOT_AVAILABLE
    case -4:   // CL_MEM_OBJECT_ALLOCATION_FAILURE
    case -5:   // CL_OUT_OF_RESOURCES (also how drivers report a lost device or a watchdog kill)
    case -6:   // CL_OUT_OF_HOST_MEMORY
    case -14:  // CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST (a prior command aborted)
      return ErrorKind::Retryable;
    // No usable platform, device or compiler, or the device cannot build the kernels.
    case -1001:  // CL_PLATFORM_NOT_FOUND_KHR
    case -1:     // CL_DEVICE_NOT_FOUND
    case -3:     // CL_COMPILER_NOT_AVAILABLE
    case -11:    // CL_BUILD_PROGRAM_FAILURE
    case -15:    // CL_COMPILE_PROGRAM_FAILURE
    case -16:    // CL_LINKER_NOT_AVAILABLE
    case -17:    // CL_LINK_PROGRAM_FAILURE
      return ErrorKind::Device;
    default:
      return ErrorKind::Internal;
  }
}

OpenCLError::OpenCLError(const std::string& call, cl_int code, const std::string& detail)
    : Error(cl_error_kind(code), format_message(call, code, detail)), call_(call), code_(code) {}

void cl_check(cl_int code, const char* call) {
  if (code != CL_SUCCESS) throw OpenCLError(call, code);
}

}  // namespace stex
