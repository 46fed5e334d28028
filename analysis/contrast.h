// Contrast oscillations of stochastic textures and their renormalisation (S5: "Understanding and
// controlling contrast oscillations in stochastic texture algorithms using Spectrum of Variance",
// supplemental material: Fig. 6, 7, 9, 10 pseudo-code, 13-17).
//
// Power-spectrum noises (Gabor, Fourier synthesis, texton) show low-frequency contrast variations even when
// their spectrum has no low frequency: the square of the centred signal has a low-frequency lobe (the
// autoconvolution of the spectrum, Fig. 6). Definitions used here (one image; colour images use the mean of
// their channels' squared deviations, and every channel is scaled by the same factor):
//  - window at stationarity scale L: a Gaussian of standard deviation L / 2 pixels; its transfer function
//    LF(xi) = exp(-2 pi^2 (L/2)^2 |xi|^2) is the "LF_filter" of Fig. 10;
//  - windowed second moment E = LF * (im - mean)^2 (Fig. 9e), contrast C = sqrt(|E|);
//  - variance spectrum: |FFT((im - mean)^2)| (Fig. 6 right, 9f right), written centred.
// Renormalisation (Fig. 10, kept line by line): C /= Cref (Cref = max C, the paper's choice, or a fixed
// reference for deterministic tiles), K = (minC + 1) / (minC + C), im = mean + (im - mean) K. The simple
// mode is one pass; the quality mode iterates the pass followed by spectrum reprofiling: the spectrum of the
// result is multiplied by the initial footprint (|spectrum| above a threshold of its peak after smoothing,
// or its smooth Gaussian-weighted variant), which smooths the sudden inversions at the zero-contrast locus
// (Fig. 9b vs 9c). FFTs go through analysis/device_fft.h (clFFT on the device where the size factors into
// 2, 3, 5, 7, 11, 13; FFTW otherwise) or analysis/fft.h (FFTW on the host).
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "analysis/image_io.h"
#include "runtime/context.h"
#include "runtime/noise_renderer.h"

