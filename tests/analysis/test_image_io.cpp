// Exemplar loading and atomic writing (analysis/image_io.h): round trips of every supported layout and
// sample type (files written with OIIO directly, independent of write_image_atomic), alpha dropping, palette
// expansion, and each bad-input defence of docs/hardening.md: missing and truncated files, a PNG
// header declaring 10^5 x 10^5 pixels, NaN/Inf in an EXR, a Targa named .png, formats off the allow-list.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "analysis/image_io.h"
#include "analysis/texton.h"
#include "core/error.h"

namespace fs = std::filesystem;

namespace {

std::string tmp_dir() {
  static const std::string dir = [] {
    std::string d = std::string(STEX_TEST_TMP_DIR) + "/image_io";
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

// Value of channel c at (x, y) exactly representable in `type` (uint8 k/255, uint16 k/65535, half k/1024);
// float gets values outside [0,1] too.
float pattern(int x, int y, int c, OIIO::TypeDesc type) {
  const int k = (x * 7 + y * 13 + c * 29) % 256;
  if (type == OIIO::TypeDesc::UINT8) return float(k) / 255.0f;
  if (type == OIIO::TypeDesc::UINT16) return float(k * 257 + c) / 65535.0f;
  if (type == OIIO::TypeDesc::HALF) return float(k) / 1024.0f;
  return float(k) / 64.0f - 1.5f;
}

void write_oiio(const std::string& path, int w, int h, int ch, OIIO::TypeDesc type,
                const std::vector<float>* values = nullptr) {
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out) << path;
  OIIO::ImageSpec spec(w, h, ch, type);
  if (ch == 2 || ch == 4) spec.alpha_channel = ch - 1;
  // Store the colour values as given (no premultiplication by alpha), as the loader reads them.
  spec.attribute("oiio:UnassociatedAlpha", 1);
  ASSERT_TRUE(out->open(path, spec)) << out->geterror();
  std::vector<float> data;
  if (values) {
    data = *values;
  } else {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < ch; ++c) data.push_back(pattern(x, y, c, type));
  }
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, data.data())) << out->geterror();
  ASSERT_TRUE(out->close());
}

std::pair<stex::ErrorKind, std::string> load_error(const std::string& path, const stex::LoadOptions& o = {}) {
  try {
    stex::load_exemplar(path, o);
  } catch (const stex::Error& e) {
    return {e.kind(), e.what()};
  }
  return {stex::ErrorKind::Internal, "no error"};
}

void truncate_file(const std::string& path, double fraction) {
  auto size = fs::file_size(path);
  fs::resize_file(path, std::uintmax_t(double(size) * fraction));
}

// --- Hand-made PNGs (a CRC-32 and zlib "stored" blocks; no compression library needed) ---
std::uint32_t crc32(const std::uint8_t* p, std::size_t n, std::uint32_t crc = 0) {
  crc = ~crc;
  for (std::size_t i = 0; i < n; ++i) {
    crc ^= p[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}
void put_be32(std::vector<std::uint8_t>& v, std::uint32_t x) {
  for (int i = 3; i >= 0; --i) v.push_back(std::uint8_t(x >> (8 * i)));
}
void png_chunk(std::vector<std::uint8_t>& png, const char* type, const std::vector<std::uint8_t>& data) {
  put_be32(png, std::uint32_t(data.size()));
  std::vector<std::uint8_t> body(type, type + 4);
  body.insert(body.end(), data.begin(), data.end());
  png.insert(png.end(), body.begin(), body.end());
  put_be32(png, crc32(body.data(), body.size()));
}
std::vector<std::uint8_t> png_header(std::uint32_t w, std::uint32_t h, std::uint8_t depth,
                                     std::uint8_t colour) {
  std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<std::uint8_t> ihdr;
  put_be32(ihdr, w);
  put_be32(ihdr, h);
  ihdr.insert(ihdr.end(), {depth, colour, 0, 0, 0});
  png_chunk(png, "IHDR", ihdr);
  return png;
}
std::vector<std::uint8_t> zlib_stored(const std::vector<std::uint8_t>& raw) {
  std::vector<std::uint8_t> z = {0x78, 0x01, 0x01};  // zlib header; one final stored block (raw < 65536)
  const std::uint16_t len = std::uint16_t(raw.size());
  z.insert(z.end(), {std::uint8_t(len), std::uint8_t(len >> 8), std::uint8_t(~len), std::uint8_t(~len >> 8)});
  z.insert(z.end(), raw.begin(), raw.end());
  std::uint32_t a = 1, b = 0;  // Adler-32
  for (auto c : raw) {
    a = (a + c) % 65521;
    b = (b + a) % 65521;
  }
  put_be32(z, (b << 16) | a);
  return z;
}
void write_bytes(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), bytes.size());
}

