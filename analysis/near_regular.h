// Synthetic near-regular textures with a known primitive lattice: the corpus on which period estimation
// (analysis/cs_lattice.h) is measured (`stex periods --corpus`, tests/cs/test_cs_lattice.cpp).
//
// Each exemplar is a motif repeated on a lattice t0, t1 (any rotation, shear, hexagonal, sub-pixel lengths),
// with what photographs of tiles and slabs have: grout lines, a motif that varies from one cell to the next
// (colour, contrast, and each tile laid with its own sub-pixel shift, grout included), white noise, a lighting gradient, colour, and optionally JPEG
// compression. The motif is a random periodic field of the cell coordinates with a 1/f spectrum (detail at
// every scale down to a few pixels, like stone or ceramic grain; its random order-1 terms mean no finer
// lattice repeats it) plus a random disc, so the lattice given is the primitive one. Everything is drawn from one seed with an integer RNG: the same spec
// gives the same image on every machine (up to the JPEG codec).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/cs_lattice.h"
#include "analysis/image_io.h"

namespace stex {

struct NearRegularSpec {
  int width = 512, height = 512, channels = 3;
  Lattice lattice;                 // the primitive periods, pixels
  double origin_x = 0.0, origin_y = 0.0;  // a lattice node
  double grout_width = 0.04;       // grout line half-width, in cell units (0: no grout)
  double cell_colour = 0.05;       // per-cell random colour offset amplitude
  double cell_contrast = 0.15;     // per-cell random motif contrast amplitude (relative)
  double cell_jitter = 0.05;       // per-cell random motif shift amplitude, pixels (uniform in +-)
  double noise = 0.02;             // white noise standard deviation
  double gradient = 0.0;           // lighting: the image is multiplied by 1 + gradient * (ramp in [-1/2, 1/2])
  double gradient_angle = 0.0;     // direction of the ramp, radians
  int jpeg_quality = 0;            // 0: none; else a JPEG round trip at this quality (1..100)
  std::uint64_t seed = 1;
  std::string kind;                // "rect", "sheared", "hex": how the lattice was drawn (for reports)
};

// The exemplar of a spec. JPEG round trips go through a temporary file in `tmp_dir` (default: $TMPDIR or /tmp).
Image make_near_regular(const NearRegularSpec& spec, const std::string& tmp_dir = "");

// The lattice of the tiles as drawn: each cell is laid at its node plus its own shift (cell_jitter), so the
// lattice the image shows is the weighted least-squares fit of the drawn cells' positions (weights: the
// pixels of each cell in the image), not exactly spec.lattice. With n cells and shifts of standard deviation
// s the two differ by about s sqrt(12 / n) / repetitions per axis; this is the truth estimates are judged
// against (`stex periods --corpus` also reports the error against spec.lattice).
Lattice realised_lattice(const NearRegularSpec& spec);

// `count` random specs from `seed`: sizes 128..512, 2 to 30 repetitions per axis (periods >= 4 pixels and at
// most half the exemplar), rectangular (rotated), sheared and hexagonal lattices, grey and colour, a third
// with a lighting gradient, half JPEG-compressed, the rest of the parameters drawn over the ranges above.
// The per-cell shift is at most 0.1 pixel.
std::vector<NearRegularSpec> near_regular_corpus(int count, std::uint64_t seed);

// One line describing a spec (kind, size, lattice, repetitions, the nuisances).
std::string describe(const NearRegularSpec& spec);

}  // namespace stex
