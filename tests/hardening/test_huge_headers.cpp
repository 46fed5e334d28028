// Headers declaring huge images are rejected before any allocation, and readers are checked against the
// allow-list (issue #12; measured on OIIO 2.4.7: a 69-byte PNG declaring 100000x100000 opens fine, OIIO
// picks readers by content). Small valid files are written by OIIO (in a forked child), then their size
// fields are patched to 100000 x 100000 (10^10 pixels: 40 GB as floats per channel). Each load runs in a
// child capped at 1 GiB of address space, so an attempt to allocate the declared size would fail there
// with std::bad_alloc or a crash instead of stex::Error, and the test would report it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "analysis/image_io.h"
#include "core/error.h"
#include "farm/tile_grid.h"
#include "hardening/isolate.h"

namespace fs = std::filesystem;
using stex::test::run_isolated_batch;

namespace {

constexpr std::uint32_t k_huge = 100000;

fs::path tmp_dir(const std::string& name) {
  fs::path d = fs::path(STEX_TEST_TMP_DIR) / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::vector<std::uint8_t> read_bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(f), {});
}

void write_bytes(const fs::path& p, const std::vector<std::uint8_t>& b) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
}

// A small image written through OIIO in a forked child (the parent keeps no OIIO thread pools).
std::vector<std::uint8_t> small_image_bytes(const fs::path& path, int w = 8, int h = 8) {
  auto r = run_isolated_batch({0}, [&](std::uint64_t, const std::function<void(const std::string&)>&) {
    stex::Image img;
    img.width = w;
    img.height = h;
    img.channels = 3;
    img.pixels.assign(std::size_t(w) * h * 3, 0.25f);
    stex::write_image_atomic(path.string(), img);
  });
  EXPECT_TRUE(r.failures.empty()) << (r.failures.empty() ? "" : r.failures.front());
  return read_bytes(path);
}

void put_be32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + i] = std::uint8_t(v >> (24 - 8 * i));
}
void put_le32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + i] = std::uint8_t(v >> (8 * i));
}
void put_le16(std::vector<std::uint8_t>& b, std::size_t at, std::uint16_t v) {
  b[at] = std::uint8_t(v);
  b[at + 1] = std::uint8_t(v >> 8);
}
std::uint32_t get_le32(const std::vector<std::uint8_t>& b, std::size_t at) {
  return std::uint32_t(b[at]) | std::uint32_t(b[at + 1]) << 8 | std::uint32_t(b[at + 2]) << 16 |
         std::uint32_t(b[at + 3]) << 24;
}
std::uint16_t get_le16(const std::vector<std::uint8_t>& b, std::size_t at) {
  return std::uint16_t(b[at] | b[at + 1] << 8);
}

// CRC-32 of PNG chunks (ISO 3309 polynomial, reflected), so that libpng accepts the patched IHDR.
std::uint32_t crc32(const std::uint8_t* p, std::size_t n) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return c ^ 0xFFFFFFFFu;
}

// What a load did, from inside the capped child: "ok WxH", "error <kind> <message>", or a failure.
struct Outcome {
  std::vector<std::string> failures;
  int kind = 0;  // stex::Error kind, 0 if loaded
  std::string message;
};

Outcome load_capped(const fs::path& path, std::vector<std::string>* warnings_out = nullptr) {
  Outcome out;
  const fs::path result = path.string() + ".result";
  fs::remove(result);
  auto r = run_isolated_batch({0}, [&](std::uint64_t, const std::function<void(const std::string&)>& fail) {
    std::ofstream f(result);
    std::vector<std::string> warnings;
    try {
      stex::load_exemplar(path.string(), {}, &warnings);
      f << 0 << "\n";
    } catch (const stex::Error& e) {
      if (!*e.what()) fail("empty error message");
      f << int(e.kind()) << "\n" << e.what() << "\n";
    }
    for (auto& w : warnings) f << "W " << w << "\n";
  });
  out.failures = r.failures;
  std::ifstream f(result);
  f >> out.kind;
  std::string line;
  std::getline(f, line);
  if (out.kind != 0) std::getline(f, out.message);
  while (std::getline(f, line))
    if (warnings_out && line.rfind("W ", 0) == 0) warnings_out->push_back(line.substr(2));
  return out;
}

}  // namespace

TEST(HugeHeaders, PngRejectedBeforeAllocation) {
  const fs::path dir = tmp_dir("huge_png");
  std::vector<std::uint8_t> b = small_image_bytes(dir / "small.png");
  ASSERT_GT(b.size(), 33u);
  ASSERT_EQ(std::memcmp(b.data() + 12, "IHDR", 4), 0);
  put_be32(b, 16, k_huge);
  put_be32(b, 20, k_huge);
  put_be32(b, 29, crc32(b.data() + 12, 17));
  write_bytes(dir / "huge.png", b);
  Outcome o = load_capped(dir / "huge.png");
  EXPECT_TRUE(o.failures.empty()) << o.failures.front();
  EXPECT_EQ(o.kind, int(stex::ErrorKind::Limit));
  EXPECT_NE(o.message.find("100000x100000"), std::string::npos) << o.message;
}

