// Gabor noise models (runtime/gabor_params.h) as stored models of kind "gabor" (docs/model-format.md), and
// the ways to make one: from parameters (anisotropic, isotropic, multi-lobe: `stex gabor`), from a power
// spectrum given as an image, or from an exemplar's power spectrum (`stex analyze --method gabor`): Lagae et
// al. 2009's "arbitrary PSD" Gabor noise, a PSD approximated by a sum of anisotropic components, one per
// frequency bin, each a Gaussian lobe of bandwidth a.
#pragma once
#include <string>
#include <vector>

#include "analysis/image_io.h"
#include "model/codecs.h"
#include "runtime/gabor_params.h"

namespace stex {

// Stored values are float32 (payload) and doubles (metadata): gabor_roundtrip gives the model a file would
// give back (through the codec, model/codecs.h).
GaborModel gabor_roundtrip(const GaborModel& model);

// A PSD on a centred frequency grid: pixel (i, j) of a width x height image is the power at frequency
// ((i - width/2) / width, (j - height/2) / height) cycles per pixel (channel 0; negative values are an
// error). Symmetrised (P(f) + P(-f)), bins above 0.5 cycles per pixel or below `floor` x the peak dropped,
// the strongest `max_components` kept as anisotropic components of weight P. Error(Input) for an empty
// PSD. The defaults keep every bin of a 64^2 grid inside 0.5 cycles per pixel (1602): a peak-relative floor
// or a smaller cap drops the weak high frequencies, which the spectrum check shows (data/brick.png: median
// radial error 0.71 with floor 1e-3 and 1024 components, 0.10 with these defaults; docs/gabor.md).
GaborModel gabor_model_from_psd(const Image& psd, double bandwidth, int max_components = 4096, double floor = 0.0,
                                int* dropped = nullptr);

// The power spectrum of an exemplar (channel mean, mean removed, periodic component: S1 §4.1's
// periodic-plus-smooth decomposition, analysis/periodic.h) averaged over grid x grid frequency bins, as a
// centred PSD image for gabor_model_from_psd; mean and std of the model are the exemplar's.
Image exemplar_psd(const Image& exemplar, int grid, double* mean = nullptr, double* stddev = nullptr);

}  // namespace stex