TEST(ImageIo, RoundTripsEveryLayoutAndSampleType) {
  struct Case {
    const char* ext;
    OIIO::TypeDesc type;
  };
  const Case cases[] = {{"png", OIIO::TypeDesc::UINT8}, {"png", OIIO::TypeDesc::UINT16},
                        {"tif", OIIO::TypeDesc::UINT8}, {"tif", OIIO::TypeDesc::UINT16},
                        {"tif", OIIO::TypeDesc::FLOAT}, {"exr", OIIO::TypeDesc::HALF},
                        {"exr", OIIO::TypeDesc::FLOAT}};
  const int w = 17, h = 11;
  for (const Case& cs : cases) {
    for (int ch = 1; ch <= 4; ++ch) {
      const std::string path = tmp_dir() + "/rt_" + std::to_string(ch) + "_" + cs.type.c_str() + "." + cs.ext;
      write_oiio(path, w, h, ch, cs.type);
      std::vector<std::string> warnings;
      stex::Image img = stex::load_exemplar(path, {}, &warnings);
      const bool has_alpha = ch == 2 || ch == 4;
      ASSERT_EQ(img.width, w);
      ASSERT_EQ(img.height, h);
      ASSERT_EQ(img.channels, has_alpha ? ch - 1 : ch) << path;
      EXPECT_EQ(warnings.size(), has_alpha ? 1u : 0u) << path;
      if (has_alpha) {
        EXPECT_NE(warnings[0].find("alpha"), std::string::npos);
      }
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
          for (int c = 0; c < img.channels; ++c)
            // The stored values are exactly representable; OIIO's integer -> float conversion is k / max,
            // which float division reproduces to 1 ulp.
            ASSERT_NEAR(img.at(x, y, c), pattern(x, y, c, cs.type), 1e-7f) << path << " " << x << "," << y;
    }
  }
}

TEST(ImageIo, JpegAndPaletteAreDecoded) {
  const std::string jpg = tmp_dir() + "/grey.jpg";
  std::vector<float> flat(32 * 32 * 3, 0.5f);
  write_oiio(jpg, 32, 32, 3, OIIO::TypeDesc::UINT8, &flat);
  stex::Image j = stex::load_exemplar(jpg);
  EXPECT_EQ(j.channels, 3);
  EXPECT_NEAR(j.at(5, 5, 1), 0.5f, 2.0f / 255);  // a flat image survives JPEG up to rounding

  // An 8-bit palette PNG (colour type 3), 2x2, three palette entries: OIIO expands it to RGB.
  std::vector<std::uint8_t> png = png_header(2, 2, 8, 3);
  png_chunk(png, "PLTE", {255, 0, 0, 0, 255, 0, 0, 0, 255});
  png_chunk(png, "IDAT", zlib_stored({0, 0, 1, 0, 2, 0}));  // rows: filter 0, indices
  png_chunk(png, "IEND", {});
  const std::string pal = tmp_dir() + "/palette.png";
  write_bytes(pal, png);
  stex::Image p = stex::load_exemplar(pal);
  ASSERT_EQ(p.channels, 3);
  EXPECT_EQ(p.at(0, 0, 0), 1.0f);
  EXPECT_EQ(p.at(1, 0, 1), 1.0f);
  EXPECT_EQ(p.at(0, 1, 2), 1.0f);
  EXPECT_EQ(p.at(1, 1, 0), 1.0f);
}

TEST(ImageIo, MissingFileIsAnInputError) {
  auto [kind, msg] = load_error(tmp_dir() + "/does_not_exist.png");
  EXPECT_EQ(kind, stex::ErrorKind::Input);
  EXPECT_NE(msg.find("does_not_exist.png"), std::string::npos) << msg;
  EXPECT_NE(msg.find("No such file"), std::string::npos) << msg;
}

