// Tiling and blending (kinds "tb" and "cs-tb"; Heitz & Neyret HPG 2018, S4 §5.2): the model, its render setup
// (stex_tb_params of kernels/shared/tb.h, node tables), the C++ reference and the device renderer
// (kernels/tb.cl). The analysis (Gaussianisation, PCA, cyclic mean) and the codec are in analysis/tb_model.h.
//
// Model fields, documented once here:
//  - cs: false for "tb" (random tile offsets), true for "cs-tb" (offsets congruent modulo the periods).
//  - tile: the side L of the triangle grid in model pixels (a vertex's hexagonal tile has radius L).
//  - gauss: width x height x channels, the exemplar in PCA coordinates, each channel Gaussianised by T to
//    N(0.5, 1/6^2).
//  - lut: channels x lut_size entries of T^-1 sampled uniformly on [lut_lo, lut_hi].
//  - pca: channels means, then the channels x channels rows of the PCA basis B (y = B (x - mean)).
//  - periods t0, t1 and the cyclic mean of gauss on an n0 x n1 phase grid (cs-tb only).
//  - hist (cs-tb only, optional): the cyclostationary histogram transfer (runtime/cs_hist.h, S4 §5.3.2):
//    gauss is then Gaussianised per polyphase bin and the render applies T_P(x)^-1 instead of the LUT.
// Render parameters: seed, scale (mni and cell_factor unused). Output: the model's channels.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "kernels/shared/tb.h"
#include "runtime/cs_hist.h"
#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/loop_watchdog.h"
#include "runtime/noise_renderer.h"
#include "runtime/program.h"
#include "runtime/texton_params.h"

namespace stex {

struct TbModel {
  bool cs = false;
  double tile = 32.0;
  int width = 0, height = 0, channels = 1;
  std::vector<float> gauss;
  int lut_size = 0;
  double lut_lo = -0.25, lut_hi = 1.25;
  std::vector<float> lut, pca;
  double t0x = 0.0, t0y = 0.0, t1x = 0.0, t1y = 0.0;
  int n0 = 1, n1 = 1;
  std::vector<float> mean;  // cs only; n0 x n1 x channels (a single 0.5 entry per channel for tb)
  CsHistTable hist;         // cs only; mode none (the stationary LUT) or cs
};

// Checks every field (Error(Input) naming it), including that the tile fits the exemplar (2 L + 4 <= size)
// and, for cs-tb, that the box of allowed tile centres holds a whole parallelogram of the periods.
void validate_tb_model(const TbModel& model);

struct TbSetup {
  stex_tb_params params{};
  std::vector<std::uint32_t> reduce_grid, reduce_cs;
  stex_cs_hist_params hist_params{};
  std::vector<float> hist;  // cs_hist_device_table
  // Scale 1 and (tb, or cs-tb with integer periods): every fetch lands on a texel centre (kernels/shared/tb.h,
  // stex_tb_local), so the kernels read one texel per fetch.
  bool aligned = false;
};
// Validates model and parameters (Error(Usage): tile x scale and periods x scale at most 4096 output pixels).
TbSetup make_tb_setup(const TbModel& model, const RenderParams& params);
// Start nodes (grid k, l; lattice k, l) near output pixel (px, py) for stex_tb_eval, from the bit tables.
void tb_start_nodes(const TbSetup& setup, std::int64_t px, std::int64_t py, std::int64_t* start4);
// The canonical nodes (grid k, l; lattice k, l) and residuals (grid x, y; lattice x, y) of output pixel
// (px, py): the exact floors of its lattice coordinates (lattice entries 0 for tb).
void tb_canonical(const TbSetup& setup, std::int64_t px, std::int64_t py, std::int64_t* node4, std::int64_t* residual4);

class TbReference {
 public:
  TbReference(const TbModel& model, const RenderParams& params) : model_(model), setup_(make_tb_setup(model, params)) {}
  std::vector<float> render(std::int64_t x, std::int64_t y, int width, int height) const;

 private:
  TbModel model_;
  TbSetup setup_;
};

class TbNoise final : public NoiseRenderer {
 public:
  TbNoise(Context& ctx, const TbModel& model, const NoiseRendererOptions& options = {});
  std::string kind() const override { return model_.cs ? "cs-tb" : "tb"; }
  int channels() const override { return model_.channels; }
  NoiseRenderStats render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                          float* out) override;
  std::array<std::size_t, 2> local_size{0, 0};
  std::size_t max_chunk_pixels = 0;
  // The pixel kernel of a frame whose tile x scale is >= 8 output pixels (tb and cs-tb, any scale): -1 (auto)
  // the run kernel tb_run on CPU devices (PoCL vectorises the per-pixel kernel across work-items poorly; a run
  // of 8 or 16 pixels shares its scalar work and, aligned (TbSetup::aligned), reads consecutive texels) and
  // the per-pixel kernel elsewhere (GPUs: neighbouring work-items' loads already coalesce); 0 always the
  // per-pixel kernel; 1 the run kernel whenever it applies.
  // Both give the same bits (tests/cs/test_tb.cpp).
  int run_mode = -1;
  // Lanes of the run kernel: 0 (auto) 16 when the tile is at least 16 output pixels wide, else 8 (faster on
  // AVX2 and AVX-512 alike: docs/cyclostationary.md); 8 or 16 to force one (16 falls back to 8 on a narrower
  // tile). Both give the same bits.
  int run_lanes = 0;
  std::string last_kernel;  // the pixel kernel of the last render: "tb", "tb_run" (8 lanes) or "tb_run16"

 private:
  Context& ctx_;
  TbModel model_;
  RenderParams setup_params_;
  TbSetup setup_;
  Buffer<float> gauss_, lut_, pca_, mean_, hist_;
  Buffer<float> planar_, lut_pairs_;  // tb_run's exemplar (channel planes between paddings) and LUT pairs
  Buffer<cl_int> centres_;   // the vertex pass's tile centres or texel offsets (grown as needed)
  Buffer<float> out_;        // the output chunk, kept across renders (GatherChunking::out_buffer)
  // Per-pixel and vertex kernels of the programs [general at scale != 1, general at scale 1, aligned]; the run
  // kernel (aligned program).
  std::unique_ptr<Kernel> kernel_[3], vertex_kernel_[3], run_kernel_[3][2];  // run kernel: [variant][8 lanes, 16 lanes]
  std::unique_ptr<LoopWatchdog> vertex_watchdog_;  // tb_vertices' canary (loop_watchdog.h)
};

}  // namespace stex
