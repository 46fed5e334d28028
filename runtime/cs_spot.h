// Cyclostationary spot noise (S4 §5.1, kind "cs-spot"): the model, its render setup (stex_cs_params of
// kernels/shared/cs.h, the Gaussian inverse-CDF table, the node reduction table), the C++ reference on the
// shared header, Appendix A's covariance, and the device renderer (kernels/cs_spot.cl). The analysis that
// makes a model from an exemplar and the codec are in analysis/cs_spot_model.h.
//
// Model fields, documented once here:
//  - periods t0, t1 (model pixels; any parallelogram, sub-pixel): the lattice L the spot is shot on.
//  - spot: width x height x channels texels, S = w (E - M): the exemplar minus its cyclic mean, times a
//    window that goes smoothly to zero at the borders (analysis/cs_spot_model.h).
//  - mean: the cyclic mean M on an n0 x n1 grid of phases (u, v) = (i / n0, j / n1) of the parallelogram.
//  - amplitude: sqrt(|Ω⁻| / sum w^2): makes the variance that of the exemplar's polyphase components.
//  - hist: the optional histogram transfer (runtime/cs_hist.h, S4 §5.3): when enabled, spot and mean are
//    those of the Gaussianised exemplar E_G and each output channel goes through T_P(x)^-1.
// Render parameters (runtime/texton_params.h RenderParams): seed and scale (output pixels per model pixel);
// mni and cell_factor are not used (the lattice fixes where spots are shot). Output: the model's channels.
#pragma once
#include <algorithm>
#include <array>
#include <cstddef>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "kernels/shared/cs.h"
#include "runtime/cs_hist.h"
#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/noise_renderer.h"
#include "runtime/program.h"
#include "runtime/texton_params.h"

namespace stex {

struct CsSpotModel {
  double t0x = 16.0, t0y = 0.0, t1x = 0.0, t1y = 16.0;
  int width = 0, height = 0, channels = 1;
  std::vector<float> spot;  // ((j * width) + i) * channels + c
  int n0 = 0, n1 = 0;
  std::vector<float> mean;  // ((j * n0) + i) * channels + c
  double amplitude = 1.0;
  CsHistTable hist;
};

inline constexpr int k_cs_max_spot = 4096;
// Lattice nodes whose spot may cover a point are visited per pixel: at most this many (spot area / |Ω⁻|).
inline constexpr double k_cs_max_nodes_per_spot = 65536.0;

// Checks every field; Error(Input) naming it ("invalid cs-spot model: ...").
void validate_cs_spot_model(const CsSpotModel& model);

// The checks the periods of every cs model pass (cs-spot, cs-rpn, cs-tb): coordinates finite and within 8192
// pixels, each vector at least 1 pixel long, a cell of at least 2 pixels^2 with the vectors at least 5 degrees
// apart. Error(Input) "invalid <kind> model: ..." naming the check that failed.
void validate_model_periods(const std::string& kind, double t0x, double t0y, double t1x, double t1y);

struct CsSpotSetup {
  stex_cs_params params{};
  std::vector<float> gauss;           // STEX_CS_GAUSS_SEGMENTS + 1 entries
  std::vector<std::uint32_t> reduce;  // 2 axes x STEX_CS_REDUCE_BITS x (k lo, k hi, l lo, l hi)
  stex_cs_hist_params hist_params{};
  std::vector<float> hist;            // cs_hist_device_table
  // T0, T1 in fixed output units, as used.
  std::int64_t T0x = 0, T0y = 0, T1x = 0, T1y = 0;
  // params.canon == 1 (the kernel's fast path, kernels/cs_spot.cl): for each dl in [dl0, dl1], the dk range
  // (first, last; empty when first > last) of the nodes whose spot may reach a point of the base cell.
  std::vector<std::int32_t> rows;
  // The largest chunk side that keeps the fast path's weight window within k_cs_max_window_nodes.
  int max_chunk_side = 4096;
};

// The fast path's per-chunk node window is about at most this many weights (16 MB; the chunk side is halved
// until the estimate fits, down to 16 pixels).
inline constexpr std::int64_t k_cs_max_window_nodes = std::int64_t(1) << 22;

// The lattice words the parameter structs of the cs kernels share (stex_cs_params, stex_csr_params): the
// The periods T0, T1 (int64 fixed point) as lo/hi 32-bit words of kernel parameters P (cs-spot, cs-rpn, cs-tb).
template <class P>
void set_period_words(P& p, std::int64_t t0x, std::int64_t t0y, std::int64_t t1x, std::int64_t t1y) {
  p.t0x_lo = stex_lo32(t0x);
  p.t0x_hi = stex_hi32(t0x);
  p.t0y_lo = stex_lo32(t0y);
  p.t0y_hi = stex_hi32(t0y);
  p.t1x_lo = stex_lo32(t1x);
  p.t1x_hi = stex_hi32(t1x);
  p.t1y_lo = stex_lo32(t1y);
  p.t1y_hi = stex_hi32(t1y);
}

// seed and the periods T0, T1 (int64 fixed point) as lo/hi 32-bit words, 1 / fixed-point scale and the
// inverse period matrix [[i00, i01], [i10, i11]].
template <class P>
void set_cs_lattice_words(P& p, std::uint64_t seed, std::int64_t t0x, std::int64_t t0y, std::int64_t t1x,
                          std::int64_t t1y, double fs, float i00, float i01, float i10, float i11) {
  p.seed_lo = stex_lo32(static_cast<stex_i64>(seed));
  p.seed_hi = stex_hi32(static_cast<stex_i64>(seed));
  set_period_words(p, t0x, t0y, t1x, t1y);
  p.inv_fix_scale = static_cast<float>(1.0 / fs);
  p.i00 = i00;
  p.i01 = i01;
  p.i10 = i10;
  p.i11 = i11;
}

// The node window [dk0, dk1] x [dl0, dl1] of kernel parameters P (cs-spot, cs-tb): a point's residual lies in
// the base cell (lattice coordinates in [-0.01, 1.01], float rounding included) and a node U contributes when
// the point minus U lands in the box [x0, x1] x [y0, y1] (output units); to_lattice(x, y, &a, &b) maps a box
// corner to lattice coordinates.
template <class P, class ToLattice>
void set_node_window(P& p, double x0, double y0, double x1, double y1, ToLattice to_lattice) {
  double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
  for (double x : {x0, x1})
    for (double y : {y0, y1}) {
      double a = 0.0, b = 0.0;
      to_lattice(x, y, &a, &b);
      amin = std::min(amin, a);
      amax = std::max(amax, a);
      bmin = std::min(bmin, b);
      bmax = std::max(bmax, b);
    }
  p.dk0 = stex_i32(std::floor(-0.01 - amax));
  p.dk1 = stex_i32(std::ceil(1.01 - amin));
  p.dl0 = stex_i32(std::floor(-0.01 - bmax));
  p.dl1 = stex_i32(std::ceil(1.01 - bmin));
}

// The canonical base of output pixel (px, py) (the exact floor of its lattice coordinates; params.canon == 1):
// node (k, l) and residual (rx, ry) in fixed units, as the reference finds it.
void cs_spot_canonical(const CsSpotSetup& setup, std::int64_t px, std::int64_t py, std::int64_t* k, std::int64_t* l,
                       std::int64_t* rx, std::int64_t* ry);
// The spot with 2 zero texels on every side, the fast path's layout ((width + 4) x (height + 4) x channels).
std::vector<float> cs_padded_spot(const CsSpotModel& model);

// The node table of kernels/shared/cs.h for a lattice with basis T0, T1 (fixed output units): for bit j of
// a pixel coordinate, the node nearest (2^j, 0) (axis 0) and (0, 2^j) pixels. Also used by kernels/shared/tb.h.
std::vector<std::uint32_t> cs_reduce_table(std::int64_t T0x, std::int64_t T0y, std::int64_t T1x, std::int64_t T1y);
// The piecewise-linear N(0, 1) inverse CDF of kernels/shared/cs.h (mean 0, variance exactly 1 in double).
std::vector<float> cs_gaussian_table();
// Validates model (Error(Input)) and parameters (Error(Usage): seed, scale; the period vectors must stay at
// least 1 output pixel long). Sets params.canon when the fast path applies: periods x scale at most 4096
// output pixels (2^28 fixed units) and every displacement of the node window within 32 bits; it depends on
// the model and the scale only.
CsSpotSetup make_cs_spot_setup(const CsSpotModel& model, const RenderParams& params);

// The C++ reference: stex_cs_spot_eval compiled as C++, one call per pixel (single-threaded; tests).
class CsSpotReference {
 public:
  CsSpotReference(const CsSpotModel& model, const RenderParams& params)
      : model_(model), setup_(make_cs_spot_setup(model, params)) {}
  // Pixels [x, x + width) x [y, y + height), row-major, channels interleaved. Validates the region.
  std::vector<float> render(std::int64_t x, std::int64_t y, int width, int height) const;
  const CsSpotSetup& setup() const { return setup_; }