TEST(HugeHeaders, TiffRejectedBeforeAllocation) {
  const fs::path dir = tmp_dir("huge_tif");
  std::vector<std::uint8_t> b = small_image_bytes(dir / "small.tif");
  ASSERT_EQ(b[0], 'I');  // little-endian TIFF as libtiff writes on x86
  const std::uint32_t ifd = get_le32(b, 4);
  const std::uint16_t n = get_le16(b, ifd);
  int patched = 0;
  for (std::uint16_t i = 0; i < n; ++i) {
    const std::size_t e = ifd + 2 + 12u * i;
    const std::uint16_t tag = get_le16(b, e);
    if (tag == 256 || tag == 257) {  // ImageWidth, ImageLength: LONG, one value, inline
      put_le16(b, e + 2, 4);
      put_le32(b, e + 4, 1);
      put_le32(b, e + 8, k_huge);
      ++patched;
    }
  }
  ASSERT_EQ(patched, 2);
  write_bytes(dir / "huge.tif", b);
  Outcome o = load_capped(dir / "huge.tif");
  EXPECT_TRUE(o.failures.empty()) << o.failures.front();
  EXPECT_EQ(o.kind, int(stex::ErrorKind::Limit)) << o.message;
  EXPECT_NE(o.message.find("100000x100000"), std::string::npos) << o.message;
}

TEST(HugeHeaders, ExrRejectedBeforeAllocation) {
  const fs::path dir = tmp_dir("huge_exr");
  std::vector<std::uint8_t> b = small_image_bytes(dir / "small.exr");
  int patched = 0;
  for (const char* name : {"dataWindow", "displayWindow"}) {
    const std::string key = std::string(name) + std::string("\0box2i\0", 7);
    auto it = std::search(b.begin(), b.end(), key.begin(), key.end());
    ASSERT_NE(it, b.end()) << name;
    const std::size_t at = std::size_t(it - b.begin()) + key.size() + 4;  // after the attribute size
    put_le32(b, at + 8, k_huge - 1);                                       // xmax
    put_le32(b, at + 12, k_huge - 1);                                      // ymax
    ++patched;
  }
  ASSERT_EQ(patched, 2);
  // Room for the line offset table of 10^5 scanlines (8 bytes per chunk, at most one line per chunk), so
  // that OpenEXR's open() succeeds and the size check in load_exemplar is what refuses the file.
  b.resize(b.size() + 8 * std::size_t(k_huge) + 8, 0);
  write_bytes(dir / "huge.exr", b);
  Outcome o = load_capped(dir / "huge.exr");
  EXPECT_TRUE(o.failures.empty()) << o.failures.front();
  EXPECT_EQ(o.kind, int(stex::ErrorKind::Limit)) << o.message;
  EXPECT_NE(o.message.find("100000x100000"), std::string::npos) << o.message;
}

// A Targa named .png is allowed content: it loads as Targa, with a warning naming both formats.
TEST(AllowList, AllowedContentUnderAnotherNameLoadsWithWarning) {
  const fs::path dir = tmp_dir("allow_tga");
  write_bytes(dir / "targa.png", small_image_bytes(dir / "real.tga"));
  std::vector<std::string> warnings;
  Outcome o = load_capped(dir / "targa.png", &warnings);
  EXPECT_TRUE(o.failures.empty()) << o.failures.front();
  EXPECT_EQ(o.kind, 0);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("named like png but its content is targa"), std::string::npos) << warnings[0];
}

// SGI, a format OIIO reads but stex does not accept: refused as Input under its own name (by the
// allow-list, naming the format) and under a .png name (OIIO's PNG reader, chosen by the name, refuses it).
TEST(AllowList, FormatOutsideTheListIsRefused) {
  const fs::path dir = tmp_dir("allow_sgi");
  write_bytes(dir / "sgi.png", small_image_bytes(dir / "real.sgi"));
  Outcome o = load_capped(dir / "real.sgi");
  EXPECT_TRUE(o.failures.empty()) << o.failures.front();
  EXPECT_EQ(o.kind, int(stex::ErrorKind::Input));
  EXPECT_NE(o.message.find("in format 'sgi', which is not accepted"), std::string::npos) << o.message;
  o = load_capped(dir / "sgi.png");
  EXPECT_TRUE(o.failures.empty()) << o.failures.front();
  EXPECT_EQ(o.kind, int(stex::ErrorKind::Input)) << o.message;
}

// A tile spec repeating a full-grid range (70 x "0-1048575" over 1024 x 1024 tiles) stays within memory:
// collected as a list, the selection would grow to 70 Mi indices (a 1 GiB vector after doubling) and fail
// under the child's 512 MiB cap; farm/tile_grid.cpp marks a bitmap of the grid instead (found while fuzzing
// parse_tile_spec).
TEST(HugeSpecs, RepeatedRangesDoNotMultiplyMemory) {
  std::string spec;
  for (int i = 0; i < 70; ++i) spec += (i ? "," : "") + std::string("0-1048575");
  stex::test::IsolatedLimits limits;
  limits.address_space = std::uint64_t(512) << 20;
  limits.per_input_seconds = limits.seconds;  // one input: the batch's bound
  auto r = run_isolated_batch({0}, [&](std::uint64_t, const std::function<void(const std::string&)>& fail) {
    const stex::farm::TileGrid grid(1024, 1024, 1);
    const std::vector<std::int64_t> tiles = stex::farm::parse_tile_spec(spec, grid);
    if (tiles.size() != 1048576u || tiles.front() != 0 || tiles.back() != 1048575) fail("wrong selection");
  }, limits);
  for (const auto& f : r.failures) ADD_FAILURE() << f;
  EXPECT_EQ(r.inputs_done, 1);
}
