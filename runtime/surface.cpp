// Surface texton noise (S1 §6, Proposition 3): setup, frames, reference and device evaluation. See surface.h.
#include "runtime/surface.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "core/error.h"
#include "core/format.h"
#include "runtime/loop_watchdog.h"
#include "runtime/poisson_table.h"
#include "runtime/texton_params.h"

namespace stex {

static_assert(sizeof(stex_surface_params) == 96, "stex_surface_params must match the OpenCL layout (96 bytes)");

namespace {

[[noreturn]] void usage(const std::string& message) { throw Error(ErrorKind::Usage, message); }

std::string num(double v) { return exact_number(v); }

constexpr std::size_t k_default_batch = std::size_t(1) << 18;

}  // namespace

void validate_surface_params(const SurfaceParams& p) {
  if (!std::isfinite(p.mni) || p.mni <= 0.0 || p.mni > k_max_surface_mni)
    usage("--mni must be in (0, " + num(k_max_surface_mni) + "], got " + num(p.mni));
  if (!std::isfinite(p.cell_factor) || p.cell_factor < k_min_cell_factor || p.cell_factor > k_max_cell_factor)
    usage("--cell (cell side as a fraction of the texton support) must be in [" + num(k_min_cell_factor) + ", " +
          num(k_max_cell_factor) + "], got " + num(p.cell_factor));
  if (!std::isfinite(p.texel) || p.texel < 1e-9 || p.texel > 1e9)
    usage("--texel (world units per exemplar pixel) must be in [1e-9, 1e9], got " + num(p.texel));
}

SurfaceSetup make_surface_setup(const TextonModel& model, const SurfaceParams& sp) {
  validate_texton_model(model);
  // kernels/shared/surface.h evaluates nearest and bilinear textons; the B-spline orders of S1 §10 are plane
  // noise only (their taps are not in stex_surface_sum).
  if (model.order != 0 && model.order != 1)
    throw Error(ErrorKind::Input, "surface noise needs a texton model of order 0 or 1, this one has order " +
                                      std::to_string(model.order));
  validate_surface_params(sp);
  // The padded alpha planes are the plane renderer's (same layout, same fetch).
  TextonSetup plane = make_texton_setup(model, RenderParams{});

  SurfaceSetup out;
  const int s = model.support;
  const double r = double(s + model.order);
  const double lambda = sp.mni / (r * r * r);  // Proposition 3: MNI = lambda r^3
  const float a = static_cast<float>(sp.cell_factor * r);
  const double cell_mean = lambda * double(a) * double(a) * double(a);
  out.poisson_table = poisson_threshold_table(cell_mean);

  stex_surface_params& p = out.params;
  p.support = s;
  p.channels = model.channels;
  p.order = model.order;
  p.stride = s + 2;
  p.seed_lo = stex_lo32(static_cast<stex_i64>(sp.seed));
  p.seed_hi = stex_hi32(static_cast<stex_i64>(sp.seed));
  p.poisson_len = static_cast<stex_u32>(out.poisson_table.size());
  p.inv_texel = static_cast<float>(1.0 / sp.texel);
  p.cell = a;
  p.inv_cell = static_cast<float>(1.0 / double(a));
  // Every contributing impulse lies in the cube of side r about y, so within r sqrt(3)/2 of it. The float
  // dot products may accept an impulse a few ulp outside: a relative margin of 1e-3 plus 1/64 texel covers
  // that by orders of magnitude; cells the margin adds only contribute skipped impulses.
  p.reach = static_cast<float>(r * std::sqrt(3.0) / 2.0 * 1.001 + 1.0 / 64.0);
  p.two_over_r = static_cast<float>(2.0 / r);
  p.centre = static_cast<float>((s - 1) / 2.0);
  p.t_lo = model.order == 1 ? -1.0f : -0.5f;
  p.t_hi = model.order == 1 ? float(s) : float(s) - 0.5f;
  p.inv_norm = static_cast<float>(1.0 / std::sqrt(lambda * r / 3.0));
  for (int c = 0; c < STEX_MAX_CHANNELS; ++c) {
    p.mean[c] = 0.0f;
    p.lambda_half_r_sum_alpha[c] = 0.0f;
  }
  for (int c = 0; c < model.channels; ++c) {
    double sum = 0.0;
    for (int i = 0; i < s * s; ++i) sum += double(model.alpha[std::size_t(c) * s * s + i]);
    p.mean[c] = model.mean[c];
    p.lambda_half_r_sum_alpha[c] = static_cast<float>(lambda * r / 2.0 * sum);
  }
  out.alpha_padded = std::move(plane.alpha_padded);
  out.lambda = lambda;
  out.r = r;
  out.cell_mean = cell_mean;
  out.channels = model.channels;
  return out;
}

std::array<float, 9> surface_frame(const double* normal, const double* tangent, std::size_t index) {
  const std::string at = "point " + std::to_string(index) + ": ";
  double n[3] = {normal[0], normal[1], normal[2]};
  if (!std::isfinite(n[0]) || !std::isfinite(n[1]) || !std::isfinite(n[2]))
    usage(at + "the normal is not finite");
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(len > 1e-30)) usage(at + "the normal is zero");
  for (double& v : n) v /= len;
  double t[3] = {0, 0, 0};
  bool have_t = false;
  if (tangent) {
    if (!std::isfinite(tangent[0]) || !std::isfinite(tangent[1]) || !std::isfinite(tangent[2]))
      usage(at + "the tangent is not finite");
    const double d = tangent[0] * n[0] + tangent[1] * n[1] + tangent[2] * n[2];
    for (int i = 0; i < 3; ++i) t[i] = tangent[i] - d * n[i];
    const double tl = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    const double tan_len = std::sqrt(tangent[0] * tangent[0] + tangent[1] * tangent[1] + tangent[2] * tangent[2]);
    if (tl > 1e-6 * tan_len && tl > 0.0) {
      for (double& v : t) v /= tl;
      have_t = true;
    }
  }
  if (!have_t) {
    // The world X axis projected on the tangent plane: continuous over a surface except where the normal
    // is (anti)parallel to X (two antipodal points on a sphere; S1 §6: no continuous field exists there).
    // Within 1e-3 of those, Duff et al.'s branchless basis (JCGT 6(1), 2017, Listing 3).
    const double d = n[0];
    for (int i = 0; i < 3; ++i) t[i] = (i == 0 ? 1.0 : 0.0) - d * n[i];
    const double tl = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    if (tl > 1e-3) {
      for (double& v : t) v /= tl;
    } else {
      const double sign = std::copysign(1.0, n[2]);
      const double a = -1.0 / (sign + n[2]);
      const double b = n[0] * n[1] * a;
      t[0] = 1.0 + sign * n[0] * n[0] * a;
      t[1] = sign * b;
      t[2] = -sign * n[0];
    }
  }
  const double b[3] = {n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0]};
  return {float(t[0]), float(t[1]), float(t[2]), float(b[0]), float(b[1]), float(b[2]),
          float(n[0]), float(n[1]), float(n[2])};
}

