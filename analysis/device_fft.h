// Device FFTs (the device side of analysis/fft.h's interface): 2-D complex single-precision
// transforms on a stex::Context, served by clFFT for the sizes it plans (prime factors 2, 3, 5, 7, 11, 13)
// and by FFTW on the host for every other size (clFFT 2.12.2: a 97x97 plan fails with
// CLFFT_NOTIMPLEMENTED). Same convention as analysis/fft.h: forward unnormalised with exp(-2 i pi ...),
// inverse normalised by 1/(width height). Layout: width x height row-major, interleaved complex float.
//
// clFFT's clfftSetup/clfftTeardown are process-wide: every DeviceFft holds one reference, the first sets
// clFFT up and the last tears it down, so several DeviceFfts (and contexts) coexist. Plans are baked once
// per (size, direction) and kept for the DeviceFft's life; clFFT calls are serialised by a process mutex.
#pragma once
#include <CL/cl.h>

#include <map>
#include <mutex>
#include <utility>
#include <vector>

#include "analysis/fft.h"

namespace stex {

class Context;

class DeviceFft {
 public:
  enum class Backend { ClFft, Fftw };

  explicit DeviceFft(Context& ctx);
  ~DeviceFft();
  DeviceFft(const DeviceFft&) = delete;
  DeviceFft& operator=(const DeviceFft&) = delete;

  // Whether the size factors into clFFT's radices (2, 3, 5, 7, 11, 13).
  static bool clfft_radices_only(int width, int height);
  // Number of DeviceFft objects alive in the process (the clFFT setup reference count; for tests).
  static int live_count();

  // In place on a device buffer of width * height complex floats (cl_float2). The FFTW fallback reads the
  // buffer back, transforms in double and writes it again. Returns the backend used. Blocks until done.
  Backend transform(int width, int height, cl_mem buffer, bool inverse);
  // Host convenience: uploads, transforms, downloads.
  Backend transform(int width, int height, std::vector<ComplexF>& data, bool inverse);

 private:
  struct Plan;
  Plan* plan_for(int width, int height);  // nullptr: clFFT cannot plan this size (fallback)
  Context& ctx_;
  std::mutex mutex_;
  std::map<std::pair<int, int>, Plan*> plans_;  // nullptr entries remember failed sizes
};

}  // namespace stex
