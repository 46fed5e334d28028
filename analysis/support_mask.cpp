// Support masks of the SOT (S2 §3, q_S of Algorithm 2; discs as in S2 §4). See support_mask.h.
#include "analysis/support_mask.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>

#include "core/error.h"

namespace stex {
namespace {

// Strict decimal integer (no sign, no trailing garbage, no overflow).
bool parse_int(const std::string& s, long* v) {
  if (s.empty() || s.size() > 9 || s.find_first_not_of("0123456789") != std::string::npos) return false;
  errno = 0;
  char* end = nullptr;
  *v = std::strtol(s.c_str(), &end, 10);
  return errno == 0 && end == s.c_str() + s.size();
}

}  // namespace

std::size_t SupportMask::count() const {
  return std::size_t(std::count_if(in.begin(), in.end(), [](std::uint8_t v) { return v != 0; }));
}

SupportMask square_mask(int s) {
  if (s < 1 || s > k_max_mask_size)
    throw Error(ErrorKind::Usage, "square support must be 1.." + std::to_string(k_max_mask_size) +
                                      " pixels, got " + std::to_string(s));
  SupportMask m;
  m.size = s;
  m.in.assign(std::size_t(s) * s, 1);
  m.centre_x = m.centre_y = s / 2;
  m.description = "square:" + std::to_string(s);
  return m;
}

SupportMask disc_mask(int radius) {
  if (radius < 0 || 2 * radius + 1 > k_max_mask_size)
    throw Error(ErrorKind::Usage, "disc radius must be 0.." + std::to_string((k_max_mask_size - 1) / 2) +
                                      ", got " + std::to_string(radius));
  SupportMask m;
  m.size = 2 * radius + 1;
  m.in.assign(std::size_t(m.size) * m.size, 0);
  const long r2 = long(radius) * radius;
  for (int y = 0; y < m.size; ++y)
    for (int x = 0; x < m.size; ++x) {
      const long dx = x - radius, dy = y - radius;
      m.in[std::size_t(y) * m.size + x] = dx * dx + dy * dy <= r2 ? 1 : 0;
    }
  m.centre_x = m.centre_y = radius;
  m.description = "disc:" + std::to_string(radius);
  return m;
}

SupportMask mask_from_image(const Image& img, const std::string& name) {
  if (img.width <= 0 || img.height <= 0 || img.channels < 1 ||
      img.pixels.size() != std::size_t(img.width) * img.height * img.channels)
    throw Error(ErrorKind::Input, "mask image '" + name + "' is empty or malformed");
  int x0 = img.width, y0 = img.height, x1 = -1, y1 = -1;
  auto on = [&](int x, int y) {
    for (int c = 0; c < img.channels; ++c)
      if (img.at(x, y, c) != 0.0f) return true;
    return false;
  };
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (on(x, y)) {
        x0 = std::min(x0, x);
        y0 = std::min(y0, y);
        x1 = std::max(x1, x);
        y1 = std::max(y1, y);
      }
  if (x1 < 0)
    throw Error(ErrorKind::Input, "mask image '" + name + "' has no non-zero pixel: the support is empty");
  SupportMask m;
  m.size = std::max(x1 - x0 + 1, y1 - y0 + 1);
  if (m.size > k_max_mask_size)
    throw Error(ErrorKind::Input, "mask image '" + name + "': the bounding box of its non-zero pixels is " +
                                      std::to_string(m.size) + " pixels wide, above " +
                                      std::to_string(k_max_mask_size));
  m.in.assign(std::size_t(m.size) * m.size, 0);
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) m.in[std::size_t(y - y0) * m.size + (x - x0)] = on(x, y) ? 1 : 0;
  m.centre_x = (x1 - x0) / 2;
  m.centre_y = (y1 - y0) / 2;
  m.description = "image:" + name;
  return m;
}

namespace {
bool file_exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}
}  // namespace

SupportMask parse_support_mask(const std::string& spec, const LoadOptions& opts) {
  auto numeric = [&](const std::string& prefix, const char* what) {
    long v = 0;
    if (!parse_int(spec.substr(prefix.size()), &v))
      throw Error(ErrorKind::Usage,
                  "--mask '" + spec + "': expected " + prefix + what + " (a non-negative integer)");
    return v;
  };
  if (spec.rfind("square:", 0) == 0) {
    const long s = numeric("square:", "S");
    if (s < 1 || s > k_max_mask_size)
      throw Error(ErrorKind::Usage,
                  "--mask '" + spec + "': the square side must be 1.." + std::to_string(k_max_mask_size));
    return square_mask(int(s));
  }
  if (spec.rfind("disc:", 0) == 0) {
    const long r = numeric("disc:", "R");
    if (2 * r + 1 > k_max_mask_size)
      throw Error(ErrorKind::Usage, "--mask '" + spec + "': the disc radius must be 0.." +
                                        std::to_string((k_max_mask_size - 1) / 2));
    return disc_mask(int(r));
  }
  if (spec.empty())
    throw Error(ErrorKind::Usage, "--mask is empty: expected square:S, disc:R or a mask image path");
  // Not a known shape: a mask image. A word followed by ':' that names no file is a mistyped shape.
  const auto colon = spec.find(':');
  if (colon != std::string::npos && colon > 0 && spec.find('/') == std::string::npos && !file_exists(spec))
    throw Error(ErrorKind::Usage, "--mask '" + spec + "': unknown shape '" + spec.substr(0, colon) +
                                      "' (expected square:S, disc:R or a mask image path)");
  LoadOptions mo = opts;
  mo.what = "mask image";
  const Image img = load_exemplar(spec, mo);
  const auto slash = spec.find_last_of('/');
  return mask_from_image(img, slash == std::string::npos ? spec : spec.substr(slash + 1));
}

}  // namespace stex
