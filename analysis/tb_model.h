// Tiling and blending by example (kinds "tb" and "cs-tb"; Heitz & Neyret HPG 2018, Deliot & Heitz GPU Zen 2;
// S4 §5.2): PCA colour decorrelation, per-channel Gaussianisation T (ranks -> N(0.5, 1/6^2)) and its inverse
// LUT T^-1, and for cs-tb the periods and the cyclic mean of the Gaussianised exemplar (analysis/cs_lattice.h).
// runtime/tb.h renders the models; the codec is here.
#pragma once
#include <string>

#include "analysis/cs_hist.h"
#include "analysis/cs_lattice.h"
#include "analysis/image_io.h"
#include "model/codecs.h"
#include "runtime/tb.h"

namespace stex {

struct TbParams {
  double tile = -1.0;  // triangle-grid side L in exemplar pixels; -1: min(width, height) / 6
  int lut_size = 1024;
  // Histogram transfer of the PCA channels: 1 stationary (T and the LUT T^-1, Heitz & Neyret; S4 §5.3.1),
  // 2 cyclostationary per polyphase bin with neighbourhood delta (S4 §5.3.2-5.3.3, analysis/cs_hist.h;
  // cs-tb only): the exemplar is Gaussianised by its bins' T_b and the render applies T_P(x)^-1.
  int histogram = 1;
  int delta = 1;
};

// tb (periods == nullptr) or cs-tb. Error(Usage) for bad parameters or periods, Error(Input) for an exemplar
// that cannot hold them.
TbModel tb_from_exemplar(const Image& exemplar, const TbParams& params, const Lattice* periods = nullptr);

}  // namespace stex
