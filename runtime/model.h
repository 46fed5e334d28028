// The texton noise model as the runtime consumes it (S1 §4): plain data, no I/O. Produced by
// analysis/texton.{h,cpp}, stored by model/texton_codec.cpp, evaluated by runtime/texton_renderer.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace stex {

struct TextonModel {
  int channels = 0;  // 1..4 (grey, grey+?, RGB, RGBA-less: alpha is dropped at analysis, so 1 or 3 in practice)
  int support = 0;   // s: alpha is s x s per channel
  int order = 1;     // interpolation order: 0 nearest (S2's SOT), 1 bilinear (S1), 3 cubic, 5 quintic (S1 §10)
  // Texton interpolation coefficients alpha, planar: channel c, row y, column x at c*s*s + y*s + x.
  // Normalised like S1's t_u = (u - mean)/sqrt(|Omega|): the noise variance is sum of alpha's B-spline
  // weighted autocorrelation, which equals the exemplar's variance after colour correction.
  std::vector<float> alpha;
  std::array<float, 4> mean{};  // exemplar mean per channel (in the synthesis space)
  bool linear = false;          // true: synthesised in linear light; renders are encoded to sRGB

  // Provenance and analysis parameters (stored in the model file, reported by tools).
  std::string exemplar_name;
  std::string exemplar_hash;  // hex SHA-256 of the exemplar file bytes
  int exemplar_width = 0, exemplar_height = 0;
  int iterations = 0;
  std::uint64_t analysis_seed = 0;
  double rme = 0.0;            // S2's relative model error of the (uncorrected) texton vs t_u
  double variance_kept = 0.0;  // variance of the texton noise before colour correction / exemplar's
  std::string stex_version;

  float alpha_at(int c, int y, int x) const { return alpha[(std::size_t(c) * support + y) * support + x]; }
};

}  // namespace stex
