// The model file (.stex): versioned, self-describing, checksummed storage of every model kind stex renders.
// The layout is documented in docs/model-format.md: a fixed 48-byte little-endian header (magic "STEXMDL\0",
// format version, endian tag, header size, kind, metadata and payload sizes), a JSON metadata block, a float32
// little-endian payload, and a SHA-256 of everything before it.
//
// Two layers: the container (kind + JSON metadata + float payload, validated structurally: header, sizes,
// checksum, JSON) shared by all kinds, and one codec per kind (to_container / <kind>_from_container) that
// validates the kind's own fields. The texton codec is here; other kinds keep theirs beside their model.
#pragma once
#include <cstdint>
#include <string>
#include <nlohmann/json.hpp>
#include <vector>

#include "runtime/model.h"

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
ModelContainer load_container(const std::string& path);

// Field readers shared by the kinds' codecs: each throws Error(Input) "model '<what>': metadata field '<key>'
// ..." naming the field and what is wrong with it (missing, wrong type, not finite, out of [lo, hi]).
[[noreturn]] void bad_model_field(const std::string& what, const std::string& msg);
double model_number(const nlohmann::json& j, const char* key, const std::string& what);  // finite
long long model_integer(const nlohmann::json& j, const char* key, long long lo, long long hi, const std::string& what);
std::string model_string(const nlohmann::json& j, const char* key, const std::string& what);

// The texton codec. to_container validates first (Error(Usage) for an inconsistent model);
// texton_from_container validates every field (Error(Input)), and refuses another kind by name.
ModelContainer to_container(const TextonModel& model);
TextonModel texton_from_container(const ModelContainer& model, const std::string& what = "model");

// Serialises (validating the model first: Error(Usage) for an inconsistent model).
std::vector<std::uint8_t> encode_model(const TextonModel& model);
// Parses and validates every field; Error(Input) naming the failed check (see docs/model-format.md).
// `what` names the source in messages (a file name).
TextonModel decode_model(const std::uint8_t* data, std::size_t size, const std::string& what = "model");

// Atomic (temp file beside the target + fsync + rename); Error(Output) on failure.
void save_model(const TextonModel& model, const std::string& path);
// Checks the file size against the header before reading the rest: a header declaring absurd sizes is
// rejected without allocating them. Error(Input) on a missing, corrupt, truncated, foreign or
// newer-version file.
TextonModel load_model(const std::string& path);

}  // namespace stex
