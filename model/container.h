// The model file (.stex): versioned, self-describing, checksummed storage of every model kind stex renders.
// The layout is documented in docs/model-format.md: a fixed 48-byte little-endian header (magic "STEXMDL\0",
// format version, endian tag, header size, kind, metadata and payload sizes), a JSON metadata block, a float32
// little-endian payload, and a SHA-256 of everything before it.
//
// Two layers: this container (kind + JSON metadata + float payload, validated structurally: header, sizes,
// checksum, JSON) shared by all kinds, and one codec per kind (model/codecs.h) that validates the kind's own
// fields with the shared readers of model/fields.h.
#pragma once
#include <cstdint>
#include <string>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>


namespace stex {

constexpr std::uint32_t kModelFormatVersion = 1;
constexpr std::uint32_t kModelHeaderSize = 48;
constexpr std::uint64_t kModelMaxMetadataBytes = 1u << 20;  // 1 MiB of JSON
constexpr int kModelMaxSupport = 4096;

// A model of any kind as stored: `kind` is 1..8 characters of [a-z0-9-] ("texton", "lrp", "gabor", ...);
// `metadata` is the kind's JSON object (the codec adds "format": "stex-model" and "kind"); `payload` is the
// kind's float data (at most 256 MiB; finite values only).
struct ModelContainer {
  std::string kind;
  nlohmann::json metadata = nlohmann::json::object();
  std::vector<float> payload;
};

bool valid_model_kind(const std::string& kind);

// Serialises a container; Error(Usage) for an invalid kind, non-object metadata or non-finite payload.
std::vector<std::uint8_t> encode_container(const ModelContainer& model);
// Parses and checks the structure (header, sizes before allocation, checksum, JSON object, kind agreement,
// finite payload); Error(Input) naming the failed check. The kind's fields are checked by its codec.
ModelContainer decode_container(const std::uint8_t* data, std::size_t size, const std::string& what = "model");
// Atomic write (temp file + fsync + rename); Error(Output) on failure.
void save_container(const ModelContainer& model, const std::string& path);
// Reads a model file of any kind; the header's sizes are checked against the file length before allocating.
// With `file_sha256`, also the SHA-256 (hex) of the bytes read (= sha256_file_hex of the file, one read).
ModelContainer load_container(const std::string& path, std::string* file_sha256 = nullptr);

}  // namespace stex