void validate_surface_position(const SurfaceParams& params, const double* position, std::size_t index) {
  for (int i = 0; i < 3; ++i) {
    const double v = position[i];
    if (!std::isfinite(v) || std::fabs(v) / params.texel >= k_max_surface_coordinate)
      usage("point " + std::to_string(index) + ": coordinate " + std::to_string(i) + " = " + num(v) +
            " is not finite or too far from the origin (|coordinate| / texel must be below 2^22)");
  }
}

SurfaceReference::SurfaceReference(const TextonModel& model, const SurfaceParams& params)
    : setup_(make_surface_setup(model, params)) {}

void SurfaceReference::eval(const float* position, const float* frame, float* out) const {
  float v[STEX_MAX_CHANNELS];
  stex_surface_eval(setup_.params, setup_.alpha_padded.data(), setup_.poisson_table.data(), position[0],
                    position[1], position[2], frame, v);
  for (int c = 0; c < setup_.channels; ++c) out[c] = v[c];
}

void SurfaceReference::sum(const float* q, const float* frame, float* acc) const {
  float v[STEX_MAX_CHANNELS];
  stex_surface_sum(setup_.params, setup_.alpha_padded.data(), setup_.poisson_table.data(), q[0], q[1], q[2],
                   frame, v);
  for (int c = 0; c < setup_.channels; ++c) acc[c] = v[c];
}

std::uint32_t SurfaceReference::cell_count(std::int64_t kx, std::int64_t ky, std::int64_t kz) const {
  return stex_surface_count(setup_.params, stex_cell_key3(kx, ky, kz), setup_.poisson_table.data());
}

SurfaceRenderer::SurfaceRenderer(Context& ctx, const TextonModel& model) : ctx_(ctx), model_(model) {
  SurfaceSetup setup = make_surface_setup(model_, SurfaceParams{});
  alpha_ = Buffer<float>(ctx_, setup.alpha_padded, CL_MEM_READ_ONLY, "texton alpha");
}

void SurfaceRenderer::eval(const SurfaceParams& params, std::size_t count, const float* positions,
                           const float* frames, float* out, std::size_t batch) {
  const SurfaceSetup setup = make_surface_setup(model_, params);
  if (count == 0) return;
  if (!kernel_) kernel_ = std::make_unique<Kernel>(ctx_.program("surface_points.cl"), "surface_points");
  if (batch == 0) batch = k_default_batch;
  batch = std::min(batch, count);
  const std::size_t nc = std::size_t(model_.channels);
  Buffer<std::uint32_t> table(ctx_, setup.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
  Buffer<float> pos(ctx_, 3 * batch, CL_MEM_READ_ONLY, "surface positions");
  Buffer<float> frm(ctx_, 9 * batch, CL_MEM_READ_ONLY, "surface frames");
  Buffer<float> val(ctx_, batch * nc, CL_MEM_WRITE_ONLY, "surface values");
  LoopWatchdog watchdog(ctx_);
  for (std::size_t k0 = 0; k0 < count; k0 += batch) {
    const std::size_t n = std::min(batch, count - k0);
    pos.write(positions + 3 * k0, 3 * n);
    frm.write(frames + 9 * k0, 9 * n);
    cl_uint a = 0;
    kernel_->set_arg(a++, setup.params);
    kernel_->set_arg(a++, alpha_);
    kernel_->set_arg(a++, table);
    kernel_->set_arg(a++, pos);
    kernel_->set_arg(a++, frm);
    kernel_->set_arg(a++, cl_uint(n));
    kernel_->set_arg(a++, val);
    launch_watched(ctx_, *kernel_, watchdog, a, n, 1, {0, 0});
    val.read(out + k0 * nc, n * nc);
  }
}

}  // namespace stex
