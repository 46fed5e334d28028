// Model file (analysis/model_file.h, docs/model-format.md): bit-exact round trip, and every validation
// step failing with Error(Input) and the message of its check: truncation at many offsets, flipped bytes,
// foreign and newer-version files, absurd sizes in the header and in the metadata (rejected before
// allocating), inconsistent or non-finite fields (re-checksummed so that the field check itself is reached).
#include <algorithm>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "model/codecs.h"
#include "analysis/texton.h"
#include "core/error.h"
#include "core/sha256.h"

namespace fs = std::filesystem;

namespace {

using Bytes = std::vector<std::uint8_t>;

std::string tmp_dir() {
  static const std::string dir = [] {
    std::string d = std::string(STEX_TEST_TMP_DIR) + "/model_file";
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

stex::TextonModel sample_model(int channels = 3, int support = 5) {
  stex::TextonModel m;
  m.channels = channels;
  m.support = support;
  m.order = 1;
  for (int i = 0; i < channels * support * support; ++i)
    m.alpha.push_back(std::sin(0.7f * i) * 1e-3f + 1e-9f * i);
  m.mean = {0.1f, 0.2f, 1.0f / 3.0f, 0.0f};
  m.mean[channels - 1] = 0.123456789f;
  m.linear = true;
  m.exemplar_name = "gravel é.png";
  m.exemplar_hash = std::string(64, 'a');
  m.exemplar_width = 512;
  m.exemplar_height = 384;
  m.iterations = 50;
  m.analysis_seed = 0xfedcba9876543210ull;  // above 2^63: the full unsigned range survives
  m.rme = 0.47540503732319500123;
  m.variance_kept = 1.0 / 3.0;
  m.stex_version = "0.1.0";
  return m;
}

std::pair<stex::ErrorKind, std::string> decode_error(const Bytes& b) {
  try {
    stex::decode_model(b.data(), b.size(), "test.stex");
  } catch (const stex::Error& e) {
    return {e.kind(), e.what()};
  }
  return {stex::ErrorKind::Internal, "no error"};
}

std::uint64_t get_u64(const Bytes& b, std::size_t off) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= std::uint64_t(b[off + i]) << (8 * i);
  return v;
}
void set_u32(Bytes& b, std::size_t off, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[off + i] = std::uint8_t(v >> (8 * i));
}
void set_u64(Bytes& b, std::size_t off, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) b[off + i] = std::uint8_t(v >> (8 * i));
}

// Rewrites the metadata with `edit` applied, fixes the sizes and the checksum: the file is then
// well-formed except for what `edit` did, so the metadata validation is what must catch it.
template <class Edit>
Bytes with_metadata(const Bytes& good, Edit edit) {
  const std::uint64_t m = get_u64(good, 32), p = get_u64(good, 40);
  nlohmann::json meta = nlohmann::json::parse(good.begin() + 48, good.begin() + 48 + m);
  edit(meta);
  const std::string text = meta.dump();
  // One allocation of the final size, then plain copies: GCC 12 at -O3 reports a false -Warray-bounds on
  // growing a 48-byte vector by insert.
  Bytes out(48 + text.size() + p);
  std::copy(good.begin(), good.begin() + 48, out.begin());
  set_u64(out, 32, text.size());
  std::copy(text.begin(), text.end(), out.begin() + 48);
  std::copy(good.begin() + 48 + m, good.begin() + 48 + m + p, out.begin() + 48 + text.size());
  auto d = stex::sha256(out.data(), out.size());
  out.insert(out.end(), d.begin(), d.end());
  return out;
}

// Re-checksums a file whose body was edited in place.
void rechecksum(Bytes& b) {
  auto d = stex::sha256(b.data(), b.size() - 32);
  std::memcpy(b.data() + b.size() - 32, d.data(), 32);
}

void expect_input_error(const Bytes& b, const std::string& needle) {
  auto [kind, msg] = decode_error(b);
  EXPECT_EQ(kind, stex::ErrorKind::Input) << msg;
  EXPECT_NE(msg.find(needle), std::string::npos) << "message: " << msg << "\nexpected to contain: " << needle;
}

TEST(ModelFile, RoundTripIsBitExact) {
  for (int ch : {1, 3, 4}) {
    stex::TextonModel m = sample_model(ch, 7);
    m.order = ch == 3 ? 3 : ch == 4 ? 5 : 1;  // higher-order textons (S1 §10) round-trip too
    const std::string path = tmp_dir() + "/rt" + std::to_string(ch) + ".stex";
    stex::save_model(m, path);
    const stex::TextonModel r = stex::load_model(path);
    ASSERT_EQ(r.alpha.size(), m.alpha.size());
    EXPECT_EQ(std::memcmp(r.alpha.data(), m.alpha.data(), m.alpha.size() * 4), 0);
    EXPECT_EQ(r.channels, m.channels);
    EXPECT_EQ(r.support, m.support);
    EXPECT_EQ(r.order, m.order);
    for (int c = 0; c < ch; ++c) EXPECT_EQ(r.mean[c], m.mean[c]);
    EXPECT_EQ(r.linear, m.linear);
    EXPECT_EQ(r.exemplar_name, m.exemplar_name);
    EXPECT_EQ(r.exemplar_hash, m.exemplar_hash);
    EXPECT_EQ(r.exemplar_width, m.exemplar_width);
    EXPECT_EQ(r.exemplar_height, m.exemplar_height);
    EXPECT_EQ(r.iterations, m.iterations);
    EXPECT_EQ(r.analysis_seed, m.analysis_seed);
    EXPECT_EQ(r.rme, m.rme);  // doubles round-trip through JSON exactly
    EXPECT_EQ(r.variance_kept, m.variance_kept);
    EXPECT_EQ(r.stex_version, m.stex_version);
    // Re-encoding gives the same bytes.
    std::ifstream f(path, std::ios::binary);
    Bytes on_disk((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    EXPECT_EQ(stex::encode_model(r), on_disk);
  }
}

TEST(ModelFile, InvalidUtf8FileNameIsReplacedNotFatal) {
  stex::TextonModel m = sample_model();
  m.exemplar_name = std::string("bad\xff\xfe.png");  // POSIX file names are bytes, not UTF-8
  const Bytes b = stex::encode_model(m);
  const stex::TextonModel r = stex::decode_model(b.data(), b.size());
  EXPECT_EQ(r.exemplar_name, "bad\xEF\xBF\xBD\xEF\xBF\xBD.png");  // each invalid byte -> U+FFFD
  EXPECT_EQ(r.alpha, m.alpha);
}

TEST(ModelFile, AnalysedModelRoundTrips) {
  stex::Image u;
  u.width = u.height = 32;
  u.channels = 1;
  auto g = stex::texton_initial_noise(32, 32, 1, 3);
  for (double v : g) u.pixels.push_back(float(0.5 + 0.1 * v));
  stex::TextonParams p;
  p.support = 8;
  stex::TextonModel m = stex::analyse_texton(u, p);
  const std::string path = tmp_dir() + "/analysed.stex";
  stex::save_model(m, path);
  EXPECT_EQ(stex::load_model(path).alpha, m.alpha);
}

TEST(ModelFile, TruncatedAnywhereIsRejected) {
  const Bytes good = stex::encode_model(sample_model());
  const std::size_t m = get_u64(good, 32);
  for (std::size_t cut :
       {std::size_t(0), std::size_t(4), std::size_t(8), std::size_t(20), std::size_t(47), std::size_t(48),
        std::size_t(48 + m / 2), std::size_t(48 + m), good.size() - 33, good.size() - 1}) {
    Bytes b(good.begin(), good.begin() + cut);
    auto [kind, msg] = decode_error(b);
    EXPECT_EQ(kind, stex::ErrorKind::Input) << "cut " << cut;
    const bool expected = cut < 8 ? msg.find("not a stex model file") != std::string::npos
                                  : msg.find("truncated") != std::string::npos;
    EXPECT_TRUE(expected) << "cut " << cut << ": " << msg;
  }
  // And through load_model on a real file: the size check happens before the rest is read.
  const std::string path = tmp_dir() + "/truncated.stex";
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(good.data()), 100);
  try {
    stex::load_model(path);
    FAIL();
  } catch (const stex::Error& e) {
    EXPECT_EQ(e.kind(), stex::ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  Bytes trailing = good;
  trailing.push_back(0);
  expect_input_error(trailing, "trailing bytes");
}

TEST(ModelFile, FlippedBytesFailTheChecksum) {
  const Bytes good = stex::encode_model(sample_model());
  const std::size_t m = get_u64(good, 32);
  // Metadata, payload, and the checksum itself (header bytes are caught by their own checks below).
  for (std::size_t off :
       {std::size_t(60), std::size_t(48 + m - 2), std::size_t(48 + m), good.size() - 40, good.size() - 1}) {
    Bytes b = good;
    b[off] ^= 0x10;
    expect_input_error(b, "checksum mismatch");
  }
}

TEST(ModelFile, ForeignNewerAndCorruptHeaders) {
  const Bytes good = stex::encode_model(sample_model());
  Bytes b = good;
  b[0] = 'X';
  expect_input_error(b, "not a stex model file");
  expect_input_error(Bytes{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13},
                     "not a stex model file");
  b = good;
  set_u32(b, 8, 2);
  expect_input_error(b, "format version 2 is newer than this stex supports (1)");
  b = good;
  set_u32(b, 8, 0);
  expect_input_error(b, "format version 0");
  b = good;
  set_u32(b, 12, 0x04030201u);
  expect_input_error(b, "endianness");
  b = good;
  set_u32(b, 16, 64);
  expect_input_error(b, "header size");
  b = good;
  set_u32(b, 20, 1);
  expect_input_error(b, "flags");
  b = good;
  std::memcpy(b.data() + 24, "LRP!\0\0\0\0", 8);
  expect_input_error(b, "model kind field is not 1..8 characters");
  b = good;
  std::memcpy(b.data() + 24, "lrp\0\0\0\0\0", 8);  // a valid kind, but the metadata says texton
  rechecksum(b);
  expect_input_error(b, "differs from the header's kind 'lrp'");
}

// The container layer every model kind is stored through: any kind round-trips bit for bit; a texton
// reader refuses another kind by name.
TEST(ModelFile, ContainerOfAnotherKindRoundTripsAndIsNotATexton) {
  stex::ModelContainer c;
  c.kind = "cs-spot";
  c.metadata = {{"periods", {{12.5, 0.0}, {0.25, 9.75}}}, {"note", "x"}};
  c.payload = {1.0f, -2.5f, 3.25e-7f, 0.0f};
  const Bytes bytes = stex::encode_container(c);
  const stex::ModelContainer d = stex::decode_container(bytes.data(), bytes.size(), "m");
  EXPECT_EQ(d.kind, "cs-spot");
  EXPECT_EQ(d.payload, c.payload);
  EXPECT_EQ(d.metadata.at("periods"), c.metadata.at("periods"));
  EXPECT_EQ(d.metadata.at("kind"), "cs-spot");
  expect_input_error(bytes, "model kind 'cs-spot' is not a texton model");
  c.kind = "Bad Kind";
  EXPECT_THROW(stex::encode_container(c), stex::Error);
  c.kind = "toolongkind";
  EXPECT_THROW(stex::encode_container(c), stex::Error);
  // A payload that is not a whole number of floats.
  c.kind = "lrp";
  Bytes b = stex::encode_container(c);
  b.erase(b.end() - 32 - 2, b.end() - 32);
  set_u64(b, 40, get_u64(b, 40) - 2);
  rechecksum(b);
  expect_input_error(b, "not a whole number of float32");
}

TEST(ModelFile, AbsurdSizesAreRejectedBeforeAllocating) {
  const Bytes good = stex::encode_model(sample_model());
  Bytes b = good;
  set_u64(b, 40, std::uint64_t(1) << 40);  // a 1 TiB payload
  expect_input_error(b, "exceeds the largest model payload");
  b = good;
  set_u64(b, 32, std::uint64_t(1) << 62);
  expect_input_error(b, "metadata size");
  b = good;
  set_u64(b, 40, get_u64(good, 40) + 4);  // plausible but inconsistent with the file length
  expect_input_error(b, "truncated");
  // Metadata declaring support 2^20 (a 4 TiB alpha): rejected by the range check before any product is
  // formed or anything allocated.
  expect_input_error(with_metadata(good, [](nlohmann::json& j) { j["support"] = 1 << 20; }),
                     "'support' = 1048576 is out of range [1, 4096]");
  expect_input_error(with_metadata(good, [](nlohmann::json& j) { j["channels"] = 0; }), "'channels'");
  expect_input_error(with_metadata(good, [](nlohmann::json& j) { j["channels"] = 1; }), "payload is");
  expect_input_error(with_metadata(good, [](nlohmann::json& j) { j["support"] = -3; }), "'support'");
}

TEST(ModelFile, MetadataFieldsAreValidated) {
  const Bytes good = stex::encode_model(sample_model());
  using J = nlohmann::json;
  expect_input_error(with_metadata(good, [](J& j) { j.erase("order"); }), "'order' is missing");
  expect_input_error(with_metadata(good, [](J& j) { j["order"] = 2; }), "'order'");  // orders: 0, 1, 3, 5
  expect_input_error(with_metadata(good, [](J& j) { j["order"] = 7; }), "'order'");
  expect_input_error(with_metadata(good, [](J& j) { j["order"] = "one"; }), "'order' is not an integer");
  expect_input_error(with_metadata(good, [](J& j) { j["kind"] = "gabor"; }), "'kind'");
  expect_input_error(with_metadata(good, [](J& j) { j["format"] = "other"; }), "'format'");
  expect_input_error(with_metadata(good, [](J& j) { j["mean"] = J::array({0.1, 0.2}); }), "'mean'");
  expect_input_error(with_metadata(good, [](J& j) { j["mean"][0] = nullptr; }), "'mean'");
  expect_input_error(with_metadata(good, [](J& j) { j["linear"] = 1; }), "'linear'");
  expect_input_error(with_metadata(good, [](J& j) { j["alpha"]["type"] = "float16"; }), "'alpha'");
  expect_input_error(with_metadata(good, [](J& j) { j["exemplar"]["sha256"] = "xyz"; }), "sha256");
  expect_input_error(with_metadata(good, [](J& j) { j["exemplar"].erase("width"); }), "'width' is missing");
  expect_input_error(with_metadata(good, [](J& j) { j["analysis"]["seed"] = -1; }), "seed");
  expect_input_error(with_metadata(good, [](J& j) { j["report"]["rme"] = -0.5; }), "'rme'");
  expect_input_error(with_metadata(good, [](J& j) { j.erase("stex_version"); }), "'stex_version' is missing");
  expect_input_error(with_metadata(good, [](J& j) { j = J::array({1, 2}); }), "not a JSON object");
  // Unknown keys are ignored (forward compatibility within a format version).
  Bytes extra = with_metadata(good, [](J& j) { j["future_field"] = {1, 2, 3}; });
  EXPECT_EQ(stex::decode_model(extra.data(), extra.size()).alpha, sample_model().alpha);
  // Not JSON at all.
  Bytes b = good;
  b[48] = '#';
  rechecksum(b);
  expect_input_error(b, "not valid JSON");
}

TEST(ModelFile, NonFinitePayloadIsRejected) {
  Bytes b = stex::encode_model(sample_model());
  const std::size_t payload = 48 + get_u64(b, 32);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(b.data() + payload + 4 * 7, &nan, 4);
  rechecksum(b);
  expect_input_error(b, "payload value 7 is not finite");
}

TEST(ModelFile, SaveValidatesAndIsAtomic) {
  stex::TextonModel bad = sample_model();
  bad.alpha.pop_back();
  const std::string path = tmp_dir() + "/bad.stex";
  EXPECT_THROW(stex::save_model(bad, path), stex::Error);
  EXPECT_FALSE(fs::exists(path));
  try {
    stex::save_model(sample_model(), tmp_dir() + "/no_dir/m.stex");
    FAIL();
  } catch (const stex::Error& e) {
    EXPECT_EQ(e.kind(), stex::ErrorKind::Output);
  }
  try {
    stex::load_model(tmp_dir() + "/missing.stex");
    FAIL();
  } catch (const stex::Error& e) {
    EXPECT_EQ(e.kind(), stex::ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("missing.stex"), std::string::npos);
  }
  for (const auto& entry : fs::directory_iterator(tmp_dir()))
    EXPECT_EQ(entry.path().filename().string().find(".stex-tmp-"), std::string::npos) << entry.path();
}

}  // namespace
