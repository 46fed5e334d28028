// SHA-256 (FIPS 180-4 §6.2), written for stex: hashes exemplar files for model provenance and serves as
// the checksum of model files (docs/model-format.md). Tested against the FIPS 180-2 appendix vectors.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace stex {

class Sha256 {
 public:
  Sha256();
  void update(const void* data, std::size_t size);
  std::array<std::uint8_t, 32> finish();  // the object must not be updated afterwards

 private:
  void compress(const std::uint8_t* block);
  std::array<std::uint32_t, 8> h_;
  std::array<std::uint8_t, 64> buffer_;
  std::size_t buffered_ = 0;
  std::uint64_t total_bytes_ = 0;
};

std::array<std::uint8_t, 32> sha256(const void* data, std::size_t size);
std::string to_hex(const std::uint8_t* bytes, std::size_t size);
std::string sha256_hex(const void* data, std::size_t size);

}  // namespace stex