 private:
  CsSpotModel model_;
  CsSpotSetup setup_;
};

// Appendix A at scale 1: the covariance of channels c1, c2 between output pixels p = (px, py) and p + (tx, ty),
// amplitude^2 sum_u S_c1(p - u) S_c2(p + t - u), with S the bilinear spot and u over the lattice nodes (in
// the fixed-point node positions the renderer uses). The mean at p is the model's M (stex_cs_mean_at).
double cs_spot_covariance(const CsSpotModel& model, std::int64_t px, std::int64_t py, int tx, int ty, int c1, int c2);
// The mean M at output pixel p at scale 1 (the renderer's value of stex_cs_mean_at).
double cs_spot_mean(const CsSpotModel& model, std::int64_t px, std::int64_t py, int c);

class CsSpotNoise final : public NoiseRenderer {
 public:
  // Validates the model (Error(Input)); options.strategy must be "auto" or "gather" (Error(Usage)).
  CsSpotNoise(Context& ctx, const CsSpotModel& model, const NoiseRendererOptions& options = {});
  std::string kind() const override { return "cs-spot"; }
  int channels() const override { return model_.channels; }
  // Reads seed and scale of RenderParams (mni and cell_factor are validated but unused).
  NoiseRenderStats render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                          float* out) override;

  // Tests: work-group size {x, y} ({0, 0}: default) and the largest chunk in pixels (0: device limit).
  std::array<std::size_t, 2> local_size{0, 0};
  std::size_t max_chunk_pixels = 0;
  const CsSpotModel& model() const { return model_; }

 private:
  Context& ctx_;
  CsSpotModel model_;
  RenderParams setup_params_;
  CsSpotSetup setup_;
  Buffer<float> spot_, spot_pad_, mean_, gauss_, hist_, weights_;
  Buffer<std::uint32_t> reduce_;
  Buffer<std::int32_t> rows_;
  std::unique_ptr<Kernel> kernel_, weights_kernel_, general_kernel_;
};

}  // namespace stex
