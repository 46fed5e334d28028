// On-the-fly filtering of texton noise (S1 §5): the MIP pyramid of the texton, a pixel's footprint from its
// UV Jacobian (trilinear level of detail plus anisotropic probes along the major axis), a perspective plane
// camera that gives every pixel its plane position and Jacobian, and the renderers (device:
// kernels/texton_filtered.cl; C++ reference) over kernels/shared/texton_filter.h. Device and reference are
// bit-identical, and a pixel depends only on (model, parameters, camera, seed, its coordinates).
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "kernels/shared/texton_filter.h"
#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/model.h"
#include "runtime/program.h"
#include "runtime/reference.h"
#include "runtime/texton_renderer.h"
#include "runtime/texton_params.h"

namespace stex {

// Most probes along a footprint's major axis (GPUs offer 2..16; 8 keeps the cost of grazing views bounded).
inline constexpr int k_max_aniso = 8;

struct MipPyramid {
  stex_mip_params params{};
  std::vector<float> data;  // padded levels, layout of stex_mip_params (plus a zero guard)
};

// The pyramid of a bilinear (order 1) texton: level l + 1 = 2 x 2 box average of level l (zero outside), down to
// 1 x 1; computed in double from alpha (the block mean of 4^l coefficients), rounded once to float.
// Error(Usage) for orders other than 1 (S1 §5 filters the bilinear texton).
MipPyramid make_mip_pyramid(const TextonModel& model);

// The footprint of a pixel whose Jacobian (texton texels per output pixel) has columns a = (jxx, jyx) and
// b = (jxy, jyy), for a pyramid of `levels` levels; `fix_per_texel` converts texels to the position's fixed
// units (2^16 scale for the flat plane, 2^16 for mapped positions). Magnification (both axes <= 1 texel)
// gives level 0, one probe: the unfiltered tap.
stex_footprint make_footprint(int levels, double jxx, double jxy, double jyx, double jyy, double fix_per_texel);

// The box prefilter of a minified flat view (scale < 1, any order; docs/filtering.md): by linearity the box
// filter of texton noise is the shot noise of h_w = h * b_w, the texton convolved with the pixel's box (w =
// 1 / scale texels per side, normalised). h_w = sum_k alpha(k) Phi(t_x - k_x) Phi(t_y - k_y) with Phi = psi * box_w
// per axis, in closed form for every B-spline order (psi's antiderivative), sampled in double at `spacing`
// texels (1/2; a coarser power of two where the table would pass 512 samples per axis), rounded once to float.
// `texton` is that table as a bilinear texton (its texel `spacing` exemplar pixels, its sample 0 at texton
// coordinate `origin` = -shift / scale); `integral` its integral per channel (spacing^2 times the sum of its
// samples), so lambda * integral is the mean term and the mean is exact.
struct BoxPrefilter {
  TextonModel texton;
  std::array<double, 4> integral{};
  double spacing = 0.5;
  std::int64_t shift = 0;  // whole output pixels
  double origin = 0.0;     // texels
};
// Error(Usage) unless 0 < scale < 1.
BoxPrefilter make_box_prefilter(const TextonModel& model, double scale);
// The setup that renders the prefiltered noise with every texton strategy (splat, gather, gather-local): base's
// grid, intensity, Poisson table and seed (the same impulses), the table as the texton, lambda_sum_alpha from
// its integral; pixel P is evaluated at P + pixel_shift (TextonRenderer and TextonReference shift the region).
TextonSetup prefiltered_setup(const TextonSetup& base, const BoxPrefilter& pre, double scale);
// Whether a render of a texton (or mix) model reads the box prefilter: params.filter at scale < 1.
inline bool texton_prefilters(const RenderParams& params) { return params.filter && params.scale < 1.0; }
// make_texton_setup, or the prefiltered setup when texton_prefilters(params).
TextonSetup make_filtered_texton_setup(const TextonModel& model, const RenderParams& params);

// A perspective view of the textured plane z = 0 (plane units: exemplar pixels = texton texels). The camera
// stands above plane point (0, 0) at `height`, looks towards +y tilted `tilt` degrees from straight down (0:
// top view, < 90), with a vertical field of view of `fov` degrees over the image's `image_height` pixels; the
// image is `image_width` x `image_height` output pixels, pixel (i, j) with its centre at (i + 1/2, j + 1/2).
// Pixels whose ray misses the plane (above the horizon) or hits it beyond 2^40 texels are sky: the mean.
struct PerspectiveCamera {
  double height = 256.0, tilt = 60.0, fov = 60.0;
  std::int64_t image_width = 0, image_height = 0;
};
// "HEIGHT,TILT,FOV" (e.g. "200,70,60"); Error(Usage) naming the problem (height > 0, tilt in [0, 89],
// fov in (0, 170)).
PerspectiveCamera parse_camera(const std::string& spec, std::int64_t image_width, std::int64_t image_height);
// Plane point (u, v) and Jacobian j = {du/di, du/dj, dv/di, dv/dj} of pixel (i, j); false for sky.
bool camera_map(const PerspectiveCamera& cam, std::int64_t i, std::int64_t j, double* u, double* v, double jac[4]);

// The plane point (u, v) seen through the continuous image position (px, py) (pixel (i, j)'s centre is
// (i + 1/2, j + 1/2)); false for sky. camera_map(i, j) is camera_point(i + 1/2, j + 1/2) plus the Jacobian.
bool camera_point(const PerspectiveCamera& cam, double px, double py, double* u, double* v);

// A UV map (stex render --uv-map): for every pixel (i, j) of a width x height image, the plane point (u, v) in
// exemplar pixels (texels) that the pixel's centre sees, at uv[2 (j width + i)], uv[2 (j width + i) + 1]. The
// pixel's UV Jacobian comes from finite differences of its neighbours: central, (p(i+1) - p(i-1)) / 2,
// inside; one-sided, p(i+1) - p(i) or p(i) - p(i-1), on the image's border (likewise along j).
struct UvMap {
  int width = 0, height = 0;
  std::vector<double> uv;
};
// Checks the map: at least 2x2 pixels (a Jacobian needs a neighbour along each axis), uv.size() = 2 w h, every
// value finite with |value| < 2^40 texels. Error(Input) naming the first bad pixel.
void validate_uv_map(const UvMap& map, const std::string& what = "UV map");
// The Jacobian {du/di, du/dj, dv/di, dv/dj} of pixel (i, j) (finite differences, as above).
void uv_map_jacobian(const UvMap& map, int i, int j, double jac[4]);
// Positions (fixed units at scale 1) and footprints of rows [y, y + h) of the map (all columns), as
// camera_footprints.
void uv_map_footprints(const UvMap& map, int levels, int y, int h, std::vector<std::int64_t>* pos,
                       std::vector<stex_footprint>* fp, bool filter = true);

// Per-pixel positions (fixed units at scale 1) and footprints of region [x, x + w) x [y, y + h) of a camera
// view (probes = 0 marks sky). filter = false gives every ground pixel the unfiltered tap (point sampling:
// what the view looks like without S1 §5, for comparisons).
void camera_footprints(const PerspectiveCamera& cam, int levels, std::int64_t x, std::int64_t y, int w, int h,
                       std::vector<std::int64_t>* pos, std::vector<stex_footprint>* fp, bool filter = true);

// The C++ reference of the filtered evaluation (tests, baselines): stex_texton_eval_filtered per pixel.
class FilteredTextonReference {
 public:
  FilteredTextonReference(const TextonModel& model, const RenderParams& params);
  // The flat plane at params.scale, filtered: the box prefilter below scale 1 (any order), else level 0 of the
  // MIP (order 1; the unfiltered bits).
  std::vector<float> render_scaled(std::int64_t x, std::int64_t y, int width, int height) const;
  // A camera view (the setup is built at scale 1: plane units are texels).
  std::vector<float> render_camera(const PerspectiveCamera& cam, std::int64_t x, std::int64_t y, int width,
                                   int height) const;
  // A UV map's image, map.width x map.height (the setup is built at scale 1).
  std::vector<float> render_uv_map(const UvMap& map) const;
  const TextonSetup& setup() const { return setup_; }
  const MipPyramid& pyramid() const { return pyramid_; }
  // The footprint of render_scaled at scale >= 1 (level 0, one probe: the unfiltered tap).
  const stex_footprint& scaled_footprint() const { return scaled_; }

