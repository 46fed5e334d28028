// ADSN by FFT as a per-frame benchmark baseline (issue #5; S1 §3.1-3.2, S2 §2.1/§2.4): the exemplar's
// Gaussian texture mean + t_u (*) W on a width x height output, the FFT domain enlarged to the exemplar's
// size where the output is smaller (as analysis/gaussian_synthesis.h). What a frame costs: the white noise W,
// its FFT, and per channel a spectrum product and an inverse FFT. The setup (periodic component, t_u and its
// spectrum, FFT plans) is done once in the constructor and not timed, as a renderer would.
//  - AdsnFftwBaseline: on the host, FFTW single precision (real-to-complex), the host's threads (FFTW's
//    threads for the transforms, OpenMP for the noise and the products); plans by FFTW_MEASURE with a 2 s
//    planning limit. (analysis/fft.h is FFTW double on one thread: right for the analysis, not a fair speed
//    baseline.)
//  - AdsnDeviceBaseline: on the OpenCL device, complex-to-complex transforms by analysis/device_fft.h (clFFT;
//    FFTW on the host for sizes clFFT cannot plan) around the kernels of kernels/bench_adsn.cl. Available only
//    when analysis/device_fft.h is part of the build (adsn_device_available()).
// Both write planar output (channel c of pixel (i, j) at c * width * height + j * width + i).
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include "analysis/image_io.h"
#include "runtime/context.h"

namespace stex::bench {

class AdsnFftwBaseline {
 public:
  AdsnFftwBaseline(const Image& exemplar, int width, int height, int threads = 0);
  ~AdsnFftwBaseline();
  AdsnFftwBaseline(const AdsnFftwBaseline&) = delete;
  AdsnFftwBaseline& operator=(const AdsnFftwBaseline&) = delete;

  void render(std::uint64_t seed, float* planar);
  int channels() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

bool adsn_device_available();

class AdsnDeviceBaseline {
 public:
  // Throws stex::Error(Device) if adsn_device_available() is false.
  AdsnDeviceBaseline(Context& ctx, const Image& exemplar, int width, int height);
  ~AdsnDeviceBaseline();
  AdsnDeviceBaseline(const AdsnDeviceBaseline&) = delete;
  AdsnDeviceBaseline& operator=(const AdsnDeviceBaseline&) = delete;

  // Renders one frame on the device, reads it into `planar` if not null. Returns the device pipeline's
  // elapsed ms (enqueue to finish, excluding the read-back: clFFT launches are not profiled individually).
  double render(std::uint64_t seed, float* planar);
  // "clFFT" or "FFTW fallback" (the backend the last transform used).
  std::string backend() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace stex::bench
