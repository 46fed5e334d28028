// Noise mixing (S1 §7): the mixing model as the runtime consumes it (K textons alpha_{rho_k} of the OT
// barycentres tau_{rho_k}, rho_k = k / (K - 1), the means of the two exemplars, and the mixing map), its
// render setup (stex_mix_params of kernels/shared/mix.h over the texton grid of runtime/texton_params.h) and
// the C++ reference evaluator on the shared header. The model kind is "mix" (codec and analysis:
// analysis/mix.h; docs/mixing.md).
//
// Mixing maps, documented once here (`stex analyze-mix --help`, `stex render --help` and the README draw on
// them). All positions are output pixels (the same coordinates as --origin and --size):
//  - const:RHO          rho(x) = RHO everywhere, in [0, 1];
//  - ramp:X0:X1         rho(x) = clamp((x - X0) / (X1 - X0), 0, 1): S1 Fig. 5's progressive mixing from u
//                       (left of X0) to v (right of X1); quantised to the K levels it is K vertical strips;
//  - strips:P[:W]       period P: rho = 0 on [0, P/2), 1 on [P/2, P) (mod P), each edge a linear ramp of
//                       width W centred on it (default 0: hard edges; W <= P/2);
//  - an image file      a grey map (channel mean, 8/16-bit scaled to [0, 1]) of w x h pixels, each covering
//                       `scale` output pixels, its top-left corner at output pixel `origin`, bilinear between
//                       pixel centres; outside it `wrap` repeats it (default) or clamps to its edge.
// An impulse x_j uses the texton of the level nearest to rho(x_j) (S1 §7's partition D_r; x_j is the texton's
// centre, as S1 §8's kernel is centred on its impulse: kernels/shared/mix.h); the mean at a
// pixel is (1 - rho(x)) m0 + rho(x) m1.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "kernels/shared/mix.h"
#include "runtime/model.h"
#include "runtime/texton_params.h"

namespace stex {

struct MixMap {
  enum class Type { Const, Ramp, Strips, Image };
  Type type = Type::Ramp;
  double rho = 0.5;                // const
  double x0 = 0.0, x1 = 1024.0;    // ramp (output pixels)
  double period = 256.0, width = 0.0;  // strips (output pixels)
  // image: grey values in [0, 1], row-major map_width x map_height
  int map_width = 0, map_height = 0;
  std::vector<float> grey;
  double scale = 1.0;                     // output pixels per map pixel
  std::int64_t origin_x = 0, origin_y = 0;  // output pixel of the map's top-left corner
  bool clamp = false;                     // outside the map: clamp to the edge (false: repeat)
  std::string name;                       // the image's file name (provenance)
};

// Limits of a map (checked by validate_mix_map).
inline constexpr double k_mix_max_extent = 1099511627776.0;  // 2^40 output pixels: |X0|, |X1|, P, W
inline constexpr int k_mix_max_map_side = 16384;
inline constexpr double k_mix_min_map_scale = 1.0 / 256.0, k_mix_max_map_scale = 65536.0;

// Parses const:RHO, ramp:X0:X1, strips:P[:W]; Error(Usage) naming the problem. Returns false (and leaves
// `out` alone) when `spec` is none of these (the caller then treats it as an image path).
bool parse_analytic_mix_map(const std::string& spec, MixMap* out);
// The spec of an analytic map ("ramp:0:1024", ...), or "image:NAME" for an image map.
std::string mix_map_spec(const MixMap& map);
// Error(Usage) `prefix` + the bad field (ranges above; image size = map_width x map_height values, finite).
void validate_mix_map(const MixMap& map, const std::string& prefix = "invalid mixing map: ");

struct MixModel {
  int channels = 0;  // 1..4
  int support = 0;   // s
  int order = 1;     // 0, 1, 3, 5 (as texton models)
  int levels = 0;    // K in [2, STEX_MIX_MAX_LEVELS]: rho_k = k / (K - 1)
  // alpha_{rho_k}, level k, channel c, row y, column x at ((k * channels + c) * s + y) * s + x.
  std::vector<float> alpha;
  std::array<float, 4> mean0{}, mean1{};  // exemplar means of u (rho = 0) and v (rho = 1)
  bool linear = false;
  MixMap map;

  // Provenance and analysis report (stored in the model file).
  std::array<std::string, 2> exemplar_name, exemplar_hash;
  int exemplar_width = 0, exemplar_height = 0;  // Omega (the common grid of the two exemplars)
  int iterations = 0;
  std::uint64_t analysis_seed = 0;
  bool colour_correction = true;
  double ot_distance = 0.0;   // d_OT(tau_0, tau_1) (S2 eq. 1, analysis/ot_distance.h)
  std::vector<double> rme;    // per level: RME of alpha_{rho_k} against tau_{rho_k}
  std::string stex_version;

  // Level k as a texton model (mean: the interpolated mean (1 - rho_k) m0 + rho_k m1).
  TextonModel level_model(int k) const;
  double level_rho(int k) const { return levels > 1 ? double(k) / double(levels - 1) : 0.0; }
};

// Checks every field (Error(Input), "invalid mix model: ..."); the map with validate_mix_map.
void validate_mix_model(const MixModel& model);

// A filtered minified view (params.filter, scale < 1; docs/filtering.md) reads each level's texton convolved
// with the pixel's box: the same kernel, with the tables as the textons and mix.shift in every displacement.
struct MixSetup {
  TextonSetup texton;               // grid, Poisson table, taps (of level 0; every level has the same shape)
  stex_mix_params mix{};            // the map and the means
  std::vector<float> alpha_levels;  // K padded textons, level_floats apart
  std::vector<float> map;           // image map values (one 0 for analytic maps: buffers are never empty)
};

// Validates model (Error(Input)) and parameters (Error(Usage)) and builds what the kernel needs.
MixSetup make_mix_setup(const MixModel& model, const RenderParams& params);

// The C++ reference: stex_mix_eval compiled as C++, one call per pixel (single-threaded; tests).
class MixReference {
 public:
  MixReference(const MixModel& model, const RenderParams& params) : setup_(make_mix_setup(model, params)) {}
  // Pixels [x, x + width) x [y, y + height), interleaved channels. Validates the region (Error(Usage)).
  std::vector<float> render(std::int64_t x, std::int64_t y, int width, int height) const;
  // rho at the centre of output pixel (px, py) and at a fixed-point position.
  float rho_pixel(std::int64_t px, std::int64_t py) const;
  float rho_fixed(std::int64_t fx, std::int64_t fy) const;
  const MixSetup& setup() const { return setup_; }

 private:
  MixSetup setup_;
};

}  // namespace stex
