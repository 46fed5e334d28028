// Damaged exemplar files for the CLI bad-input tests (tests/cli/test_analyze_cli.cpp, test_render_cli.cpp):
// each is written here through OIIO (or patched byte by byte) and paired with the exit code (README "Exit
// codes", core/error.h) and the words of stderr that name the problem.
//  - a JPEG truncated to 60 % and a TIFF truncated to 50 %: OIIO's read_image() returns true on both
//    (docs/hardening.md), only has_error() tells -> exit 3 "truncated or corrupt";
//  - a PNG whose IHDR declares 100000 x 100000 pixels (CRC patched, 69 bytes of data): opens fine in OIIO, must
//    be refused before any allocation -> exit 5 "over the pixel budget";
//  - float EXRs with one NaN and one +Inf pixel -> exit 3 "non-finite value (NaN|Inf) at pixel (5, 7)".
#pragma once
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

namespace stex::test {

struct BadExemplar {
  std::string name;                  // what is wrong, for the test's trace
  std::string path;                  // the damaged file
  int code;                          // documented exit code
  std::vector<std::string> needles;  // each must appear in stderr
};

inline bool write_float_image(const std::string& path, int w, int h, int ch, const std::vector<float>& v,
                              OIIO::TypeDesc format) {
  auto out = OIIO::ImageOutput::create(path);
  if (!out) return false;
  OIIO::ImageSpec spec(w, h, ch, format);
  if (!out->open(path, spec)) return false;
  if (!out->write_image(OIIO::TypeDesc::FLOAT, v.data())) return false;
  return out->close();
}

inline std::vector<float> ramp_pixels(int w, int h, int ch) {
  std::vector<float> v(std::size_t(w) * h * ch);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = float((i * 37) % 251) / 255.0f;
  return v;
}

inline void truncate_to(const std::string& path, double fraction) {
  namespace fs = std::filesystem;
  fs::resize_file(path, std::uintmax_t(double(fs::file_size(path)) * fraction));
}

// CRC-32 of PNG chunks (ISO 3309, reflected), so that libpng accepts the patched IHDR.
inline std::uint32_t png_crc32(const std::uint8_t* p, std::size_t n) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return c ^ 0xFFFFFFFFu;
}

// Writes the damaged files into `dir`; ADD_FAILURE if one cannot be made (then the list is incomplete).
inline std::vector<BadExemplar> make_bad_exemplars(const std::string& dir) {
  std::vector<BadExemplar> out;
  const int w = 64, h = 64;
  const std::vector<float> ramp = ramp_pixels(w, h, 3);

  const std::string jpg = dir + "/trunc.jpg";
  if (!write_float_image(jpg, w, h, 3, ramp, OIIO::TypeDesc::UINT8)) ADD_FAILURE() << "cannot write " << jpg;
  truncate_to(jpg, 0.6);
  out.push_back({"truncated jpeg", jpg, 3, {"trunc.jpg", "truncated or corrupt"}});

  const std::string tif = dir + "/trunc.tif";
  if (!write_float_image(tif, w, h, 3, ramp, OIIO::TypeDesc::UINT8)) ADD_FAILURE() << "cannot write " << tif;
  truncate_to(tif, 0.5);
  out.push_back({"truncated tiff", tif, 3, {"trunc.tif", "truncated or corrupt"}});

  const std::string small = dir + "/small8.png", huge = dir + "/huge.png";
  if (!write_float_image(small, 8, 8, 3, ramp_pixels(8, 8, 3), OIIO::TypeDesc::UINT8))
    ADD_FAILURE() << "cannot write " << small;
  {
    std::ifstream f(small, std::ios::binary);
    std::vector<std::uint8_t> b((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    if (b.size() < 33 || std::memcmp(b.data() + 12, "IHDR", 4) != 0) {
      ADD_FAILURE() << small << " has no IHDR at byte 12";
    } else {
      auto put_be32 = [&](std::size_t at, std::uint32_t v) {
        for (int i = 0; i < 4; ++i) b[at + i] = std::uint8_t(v >> (24 - 8 * i));
      };
      put_be32(16, 100000);
      put_be32(20, 100000);
      put_be32(29, png_crc32(b.data() + 12, 17));
      std::ofstream o(huge, std::ios::binary | std::ios::trunc);
      o.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
    }
    std::filesystem::remove(small);
  }
  out.push_back({"png declaring 10^5 x 10^5", huge, 5, {"huge.png", "100000x100000", "pixel budget"}});

  for (const bool nan : {true, false}) {
    std::vector<float> v = ramp;
    v[(std::size_t(7) * w + 5) * 3 + 1] =
        nan ? std::numeric_limits<float>::quiet_NaN() : std::numeric_limits<float>::infinity();
    const std::string exr = dir + (nan ? "/nan.exr" : "/inf.exr");
    if (!write_float_image(exr, w, h, 3, v, OIIO::TypeDesc::FLOAT)) ADD_FAILURE() << "cannot write " << exr;
    out.push_back({nan ? "NaN pixel in exr" : "Inf pixel in exr", exr, 3,
                   {nan ? "nan.exr" : "inf.exr", nan ? "non-finite value (NaN)" : "non-finite value (Inf)",
                    "pixel (5, 7)"}});
  }
  return out;
}

}  // namespace stex::test