 private:
  void need_pyramid() const;  // Error(Usage) unless order 1 (cameras, UV maps, magnified views)

  TextonSetup setup_;
  int order_ = 1;
  MipPyramid pyramid_;  // order 1
  std::unique_ptr<TextonReference> minified_;  // scale < 1: the box prefilter
  stex_footprint scaled_{};
};

// The device renderer of filtered texton noise (gather, kernels/texton_filtered.cl). Interleaved output as
// TextonRenderer. Chunked by rows: output never depends on the chunking. Minified flat views (render_scaled at
// scale < 1) read the box prefilter, any order; cameras, UV maps and magnified views the MIP pyramid (order 1).
class FilteredTextonRenderer {
 public:
  FilteredTextonRenderer(Context& ctx, const TextonModel& model);
  std::vector<float> render_scaled(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                                   double* device_ms = nullptr, std::size_t max_chunk_pixels = 0);
  // params.scale is ignored (the camera defines the mapping); mni, cell factor and seed apply.
  std::vector<float> render_camera(const RenderParams& params, const PerspectiveCamera& cam, std::int64_t x,
                                   std::int64_t y, int width, int height, double* device_ms = nullptr,
                                   std::size_t max_chunk_pixels = 0, bool filter = true);
  // A UV map's image, map.width x map.height (validated first); params.scale is ignored, as for cameras.
  std::vector<float> render_uv_map(const RenderParams& params, const UvMap& map, double* device_ms = nullptr,
                                   std::size_t max_chunk_pixels = 0, bool filter = true);
  int channels() const { return model_.channels; }
  // Launches of the last render and the most launches one chunk's cells were split over (1: not split;
  // more where the driver cut an invocation's loops short, docs/portability.md, loop watchdog).
  int last_launches() const { return last_launches_; }
  int last_cell_passes() const { return last_cell_passes_; }