namespace stex {

class DeviceFft;

// Which features of the variance spectrum the renormalisation collects (Fig. 14-15). The spectrum's lobes
// s_1..s_n (both +-f of each lobe pair) give variance-spectrum lobes at s_i + s_j: 0 (LF), 2 s_i ("pure"
// lobes), the others inter-lobe interferences.
enum class LobeSelection {
  LowFrequency,       // (b) the LF lobe only (default)
  LfInterferences,    // (c) LF + inter-lobe interferences
  LfPureLobes,        // (d) LF + pure lobes
};
LobeSelection parse_lobe_selection(const std::string& name);  // "lf", "lf+interferences", "lf+pure"

struct ContrastOptions {
  double L = 32.0;  // stationarity scale, pixels (window std L / 2), in [1, 1e5]
  // "device": clFFT on the device where the size allows, else FFTW; "host": FFTW.
  std::string fft = "host";
};

struct RenormOptions : ContrastOptions {
  bool quality = false;        // quality mode: iterate normalisation + spectrum reprofiling (Fig. 9c, 10)
  int iterations = 4;          // passes of the quality mode (the simple mode makes one)
  double min_contrast = 1e-2;  // minC of Fig. 10 (avoids division by 0), in (0, 10]
  LobeSelection selection = LobeSelection::LowFrequency;
  std::vector<std::array<double, 2>> lobes;  // spectrum lobe centres (cycles/pixel), both signs
  double footprint_threshold = 1e-2;         // footprint: smoothed |spectrum| >= threshold x its peak
  bool smooth_footprint = false;             // the smooth variant of Fig. 10 (footprint = smoothed |spectrum|)
  // The initial footprint's source as a function of frequency (u, v) in cycles/pixel, e.g. a model's PSD
  // (gabor_psd); when set it replaces the image's own smoothed |spectrum| (deterministic tiles).
  std::function<double(double, double)> footprint_psd;
  // Deterministic tiles: NaN measures from the image (the paper); a value fixes the mean / Cref.
  double mean = std::numeric_limits<double>::quiet_NaN();
  double reference_contrast = std::numeric_limits<double>::quiet_NaN();
  // Rescale the result to the input's mean and standard deviation (the variant line of Fig. 10); false
  // keeps mean + (im - mean) K (its contrast is about Cref everywhere).
  bool keep_std = true;
};

// Statistics of a contrast field over its interior (a margin of L pixels removed when the image is larger
// than 4 L, to leave out the periodic wrap of the FFT window).
struct ContrastStats {
  double mean = 0.0, stddev = 0.0, cov = 0.0, min = 0.0, max = 0.0;
  int margin = 0;
};

struct ContrastField {
  int width = 0, height = 0;
  double mean = 0.0;                    // image mean (per channel mean of the channel means)
  std::vector<double> second_moment;    // E, width x height
  std::vector<double> contrast;         // C = sqrt(|E|)
  std::vector<double> variance_spectrum;  // |FFT((im - mean)^2)|, centred (zero frequency at (w/2, h/2))
  ContrastStats stats;
};

// Validates sizes and options (Error(Usage)); the FFT context is needed only for fft = "device".
ContrastField contrast_field(const Image& image, const ContrastOptions& options, Context* ctx = nullptr);
ContrastStats contrast_stats(const std::vector<double>& contrast, int width, int height, double L);

struct RenormReport {
  std::vector<ContrastStats> passes;  // contrast statistics before each pass and after the last
  std::string fft_backend;            // "clfft", "fftw" or "fftw (host)"
};

// S5 Fig. 10 on an image (1..4 channels). Error(Usage) for bad options.
Image renormalize(const Image& image, const RenormOptions& options, Context* ctx = nullptr,
                  RenormReport* report = nullptr);

// Applications and options of S5:
// Fig. 16a: the renormalised signal times a target contrast map (mean of its channels; same size).
Image apply_contrast_map(const Image& renormalized, const Image& map, double mean);
// Fig. 16b: lerp of two pre-normalised noises by a dominance map (0: a, 1: b), renormalised again.
Image dominance_blend(const Image& a, const Image& b, const Image& map, const RenormOptions& options,
                      Context* ctx = nullptr);
// Fig. 17: each layer normalised separately and the results summed (rescaled to the sum's mean and std).
Image renormalize_layers(const std::vector<Image>& layers, const RenormOptions& options, Context* ctx = nullptr);
// Fig. 13: content constraint, lerp(drawing, noise, w) = (1 - w) drawing' + w noise renormalised, drawing'
// the drawing's mean of channels mapped to the noise's mean and standard deviation.
Image content_constraint(const Image& noise, const Image& drawing, double w, const RenormOptions& options,
                         Context* ctx = nullptr);
// Fig. 1, 11, 12: a colour look-up table (row 0 of `lut`, left = low) indexed by t = 1/2 + (v - mean) /
// (2 max |v - mean|) of the mean of the channels (the normalisation of Fig. 10's last line).
Image apply_lut(const Image& image, const Image& lut);

// The spectrum lobe centres of a model's components without orientation spread: +-F (cos w, sin w).
struct GaborModel;
std::vector<std::array<double, 2>> gabor_lobes(const GaborModel& model);

// Tiled renormalisation: renders [x, x + w) x [y, y + h) padded by `overlap` x L pixels on each side,
// renormalises the padded region with fixed mean and Cref (options.mean and options.reference_contrast must
// be set) and crops. The quality mode uses the smooth footprint here. Adjacent tiles then join closely, not
// exactly: docs/contrast.md gives the measured gap.
class RenormalizedNoise final : public NoiseRenderer {
 public:
  RenormalizedNoise(Context& ctx, std::unique_ptr<NoiseRenderer> inner, RenormOptions options, double overlap = 3.0);
  std::string kind() const override { return inner_->kind(); }
  int channels() const override { return inner_->channels(); }
  NoiseRenderStats render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                          float* out) override;
  int padding() const { return pad_; }

 private:
  Context& ctx_;
  std::unique_ptr<NoiseRenderer> inner_;
  RenormOptions options_;
  int pad_ = 0;
};

}  // namespace stex
