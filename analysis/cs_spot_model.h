// Cyclostationary spot noise by example (S4 §5.1, kind "cs-spot"): the spot is the exemplar minus its cyclic
// mean M (eq. 3, analysis/cs_lattice.h), with its borders smoothed to zero (GGM11's enhancement, S4 §7), shot
// on the lattice of the periods with N(0, 1) weights (runtime/cs_spot.h renders it). And the codec of kind
// "cs-spot" (docs/model-format.md).
#pragma once
#include <string>

#include "analysis/cs_hist.h"
#include "analysis/cs_lattice.h"
#include "analysis/image_io.h"
#include "model/codecs.h"
#include "runtime/cs_spot.h"

namespace stex {

struct CsSpotParams {
  // Width in texels of the raised-cosine taper at each border of the spot (w = sin^2 ramp from 0 to 1): it
  // removes the straight-line artefacts of a spot cut from an exemplar. -1: min(width, height) / 8.
  int border = -1;
  // Histogram transfer (S4 §5.3, analysis/cs_hist.h): 0 none (a Gaussian CS texture), 1 stationary, 2 per
  // polyphase bin with neighbourhood delta. With a transfer, the spot and the mean are those of the
  // Gaussianised exemplar and the render applies T_P(x)^-1.
  int histogram = 0;
  int delta = 1;
};

struct CsSpotReport {
  Lattice periods;
  int border = 0;
  double window_energy = 0.0;  // sum of w^2 over the spot
  int mean_samples = 0;        // the fewest samples of a polyphase component in M
};

// Error(Usage) for bad periods (validate_lattice) or border; Error(Input) for an exemplar too small for them.
CsSpotModel cs_spot_from_exemplar(const Image& exemplar, const Lattice& periods, const CsSpotParams& params = {},
                                  CsSpotReport* report = nullptr);


}  // namespace stex
