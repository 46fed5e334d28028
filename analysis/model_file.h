// The model file (.stex): versioned, self-describing, checksummed storage of a TextonModel. The layout is
// documented in docs/model-format.md: a fixed 48-byte little-endian header (magic "STEXMDL\0", format
// version, endian tag, header size, kind "texton", metadata and payload sizes), a JSON metadata block, the
// float32 little-endian alpha payload, and a SHA-256 of everything before it.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/model.h"

namespace stex {

constexpr std::uint32_t kModelFormatVersion = 1;
constexpr std::uint32_t kModelHeaderSize = 48;
constexpr std::uint64_t kModelMaxMetadataBytes = 1u << 20;  // 1 MiB of JSON
constexpr int kModelMaxSupport = 4096;

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