TEST(ImageIo, TruncatedFilesAreInputErrors) {
  // Noise content so that the compressed streams are long; OIIO 2.4.7 returned success on a TIFF
  // cut at 50 % and a JPEG cut at 60 %.
  const int w = 96, h = 96;
  std::vector<float> noise;
  auto g = stex::texton_initial_noise(w, h, 3, 5);
  for (int i = 0; i < w * h; ++i)
    for (int c = 0; c < 3; ++c) noise.push_back(float(std::fmod(std::abs(g[c * w * h + i]), 1.0)));
  for (const char* ext : {"png", "jpg", "tif"}) {
    for (double fraction : {0.5, 0.6, 0.9}) {
      const std::string path = tmp_dir() + "/trunc_" + std::to_string(int(fraction * 100)) + "." + ext;
      write_oiio(path, w, h, 3, OIIO::TypeDesc::UINT8, &noise);
      truncate_file(path, fraction);
      auto [kind, msg] = load_error(path);
      EXPECT_EQ(kind, stex::ErrorKind::Input) << path << ": " << msg;
      EXPECT_NE(msg.find(path), std::string::npos) << msg;
    }
  }
}

// A PNG's chunk layout is checked before libpng reads it (analysis/image_io.cpp, check_png_layout: OIIO's
// PNG reader leaks and longjmps over C++ frames on a short read): a cut anywhere - inside the signature's
// chunk headers, inside IHDR, inside IDAT, just before IEND - is an Input error naming the file, and a whole
// file with bytes after IEND still loads.
TEST(ImageIo, PngChunkLayoutIsCheckedBeforeDecoding) {
  std::vector<std::uint8_t> raw;
  for (int y = 0; y < 4; ++y) {
    raw.push_back(0);  // filter: none
    for (int x = 0; x < 4; ++x) raw.push_back(std::uint8_t(40 * x + 10 * y));
  }
  std::vector<std::uint8_t> png = png_header(4, 4, 8, 0);
  png_chunk(png, "IDAT", zlib_stored(raw));
  png_chunk(png, "IEND", {});
  const std::string dir = tmp_dir();
  const std::string whole = dir + "/layout_whole.png";
  write_bytes(whole, png);
  EXPECT_EQ(stex::load_exemplar(whole).width, 4);
  std::vector<std::uint8_t> trailing = png;
  trailing.insert(trailing.end(), {1, 2, 3});
  write_bytes(dir + "/layout_trailing.png", trailing);
  EXPECT_EQ(stex::load_exemplar(dir + "/layout_trailing.png").height, 4);
  const std::size_t iend = png.size() - 12;
  for (std::size_t cut : {std::size_t(12), std::size_t(20), std::size_t(33 + 10), iend, png.size() - 1}) {
    const std::string path = dir + "/layout_cut_" + std::to_string(cut) + ".png";
    write_bytes(path, std::vector<std::uint8_t>(png.begin(), png.begin() + std::ptrdiff_t(cut)));
    auto [kind, msg] = load_error(path);
    EXPECT_EQ(kind, stex::ErrorKind::Input) << cut << ": " << msg;
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("truncated or corrupt PNG"), std::string::npos) << cut << ": " << msg;
  }
  std::vector<std::uint8_t> huge = png;
  huge[33] = 0xff;  // IDAT's length: 4 GiB - 1 bytes declared
  write_bytes(dir + "/layout_huge_chunk.png", huge);
  auto [kind, msg] = load_error(dir + "/layout_huge_chunk.png");
  EXPECT_EQ(kind, stex::ErrorKind::Input) << msg;
  EXPECT_NE(msg.find("chunk 'IDAT' at byte 33"), std::string::npos) << msg;
}

TEST(ImageIo, HugeDeclaredSizeIsRejectedBeforeAllocating) {
  // A valid signature and IHDR declaring 100000 x 100000 (10^10 pixels, 40 GB as float), one tiny IDAT and
  // IEND: 70 bytes that OIIO opens without complaint (2.4.7: only its TIFF reader enforces size limits).
  std::vector<std::uint8_t> png = png_header(100000, 100000, 8, 0);
  png_chunk(png, "IDAT", zlib_stored({0, 0}));
  png_chunk(png, "IEND", {});
  const std::string path = tmp_dir() + "/huge.png";
  write_bytes(path, png);
  auto [kind, msg] = load_error(path);
  EXPECT_EQ(kind, stex::ErrorKind::Limit) << msg;
  EXPECT_NE(msg.find("100000x100000"), std::string::npos) << msg;
  EXPECT_NE(msg.find("pixel budget"), std::string::npos) << msg;
  // The budget is a parameter: a 17x11 image exceeds a 100-pixel budget.
  const std::string small = tmp_dir() + "/small_budget.png";
  write_oiio(small, 17, 11, 1, OIIO::TypeDesc::UINT8);
  stex::LoadOptions o;
  o.pixel_budget = 100;
  EXPECT_EQ(load_error(small, o).first, stex::ErrorKind::Limit);
}

