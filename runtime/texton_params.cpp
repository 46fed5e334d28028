// Render parameters -> stex_texton_params (S1 §3.3 intensity, §8 cell grid). See texton_params.h.
#include "runtime/texton_params.h"

#include <cmath>
#include <sstream>

#include "core/error.h"
#include "core/format.h"
#include "runtime/poisson_table.h"

namespace stex {

static_assert(sizeof(stex_texton_params) == 104, "stex_texton_params must match the OpenCL layout (104 bytes)");

namespace {

constexpr double k_fix_one = double(std::int64_t(1) << STEX_FIX_BITS);  // 2^16

[[noreturn]] void usage(const std::string& message) { throw Error(ErrorKind::Usage, message); }

std::string num(double v) { return exact_number(v); }

// Conservative reach in fixed units of a texton support edge at `t` texton units. The tap tests
// float(D) * inv_fix_scale against t_lo/t_hi in float: the float product can land inside the support for a
// displacement whose exact value is outside by up to ~3 ulp (relative 2^-22). A relative margin of 2^-20
// plus 2 units keeps every displacement the tap may accept inside the reach, so that the gather's per-pixel
// cell range contains every impulse with non-zero weights (S1 §8); extra cells only add exact zeros.
std::int64_t reach_units(double t, double scale) {
  return static_cast<std::int64_t>(std::ceil(t * k_fix_one * scale * (1.0 + 1.0 / 1048576.0))) + 2;
}

}  // namespace

void validate_texton_model(const TextonModel& m) {
  auto bad = [](const std::string& what) { throw Error(ErrorKind::Input, "invalid texton model: " + what); };
  if (m.channels < 1 || m.channels > STEX_MAX_CHANNELS) bad("channels must be 1..4, got " + std::to_string(m.channels));
  if (m.support < 1 || m.support > k_max_texton_support)
    bad("support must be 1.." + std::to_string(k_max_texton_support) + ", got " + std::to_string(m.support));
  if (!valid_texton_order(m.order)) bad("order must be 0, 1, 3 or 5, got " + std::to_string(m.order));
  const std::size_t expected = std::size_t(m.channels) * std::size_t(m.support) * std::size_t(m.support);
  if (m.alpha.size() != expected)
    bad("alpha has " + std::to_string(m.alpha.size()) + " values, expected channels*support^2 = " +
        std::to_string(expected));
  for (std::size_t i = 0; i < m.alpha.size(); ++i)
    if (!std::isfinite(m.alpha[i])) bad("alpha[" + std::to_string(i) + "] is not finite");
  for (int c = 0; c < m.channels; ++c)
    if (!std::isfinite(m.mean[c])) bad("mean[" + std::to_string(c) + "] is not finite");
}

TextonSetup make_texton_setup(const TextonModel& model, const RenderParams& rp) {
  validate_texton_model(model);
  validate_render_params(rp);

  TextonSetup out;
  const int s = model.support;
  const int r = s + model.order;
  const double lambda = rp.mni / (double(r) * double(r));
  const double a_real = rp.cell_factor * double(r) * rp.scale * k_fix_one;
  if (a_real < 256.0)
    usage("cell side c*r*scale = " + num(a_real / k_fix_one) +
          " output pixels is below 1/256 pixel: raise --scale or --cell");
  if (a_real >= std::ldexp(1.0, 38))
    usage("cell side c*r*scale = " + num(a_real / k_fix_one) + " output pixels is too large (>= 2^22)");
  const std::int64_t a = std::llround(a_real);
  // The intensity lambda is exact; only the grid follows the rounded A.
  const double cell_side = double(a) / (k_fix_one * rp.scale);  // exemplar pixels
  const double cell_mean = lambda * cell_side * cell_side;
  std::vector<std::uint32_t> table = poisson_threshold_table(cell_mean);

  // Support of h: [-(order+1)/2, s - 1 + (order+1)/2) (texton.h).
  const float half_width = 0.5f * float(model.order + 1);
  const float t_lo = -half_width;
  const float t_hi = float(s - 1) + half_width;
  // Zero frame of the padded alpha: the taps of a displacement inside the support stay within it.
  const int frame = model.order <= 1 ? 1 : model.order;
  const std::int64_t reach_back = reach_units(double(t_hi), rp.scale);
  const std::int64_t reach_fwd = reach_units(-double(t_lo), rp.scale);

  stex_texton_params& p = out.params;
  p.support = s;
  p.channels = model.channels;
  p.order = model.order;
  p.stride = s + 2 * frame;
  p.seed_lo = stex_lo32(static_cast<stex_i64>(rp.seed));
  p.seed_hi = stex_hi32(static_cast<stex_i64>(rp.seed));
  p.cell_lo = stex_lo32(a);
  p.cell_hi = stex_hi32(a);
  p.reach_back_lo = stex_lo32(reach_back);
  p.reach_back_hi = stex_hi32(reach_back);
  p.reach_fwd_lo = stex_lo32(reach_fwd);
  p.reach_fwd_hi = stex_hi32(reach_fwd);
  p.inv_fix_scale = static_cast<float>(1.0 / (k_fix_one * rp.scale));
  p.inv_sqrt_lambda = static_cast<float>(1.0 / std::sqrt(lambda));
  p.poisson_len = static_cast<stex_u32>(table.size());
  p.t_lo = t_lo;
  p.t_hi = t_hi;
  p.frame = frame;
  for (int c = 0; c < STEX_MAX_CHANNELS; ++c) {
    p.mean[c] = 0.0f;
    p.lambda_sum_alpha[c] = 0.0f;
  }

  // Padded planar alpha: plane c holds alpha(c, y, x) at (y + frame) * stride + (x + frame), zero frame
  // (1 for orders 0 and 1, `order` for 3 and 5).
  // The last plane is followed by stride + 2 zeros, defensively: stex_texton_fetch reads the 2x2 texels of
  // a tap even when some weights are 0, and a read past the last plane would need an order-0 tap with
  // floor(tx + 0.5f) = s for tx < s - 0.5 (float rounding cannot produce it: tx and tx + 0.5 share a binade
  // there) - should a future tap change allow it, the read stays in the buffer and sees the frame's 0.
  const std::size_t stride = std::size_t(s) + 2 * std::size_t(frame);
  const std::size_t plane = stride * stride;
  out.alpha_padded.assign(plane * std::size_t(model.channels) + stride + 2, 0.0f);
  for (int c = 0; c < model.channels; ++c) {
    double sum = 0.0;
    for (int y = 0; y < s; ++y)
      for (int x = 0; x < s; ++x) {
        const float v = model.alpha_at(c, y, x);
        out.alpha_padded[std::size_t(c) * plane + (std::size_t(y) + frame) * stride + std::size_t(x) + frame] = v;
        sum += double(v);
      }
    p.mean[c] = model.mean[c];
    p.lambda_sum_alpha[c] = static_cast<float>(lambda * sum);
  }

  out.poisson_table = std::move(table);
  out.lambda = lambda;
  out.cell_mean = cell_mean;
  out.cell_fix = a;
  out.reach_back = reach_back;
  out.reach_fwd = reach_fwd;
  out.channels = model.channels;
  return out;
}

}  // namespace stex