 private:
  // Fills positions and footprints of rows [r0, r0 + rows) of a width-wide image.
  using FootprintRows = void (*)(const void* source, int levels, std::int64_t x, std::int64_t r0, int width,
                                 int rows, bool filter, std::vector<std::int64_t>* pos,
                                 std::vector<stex_footprint>* fp);
  std::vector<float> render_mapped(const RenderParams& params, const void* source, FootprintRows rows_of,
                                   std::int64_t x, std::int64_t y, int width, int height, double* device_ms,
                                   std::size_t max_chunk_pixels, bool filter);

  // Launches `kernel` (arguments before `index` set; `index`.. are cell_first, cell_end, pass, then the
  // watchdog) over width x height pixels whose most cells is max_cells: all cells in one launch, and where
  // the loop watchdog trips, the cells split into windows of half the size, again and again, each window a
  // launch continuing the last one's sums (same bits); Error(Device) if one cell per launch still trips.
  double launch_cells(Kernel& kernel, cl_uint index, int width, int height, std::int64_t max_cells);

  void need_pyramid() const;  // Error(Usage) unless order 1

  Context& ctx_;
  int last_launches_ = 0;
  int last_cell_passes_ = 0;
  TextonModel model_;
  MipPyramid pyramid_;  // order 1: cameras, UV maps, magnified views
  Buffer<float> pyr_;
  std::unique_ptr<TextonRenderer> minified_;  // scale < 1: the box prefilter, the default strategy
  std::unique_ptr<Kernel> scaled_, mapped_;
};

}  // namespace stex