TEST(ImageIo, NonFinitePixelsAreRejected) {
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    std::vector<float> v(8 * 8, 0.25f);
    v[3 * 8 + 5] = bad;
    const std::string path = tmp_dir() + (std::isnan(bad) ? "/nan.exr" : "/inf.exr");
    write_oiio(path, 8, 8, 1, OIIO::TypeDesc::FLOAT, &v);
    auto [kind, msg] = load_error(path);
    EXPECT_EQ(kind, stex::ErrorKind::Input);
    EXPECT_NE(msg.find(std::isnan(bad) ? "NaN" : "Inf"), std::string::npos) << msg;
    EXPECT_NE(msg.find("(5, 3)"), std::string::npos) << msg;
  }
}

TEST(ImageIo, ContentDecidesTheFormat) {
  // A Targa named .png: targa is on the allow-list, so it loads as what it is, with a warning (documented in
  // image_io.h). A format off the list (SGI) is rejected by name.
  const std::string tga = tmp_dir() + "/real.tga", fake = tmp_dir() + "/fake.png";
  write_oiio(tga, 9, 7, 3, OIIO::TypeDesc::UINT8);
  fs::copy_file(tga, fake, fs::copy_options::overwrite_existing);
  std::vector<std::string> warnings;
  stex::Image img = stex::load_exemplar(fake, {}, &warnings);
  EXPECT_EQ(img.width, 9);
  EXPECT_EQ(img.at(2, 3, 1), pattern(2, 3, 1, OIIO::TypeDesc::UINT8));
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("targa"), std::string::npos) << warnings[0];

  const std::string sgi = tmp_dir() + "/image.sgi";
  write_oiio(sgi, 9, 7, 3, OIIO::TypeDesc::UINT8);
  auto [kind, msg] = load_error(sgi);
  EXPECT_EQ(kind, stex::ErrorKind::Input);
  EXPECT_NE(msg.find("'sgi'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("not accepted"), std::string::npos) << msg;

  // Not an image at all.
  const std::string text = tmp_dir() + "/text.png";
  { std::ofstream(text) << "hello, I am not a PNG"; }
  EXPECT_EQ(load_error(text).first, stex::ErrorKind::Input);
}

TEST(ImageIo, OnePixelImageLoadsButIsSmallerThanAnySupport) {
  const std::string path = tmp_dir() + "/one.png";
  write_oiio(path, 1, 1, 1, OIIO::TypeDesc::UINT8);
  stex::Image img = stex::load_exemplar(path);
  EXPECT_EQ(img.width * img.height, 1);
  try {
    stex::analyse_texton(img, stex::TextonParams{});
    FAIL() << "expected an error";
  } catch (const stex::Error& e) {
    EXPECT_EQ(e.kind(), stex::ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("1x1, smaller than the texton support 64x64"), std::string::npos)
        << e.what();
  }
}

TEST(ImageIo, SrgbTransferFunctions) {
  // IEC 61966-2-1 reference points: 0.5 encoded = 0.214041 linear; the linear segment below 0.04045.
  EXPECT_NEAR(stex::srgb_to_linear(0.5f), 0.2140411f, 1e-6f);
  EXPECT_NEAR(stex::srgb_to_linear(0.02f), 0.02f / 12.92f, 1e-9f);
  EXPECT_EQ(stex::srgb_to_linear(0.0f), 0.0f);
  EXPECT_NEAR(stex::srgb_to_linear(1.0f), 1.0f, 1e-6f);
  EXPECT_EQ(stex::srgb_to_linear(-0.5f), -stex::srgb_to_linear(0.5f));
  float worst = 0.0f;
  for (int i = 0; i <= 1000; ++i) {
    float v = i / 1000.0f;
    worst = std::max(worst, std::abs(stex::linear_to_srgb(stex::srgb_to_linear(v)) - v));
  }
  EXPECT_LT(worst, 2e-6f);  // float pow round trip: a few ulp of values <= 1
}

TEST(ImageIo, LinearOptionDecodesEncodedFilesOnly) {
  const std::string png = tmp_dir() + "/lin.png";
  write_oiio(png, 8, 8, 1, OIIO::TypeDesc::UINT8);
  stex::LoadOptions o;
  o.linear = true;
  stex::Image img = stex::load_exemplar(png, o);
  EXPECT_NEAR(img.at(3, 2, 0), stex::srgb_to_linear(pattern(3, 2, 0, OIIO::TypeDesc::UINT8)), 1e-7f);
  const std::string exr = tmp_dir() + "/lin.exr";
  write_oiio(exr, 8, 8, 1, OIIO::TypeDesc::FLOAT);
  std::vector<std::string> warnings;
  stex::Image e = stex::load_exemplar(exr, o, &warnings);
  EXPECT_EQ(e.at(3, 2, 0), pattern(3, 2, 0, OIIO::TypeDesc::FLOAT));
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("linear"), std::string::npos);
}

