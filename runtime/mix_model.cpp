// Noise mixing model, maps, setup and reference (S1 §7). See mix_model.h and kernels/shared/mix.h.
#include "runtime/mix_model.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "core/error.h"
#include "runtime/texton_filter.h"

namespace stex {

static_assert(sizeof(stex_mix_params) == 104, "stex_mix_params must match the OpenCL layout (104 bytes)");

namespace {

constexpr double k_fix_one = double(std::int64_t(1) << STEX_FIX_BITS);

std::string num(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

bool parse_double(const std::string& s, double* v) {
  if (s.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const double r = std::strtod(s.c_str(), &end);
  if (errno != 0 || end != s.c_str() + s.size() || !std::isfinite(r)) return false;
  *v = r;
  return true;
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t at = s.find(sep, start);
    out.push_back(s.substr(start, at == std::string::npos ? std::string::npos : at - start));
    if (at == std::string::npos) break;
    start = at + 1;
  }
  return out;
}

// A length in output pixels -> fixed units, rounded to a multiple of `multiple`.
std::int64_t to_fix(double v, std::int64_t multiple = 1) {
  return std::llround(v * k_fix_one / double(multiple)) * multiple;
}

}  // namespace

bool parse_analytic_mix_map(const std::string& spec, MixMap* out) {
  const std::vector<std::string> f = split(spec, ':');
  const std::string& t = f[0];
  if (t != "const" && t != "ramp" && t != "strips") return false;
  auto bad = [&](const std::string& what) {
    throw Error(ErrorKind::Usage, "--mix-map '" + spec + "': " + what);
  };
  MixMap m;
  std::vector<double> v(f.size() - 1);
  for (std::size_t i = 1; i < f.size(); ++i)
    if (!parse_double(f[i], &v[i - 1])) bad("'" + f[i] + "' is not a finite number");
  if (t == "const") {
    if (v.size() != 1) bad("expected const:RHO");
    m.type = MixMap::Type::Const;
    m.rho = v[0];
  } else if (t == "ramp") {
    if (v.size() != 2) bad("expected ramp:X0:X1 (output pixels)");
    m.type = MixMap::Type::Ramp;
    m.x0 = v[0];
    m.x1 = v[1];
  } else {
    if (v.size() != 1 && v.size() != 2) bad("expected strips:PERIOD[:WIDTH] (output pixels)");
    m.type = MixMap::Type::Strips;
    m.period = v[0];
    m.width = v.size() == 2 ? v[1] : 0.0;
  }
  validate_mix_map(m, "--mix-map '" + spec + "': ");
  *out = m;
  return true;
}

std::string mix_map_spec(const MixMap& m) {
  switch (m.type) {
    case MixMap::Type::Const: return "const:" + num(m.rho);
    case MixMap::Type::Ramp: return "ramp:" + num(m.x0) + ":" + num(m.x1);
    case MixMap::Type::Strips: return "strips:" + num(m.period) + ":" + num(m.width);
    case MixMap::Type::Image: break;
  }
  return "image:" + m.name + " (" + std::to_string(m.map_width) + "x" + std::to_string(m.map_height) + ", scale " +
         num(m.scale) + ", origin " + std::to_string(m.origin_x) + "," + std::to_string(m.origin_y) + ", " +
         (m.clamp ? "clamp" : "repeat") + ")";
}

void validate_mix_map(const MixMap& m, const std::string& prefix) {
  auto bad = [&](const std::string& what) { throw Error(ErrorKind::Usage, prefix + what); };
  switch (m.type) {
    case MixMap::Type::Const:
      if (!std::isfinite(m.rho) || m.rho < 0.0 || m.rho > 1.0) bad("rho must be in [0, 1], got " + num(m.rho));
      break;
    case MixMap::Type::Ramp:
      if (!std::isfinite(m.x0) || !std::isfinite(m.x1) || std::fabs(m.x0) > k_mix_max_extent ||
          std::fabs(m.x1) > k_mix_max_extent)
        bad("ramp ends must be finite and within +-2^40 pixels");
      if (std::fabs(m.x1 - m.x0) < 1.0 / 256.0) bad("ramp ends must be at least 1/256 pixel apart");
      break;
    case MixMap::Type::Strips:
      if (!std::isfinite(m.period) || m.period < 1.0 || m.period > k_mix_max_extent)
        bad("strip period must be in [1, 2^40] pixels, got " + num(m.period));
      if (!std::isfinite(m.width) || m.width < 0.0 || m.width > m.period / 2.0)
        bad("strip transition width must be in [0, period/2], got " + num(m.width));
      break;
    case MixMap::Type::Image:
      if (m.map_width < 1 || m.map_height < 1 || m.map_width > k_mix_max_map_side ||
          m.map_height > k_mix_max_map_side)
        bad("map image must be 1.." + std::to_string(k_mix_max_map_side) + " pixels a side, got " +
            std::to_string(m.map_width) + "x" + std::to_string(m.map_height));
      if (m.grey.size() != std::size_t(m.map_width) * std::size_t(m.map_height))
        bad("map has " + std::to_string(m.grey.size()) + " values, expected width x height");
      for (float g : m.grey)
        if (!std::isfinite(g) || g < 0.0f || g > 1.0f) bad("map values must be in [0, 1]");
      if (!std::isfinite(m.scale) || m.scale < k_mix_min_map_scale || m.scale > k_mix_max_map_scale)
        bad("map scale (output pixels per map pixel) must be in [1/256, 65536], got " + num(m.scale));
      if (m.origin_x <= -(std::int64_t(1) << 40) || m.origin_x >= (std::int64_t(1) << 40) ||
          m.origin_y <= -(std::int64_t(1) << 40) || m.origin_y >= (std::int64_t(1) << 40))
        bad("map origin must be within +-2^40 pixels");
      break;
  }
}

TextonModel MixModel::level_model(int k) const {
  TextonModel t;
  t.channels = channels;
  t.support = support;
  t.order = order;
  const std::size_t n = std::size_t(channels) * std::size_t(support) * std::size_t(support);
  t.alpha.assign(alpha.begin() + std::ptrdiff_t(n * std::size_t(k)), alpha.begin() + std::ptrdiff_t(n * std::size_t(k + 1)));
  const double rho = level_rho(k);
  for (int c = 0; c < 4; ++c) t.mean[c] = float((1.0 - rho) * double(mean0[c]) + rho * double(mean1[c]));
  t.linear = linear;
  t.exemplar_width = exemplar_width;
  t.exemplar_height = exemplar_height;
  t.iterations = iterations;
  t.analysis_seed = analysis_seed;
  t.stex_version = stex_version;
  return t;
}

void validate_mix_model(const MixModel& m) {
  auto bad = [](const std::string& what) { throw Error(ErrorKind::Input, "invalid mix model: " + what); };
  if (m.channels < 1 || m.channels > STEX_MAX_CHANNELS) bad("channels must be 1..4, got " + std::to_string(m.channels));
  if (m.support < 1 || m.support > k_max_texton_support)
    bad("support must be 1.." + std::to_string(k_max_texton_support) + ", got " + std::to_string(m.support));
  if (!valid_texton_order(m.order)) bad("order must be 0, 1, 3 or 5, got " + std::to_string(m.order));
  if (m.levels < 2 || m.levels > STEX_MIX_MAX_LEVELS)
    bad("levels must be 2.." + std::to_string(STEX_MIX_MAX_LEVELS) + ", got " + std::to_string(m.levels));
  const std::size_t expected =
      std::size_t(m.levels) * std::size_t(m.channels) * std::size_t(m.support) * std::size_t(m.support);
  if (m.alpha.size() != expected)
    bad("alpha has " + std::to_string(m.alpha.size()) + " values, expected levels*channels*support^2 = " +
        std::to_string(expected));
  for (std::size_t i = 0; i < m.alpha.size(); ++i)
    if (!std::isfinite(m.alpha[i])) bad("alpha[" + std::to_string(i) + "] is not finite");
  for (int c = 0; c < m.channels; ++c)
    if (!std::isfinite(m.mean0[c]) || !std::isfinite(m.mean1[c])) bad("the means must be finite");
  try {
    validate_mix_map(m.map, "");
  } catch (const Error& e) {
    bad(std::string("map: ") + e.what());
  }
}

MixSetup make_mix_setup(const MixModel& model, const RenderParams& rp) {
  validate_mix_model(model);
  MixSetup out;
  // The grid, taps and intensity of a texton model of the same shape (lambda = MNI / r^2 counts both signs).
  out.texton = make_texton_setup(model.level_model(0), rp);
  const std::size_t level_floats = out.texton.alpha_padded.size();
  if (level_floats * std::size_t(model.levels) >= (std::size_t(1) << 31))
    throw Error(ErrorKind::Limit, "mix model: levels x padded texton size exceeds 2^31 floats");
  out.alpha_levels.reserve(level_floats * std::size_t(model.levels));
  for (int k = 0; k < model.levels; ++k) {
    const TextonSetup s = k == 0 ? out.texton : make_texton_setup(model.level_model(k), rp);
    out.alpha_levels.insert(out.alpha_levels.end(), s.alpha_padded.begin(), s.alpha_padded.end());
  }

  stex_mix_params& p = out.mix;
  p = stex_mix_params{};
  p.levels = model.levels;
  p.level_floats = static_cast<stex_i32>(level_floats);
  p.map_wrap = model.map.clamp ? STEX_MIX_WRAP_CLAMP : STEX_MIX_WRAP_REPEAT;
  auto set_a = [&](std::int64_t v) {
    p.a_lo = stex_lo32(v);
    p.a_hi = stex_hi32(v);
  };
  auto set_b = [&](std::int64_t v) {
    p.b_lo = stex_lo32(v);
    p.b_hi = stex_hi32(v);
  };
  auto set_c = [&](std::int64_t v) {
    p.c_lo = stex_lo32(v);
    p.c_hi = stex_hi32(v);
  };
  const MixMap& m = model.map;
  out.map.assign(1, 0.0f);
  switch (m.type) {
    case MixMap::Type::Const:
      p.map_type = STEX_MIX_MAP_CONST;
      p.rho_const = static_cast<float>(m.rho);
      break;
    case MixMap::Type::Ramp: {
      p.map_type = STEX_MIX_MAP_RAMP;
      const std::int64_t a = to_fix(m.x0), b = to_fix(m.x1);
      set_a(a);
      p.inv_len = static_cast<float>(1.0 / double(b - a));
      break;
    }
    case MixMap::Type::Strips: {
      p.map_type = STEX_MIX_MAP_STRIPS;
      set_a(to_fix(m.period, 4));  // a multiple of 4: P/2 and P/4 exact
      const std::int64_t w = to_fix(m.width);
      set_b(w);
      p.inv_len = w > 0 ? static_cast<float>(1.0 / double(w)) : 0.0f;
      break;
    }
    case MixMap::Type::Image: {
      p.map_type = STEX_MIX_MAP_IMAGE;
      const std::int64_t side = to_fix(m.scale, 2);  // even: the half-pixel offset is exact
      set_a(m.origin_x * (std::int64_t(1) << STEX_FIX_BITS));
      set_b(m.origin_y * (std::int64_t(1) << STEX_FIX_BITS));
      set_c(side);
      p.inv_len = static_cast<float>(1.0 / double(side));
      p.map_width = m.map_width;
      p.map_height = m.map_height;
      out.map = m.grey;
      break;
    }
  }
  // The texton's centre relative to its impulse: (s - 1)/2 texton pixels = (s - 1)/2 scale output pixels.
  const std::int64_t centre = std::llround(0.5 * double(model.support - 1) * rp.scale * k_fix_one);
  p.centre_lo = stex_lo32(centre);
  p.centre_hi = stex_hi32(centre);
  for (int c = 0; c < STEX_MAX_CHANNELS; ++c) {
    p.mean0[c] = c < model.channels ? model.mean0[c] : 0.0f;
    p.mean1[c] = c < model.channels ? model.mean1[c] : 0.0f;
  }
  p.shift_lo = p.shift_hi = 0;
  if (texton_prefilters(rp)) {
    // A filtered minified view: each level's texton convolved with the pixel's box (runtime/texton_filter.h),
    // the same impulses, signs and levels. The tables start `shift` whole pixels before the impulse: every
    // displacement gains shift 2^16, so the cell range reaches that much less back and more forward.
    out.alpha_levels.clear();
    for (int k = 0; k < model.levels; ++k) {
      const BoxPrefilter pre = make_box_prefilter(model.level_model(k), rp.scale);
      const TextonSetup t = prefiltered_setup(out.texton, pre, rp.scale);
      if (k == 0) {
        if (t.alpha_padded.size() * std::size_t(model.levels) >= (std::size_t(1) << 31))
          throw Error(ErrorKind::Limit, "mix model: levels x box-prefiltered texton size exceeds 2^31 floats");
        const std::int64_t shift = pre.shift * (std::int64_t(1) << STEX_FIX_BITS);
        TextonSetup s = t;
        s.reach_back = std::max<std::int64_t>(0, t.reach_back - shift);
        s.reach_fwd = t.reach_fwd + shift;
        s.params.reach_back_lo = stex_lo32(s.reach_back);
        s.params.reach_back_hi = stex_hi32(s.reach_back);
        s.params.reach_fwd_lo = stex_lo32(s.reach_fwd);
        s.params.reach_fwd_hi = stex_hi32(s.reach_fwd);
        s.pixel_shift = 0;  // the shift is in the displacement, not the region: the mean term reads the pixel
        out.texton = std::move(s);
        p.level_floats = static_cast<stex_i32>(t.alpha_padded.size());
        p.shift_lo = stex_lo32(shift);
        p.shift_hi = stex_hi32(shift);
        out.alpha_levels.reserve(t.alpha_padded.size() * std::size_t(model.levels));
      }
      out.alpha_levels.insert(out.alpha_levels.end(), t.alpha_padded.begin(), t.alpha_padded.end());
    }
  }
  return out;
}

std::vector<float> MixReference::render(std::int64_t x, std::int64_t y, int width, int height) const {
  validate_region(x, y, width, height);
  const int nc = setup_.texton.channels;
  std::vector<float> out(std::size_t(width) * std::size_t(height) * std::size_t(nc));
  float v[STEX_MAX_CHANNELS];
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      stex_mix_eval(setup_.texton.params, setup_.mix, setup_.alpha_levels.data(), setup_.map.data(),
                    setup_.texton.poisson_table.data(), stex_pixel_fix(x + i), stex_pixel_fix(y + j), v);
      for (int c = 0; c < nc; ++c) out[(std::size_t(j) * std::size_t(width) + std::size_t(i)) * nc + c] = v[c];
    }
  return out;
}

float MixReference::rho_fixed(std::int64_t fx, std::int64_t fy) const {
  return stex_mix_rho(setup_.mix, setup_.map.data(), fx, fy);
}

float MixReference::rho_pixel(std::int64_t px, std::int64_t py) const {
  return rho_fixed(stex_pixel_fix(px), stex_pixel_fix(py));
}

}  // namespace stex
