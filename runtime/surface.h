// Surface texton noise (S1 §6): the parameters, the kernel struct (kernels/shared/surface.h), tangent frames,
// the C++ reference evaluator and the device point-query renderer.
//
// A surface point is a world position y with an orthonormal frame (u1, u2, u3), u3 the surface normal; its
// value is the normalised surface noise g^s(y) of Proposition 3: mean, variance and covariance in the
// tangent plane are those of the model's plane noise, for any frame. The frame orients the texton in the
// tangent plane: it should vary continuously over the surface (S1 §6), e.g. interpolated vertex normals and
// tangents. surface_frame builds one from a normal alone: u1 is the world X axis projected on the tangent
// plane, continuous except near the (at most two) points where the normal is parallel to X.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "kernels/shared/surface.h"
#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/model.h"
#include "runtime/program.h"

namespace stex {

// Parameters of surface noise. Documented once here; `stex surface --help`, the C API and README use it.
struct SurfaceParams {
  // Mean number of impacts lambda r^3 (Proposition 3), in (0, 10000]. S1 §9 uses 60 for surfaces (the
  // weight (1 - 2|t|/r)^+ makes fewer impulses count fully than in the plane).
  double mni = 60.0;
  // Cell side of the 3-D grid Poisson process as a fraction of r, in [0.1, 2] (S1 §8: 0.6).
  double cell_factor = 0.6;
  std::uint64_t seed = 0;
  // World units per exemplar pixel (texton texel), in [1e-9, 1e9]: the texture's scale on the surface.
  double texel = 1.0;
};

inline constexpr double k_max_surface_mni = 10000.0;
// World coordinates are converted to float texton units; beyond 2^22 texton units float positions lose
// the sub-texel precision the texton needs.
inline constexpr double k_max_surface_coordinate = 4194304.0;  // 2^22 texton units

struct SurfaceSetup {
  stex_surface_params params{};
  std::vector<float> alpha_padded;           // as TextonSetup::alpha_padded
  std::vector<std::uint32_t> poisson_table;  // Poisson(lambda a^3) thresholds
  double lambda = 0.0;                       // impulses per cubic texel
  double r = 0.0;                            // support side (texels)
  double cell_mean = 0.0;                    // lambda a^3
  int channels = 0;
};

// Throws stex::Error(Usage) naming the parameter.
void validate_surface_params(const SurfaceParams& params);
// Validates model (Error(Input)) and parameters, builds the kernel struct, padded alpha and Poisson table.
SurfaceSetup make_surface_setup(const TextonModel& model, const SurfaceParams& params);

// An orthonormal frame u1 u2 u3 (9 floats) from a normal and an optional tangent (nullptr: projected X axis).
// The normal is normalised; the tangent is made orthogonal to it (Gram-Schmidt) and normalised, u2 = u3 x u1.
// A tangent parallel to the normal falls back to the projected X axis. Error(Usage) for a zero or non-finite normal
// or non-finite tangent; `index` names the point in the message.
std::array<float, 9> surface_frame(const double* normal, const double* tangent, std::size_t index = 0);

// Checks one world position: finite and |coordinate| / texel below k_max_surface_coordinate.
void validate_surface_position(const SurfaceParams& params, const double* position, std::size_t index);

// The C++ reference: stex_surface_eval on the host (tests, small meshes).
class SurfaceReference {
 public:
  SurfaceReference(const TextonModel& model, const SurfaceParams& params);
  // out[c] for c < channels(); position in world units (converted to float), frame 9 floats.
  void eval(const float* position, const float* frame, float* out) const;
  // Unnormalised f^s (Proposition 3's sum) at a position in texton units.
  void sum(const float* q, const float* frame, float* acc) const;
  std::uint32_t cell_count(std::int64_t kx, std::int64_t ky, std::int64_t kz) const;
  int channels() const { return setup_.channels; }
  const SurfaceSetup& setup() const { return setup_; }

 private:
  SurfaceSetup setup_;
};

// Device evaluation of surface points (kernels/surface_points.cl), bit-identical to SurfaceReference.
class SurfaceRenderer {
 public:
  SurfaceRenderer(Context& ctx, const TextonModel& model);
  SurfaceRenderer(const SurfaceRenderer&) = delete;
  SurfaceRenderer& operator=(const SurfaceRenderer&) = delete;

  // count points: positions 3 floats (world units), frames 9 floats each, out count * channels floats
  // (interleaved). Processed in batches; the result does not depend on the batch size.
  void eval(const SurfaceParams& params, std::size_t count, const float* positions, const float* frames,
            float* out, std::size_t batch = 0);
  int channels() const { return model_.channels; }

 private:
  Context& ctx_;
  TextonModel model_;
  Buffer<float> alpha_;
  std::unique_ptr<Kernel> kernel_;
};

}  // namespace stex