bool has_temp_files(const std::string& dir) {
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().filename().string().find(".stex-tmp-") != std::string::npos) return true;
  return false;
}

TEST(ImageIo, AtomicWriteClampsAndRoundTrips) {
  const std::string dir = tmp_dir() + "/write";
  fs::create_directories(dir);
  stex::Image img;
  img.width = 4;
  img.height = 3;
  img.channels = 3;
  // Exact binary fractions: i < 8 below 0 (8 values), i > 24 above 1 (11 values).
  for (int i = 0; i < 36; ++i) img.pixels.push_back(float(i - 8) / 16.0f);
  const std::size_t expect_clamped = 8 + 11;
  EXPECT_EQ(stex::write_image_atomic(dir + "/a.png", img), expect_clamped);
  EXPECT_EQ(stex::write_image_atomic(dir + "/a.exr", img), 0u);
  stex::Image e = stex::load_exemplar(dir + "/a.exr");
  EXPECT_EQ(e.pixels, img.pixels);  // float EXR is exact
  stex::Image p = stex::load_exemplar(dir + "/a.png");
  for (std::size_t i = 0; i < p.pixels.size(); ++i)
    EXPECT_NEAR(p.pixels[i], std::min(1.0f, std::max(0.0f, img.pixels[i])), 0.5f / 255 + 1e-7f);
  stex::WriteOptions w16;
  w16.bits = 16;
  w16.metadata.push_back({"Software", "stex test"});
  stex::write_image_atomic(dir + "/b.png", img, w16);
  auto in = OIIO::ImageInput::open(dir + "/b.png");
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().format, OIIO::TypeDesc::UINT16);
  EXPECT_EQ(in->spec().get_string_attribute("Software"), "stex test");
  in.reset();
  stex::WriteOptions srgb;
  srgb.encode_srgb = true;
  stex::write_image_atomic(dir + "/c.exr", img, srgb);
  EXPECT_NEAR(stex::load_exemplar(dir + "/c.exr").pixels[20], stex::linear_to_srgb(img.pixels[20]), 1e-7f);
  EXPECT_FALSE(has_temp_files(dir));
}

TEST(ImageIo, AtomicWriteFailuresLeaveNothing) {
  const std::string dir = tmp_dir() + "/write_fail";
  fs::create_directories(dir);
  stex::Image img;
  img.width = img.height = 2;
  img.channels = 1;
  img.pixels = {0, 0.5f, 1, 0.25f};
  auto kind_of = [&](const std::string& path, stex::WriteOptions o = {}) {
    try {
      stex::write_image_atomic(path, img, o);
    } catch (const stex::Error& e) {
      return e.kind();
    }
    return stex::ErrorKind::Internal;
  };
  EXPECT_EQ(kind_of(dir + "/no_such_dir/x.png"), stex::ErrorKind::Output);
  EXPECT_EQ(kind_of(dir + "/x.unknownext"), stex::ErrorKind::Output);
  stex::WriteOptions bad_bits;
  bad_bits.bits = 12;
  EXPECT_EQ(kind_of(dir + "/x.png", bad_bits), stex::ErrorKind::Output);
  stex::Image malformed = img;
  malformed.pixels.pop_back();
  EXPECT_THROW(stex::write_image_atomic(dir + "/m.png", malformed), stex::Error);
  EXPECT_TRUE(fs::is_empty(dir));  // no output, no temp file
}

}  // namespace
