// SHA-256 (core/sha256.h) against the FIPS 180-2 appendix vectors and the standard NIST examples, plus
// streaming in uneven pieces (the padding across block boundaries is where hand-written SHA-256 goes wrong).
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "analysis/image_io.h"
#include "core/error.h"
#include "core/sha256.h"

namespace {

std::string hex_of(const std::string& s) { return stex::sha256_hex(s.data(), s.size()); }

TEST(Sha256, FipsVectors) {
  EXPECT_EQ(hex_of("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(hex_of(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(hex_of("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(hex_of(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256, StreamingInPiecesMatchesOneShot) {
  std::string msg;
  for (int i = 0; i < 1000; ++i) msg.push_back(char(i * 37 + 11));
  const std::string one_shot = hex_of(msg);
  for (std::size_t piece : {1u, 3u, 55u, 56u, 63u, 64u, 65u, 127u}) {
    stex::Sha256 h;
    for (std::size_t i = 0; i < msg.size(); i += piece)
      h.update(msg.data() + i, std::min(piece, msg.size() - i));
    auto d = h.finish();
    EXPECT_EQ(stex::to_hex(d.data(), d.size()), one_shot) << "piece " << piece;
  }
  // Lengths around the 55/56/64-byte padding boundaries differ from each other.
  EXPECT_NE(hex_of(std::string(55, 'x')), hex_of(std::string(56, 'x')));
}

TEST(Sha256, FileHashEqualsBufferHash) {
  const std::string dir = STEX_TEST_TMP_DIR;
  std::system(("mkdir -p '" + dir + "'").c_str());
  const std::string path = dir + "/sha_abc.txt";
  { std::ofstream(path, std::ios::binary) << "abc"; }
  EXPECT_EQ(stex::sha256_file_hex(path), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_THROW(stex::sha256_file_hex(dir + "/no_such_file"), stex::Error);
}

}  // namespace
