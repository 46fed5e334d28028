// Support masks S for the synthesis-oriented texton (S2 §3, problem (4) and Algorithm 2: q_S(t) = t 1_S).
// A mask lives on the square [0, s)^2 (its bounding box, placed at the top-left corner of Omega like the
// texton support of analysis/texton.h); s is the `support` of the resulting TextonModel, whose alpha is zero
// outside the mask. Kinds:
//  - square:S  every pixel of [0, S)^2 (S1's and analysis/texton.h's support);
//  - disc:R    the digital disc {(x, y) : (x - R)^2 + (y - R)^2 <= R^2} in a (2R + 1)^2 box (S2 §4 uses
//  discs:
//              Fig. 5 has R = 5, 15, 25; a 31 x 31 support is R = 15);
//  - an image  non-zero (in any channel) = in S, cropped to the bounding box of its non-zero pixels and
//  padded
//              with zeros (right, bottom) to a square.
// The placement of S inside Omega does not change the model (a circular shift only changes the phases); the
// centre (cx, cy) is where the concentrated baselines (the luminance texton, analysis/luminance_texton.h) put
// the origin.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/image_io.h"

namespace stex {

struct SupportMask {
  int size = 0;                  // s: the mask is s x s
  std::vector<std::uint8_t> in;  // s * s, row-major; 1 inside S, 0 outside
  int centre_x = 0, centre_y = 0;
  std::string description;  // "square:31", "disc:15", "image:mask.png"

  bool contains(int x, int y) const { return in[std::size_t(y) * size + x] != 0; }
  std::size_t count() const;  // |S|
};

constexpr int k_max_mask_size = 4096;  // the largest texton support (runtime/texton_params.h)

// Error(Usage) for s outside [1, 4096] or r outside [0, 2047].
SupportMask square_mask(int s);
SupportMask disc_mask(int radius);
// Error(Input) when no pixel is non-zero. `name` goes into the description.
SupportMask mask_from_image(const Image& img, const std::string& name);

// "square:S", "disc:R", or a path to a mask image (loaded by load_exemplar with `opts`: allow-list, pixel
// budget). Error(Usage) for a malformed spec ("disc:" with a bad number), Error(Input) for a bad file.
SupportMask parse_support_mask(const std::string& spec, const LoadOptions& opts = {});

}  // namespace stex
