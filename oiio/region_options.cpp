// Parsing of a model-as-image name's options. See region_options.h.
#include "oiio/region_options.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <set>

#include "core/error.h"
#include "core/format.h"

namespace stex::oiio {

namespace {

[[noreturn]] void usage(const std::string& message) { throw Error(ErrorKind::Usage, message); }

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// A whole decimal integer (optional sign), else Error(Usage) naming the option.
std::int64_t parse_int(const std::string& key, const std::string& s) {
  if (s.empty()) usage(key + " needs a value");
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(s.c_str(), &end, 10);
  if (end != s.c_str() + s.size() || errno == ERANGE || std::isspace(static_cast<unsigned char>(s[0])))
    usage(key + " must be an integer, got '" + s + "'");
  return v;
}

double parse_real(const std::string& key, const std::string& s) {
  if (s.empty()) usage(key + " needs a value");
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(v) ||
      std::isspace(static_cast<unsigned char>(s[0])))
    usage(key + " must be a finite number, got '" + s + "'");
  return v;
}

bool parse_flag(const std::string& key, const std::string& s) {
  if (s == "1") return true;
  if (s == "0") return false;
  usage(key + " must be 0 or 1, got '" + s + "'");
}

// "AxB" (RES) or "A,B" (ORIGIN): two integers around one separator.
std::pair<std::int64_t, std::int64_t> parse_pair(const std::string& key, const std::string& s, char sep) {
  const auto at = s.find(sep);
  if (at == std::string::npos || s.find(sep, at + 1) != std::string::npos)
    usage(key + " must be two integers as A" + std::string(1, sep) + "B, got '" + s + "'");
  return {parse_int(key, s.substr(0, at)), parse_int(key, s.substr(at + 1))};
}

}  // namespace

std::string region_model_path(const std::string& name) { return name.substr(0, name.find('?')); }

RegionOptions parse_region_options(const std::string& name) {
  RegionOptions o;
  const auto q = name.find('?');
  o.path = name.substr(0, q);
  if (o.path.empty()) usage("no model file before the options in '" + name + "'");
  if (q == std::string::npos) return o;

  std::set<std::string> seen;
  std::string rest = name.substr(q + 1);
  std::size_t pos = 0;
  while (pos <= rest.size()) {
    const auto amp = rest.find('&', pos);
    const std::string item = rest.substr(pos, amp == std::string::npos ? std::string::npos : amp - pos);
    pos = amp == std::string::npos ? rest.size() + 1 : amp + 1;
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string::npos) usage("option '" + item + "' has no value (KEY=VALUE)");
    const std::string key = upper(item.substr(0, eq)), value = item.substr(eq + 1);
    if (!seen.insert(key).second) usage("option " + key + " is given twice");
    if (key == "RES") {
      const auto [w, h] = parse_pair(key, upper(value), 'X');
      if (w < 1 || h < 1 || w > k_max_region_side || h > k_max_region_side)
        usage("RES must be WxH with each side in [1, " + std::to_string(k_max_region_side) + "], got '" + value +
              "'");
      o.width = static_cast<int>(w);
      o.height = static_cast<int>(h);
    } else if (key == "ORIGIN") {
      const auto [x, y] = parse_pair(key, value, ',');
      o.x = x;
      o.y = y;
    } else if (key == "SEED") {
      if (value.empty() || value[0] == '-') usage("SEED must be an unsigned 64-bit integer, got '" + value + "'");
      errno = 0;
      char* end = nullptr;
      const unsigned long long v = std::strtoull(value.c_str(), &end, 10);
      if (end != value.c_str() + value.size() || errno == ERANGE || !std::isdigit(static_cast<unsigned char>(value[0])))
        usage("SEED must be an unsigned 64-bit integer, got '" + value + "'");
      o.params.seed = v;
    } else if (key == "MNI") {
      o.params.mni = parse_real(key, value);
      o.mni_given = true;
      if (o.params.mni <= 0.0 || o.params.mni > k_max_mni)
        usage("MNI must be in (0, " + exact_number(k_max_mni) + "], got '" + value + "'");
    } else if (key == "CELL") {
      o.params.cell_factor = parse_real(key, value);
      o.cell_given = true;
      if (o.params.cell_factor < k_min_cell_factor || o.params.cell_factor > k_max_cell_factor)
        usage("CELL must be in [" + exact_number(k_min_cell_factor) + ", " + exact_number(k_max_cell_factor) +
              "], got '" + value + "'");
    } else if (key == "SCALE") {
      o.params.scale = parse_real(key, value);
      if (o.params.scale < k_min_scale || o.params.scale > k_max_scale)
        usage("SCALE must be in [1/1024, 1024], got '" + value + "'");
    } else if (key == "TILE") {
      const std::int64_t t = parse_int(key, value);
      if (t < k_min_tile || t > k_max_tile)
        usage("TILE must be in [" + std::to_string(k_min_tile) + ", " + std::to_string(k_max_tile) + "], got '" +
              value + "'");
      o.tile = static_cast<int>(t);
    } else if (key == "MIP") {
      o.mip = parse_flag(key, value);
    } else if (key == "FILTER") {
      o.filter = parse_flag(key, value);
    } else if (key == "STRATEGY") {
      if (value.empty()) usage("STRATEGY needs a value");
      o.strategy = value;
    } else {
      usage("unknown option '" + item.substr(0, eq) +
            "' (known: RES, ORIGIN, SEED, MNI, CELL, SCALE, TILE, MIP, FILTER, STRATEGY)");
    }
  }
  try {
    validate_region(o.x, o.y, o.width, o.height);
  } catch (const Error& e) {
    usage(std::string("ORIGIN and RES: ") + e.what());
  }
  validate_render_params(o.params);
  return o;
}

}  // namespace stex::oiio
