// Model file encoding, decoding and validation (layout: docs/model-format.md). Every field is checked in a
// fixed order — magic, header, sizes against the file length (before anything is allocated from them),
// checksum, metadata, payload — and each failure is an Error(Input) that names the check.
#include "model/container.h"

#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/sha256.h"
#include "model/fields.h"

namespace stex {
namespace {

using nlohmann::json;

constexpr char kMagic[8] = {'S', 'T', 'E', 'X', 'M', 'D', 'L', '\0'};
constexpr std::uint32_t kEndianTag = 0x01020304u;
constexpr std::size_t kChecksumSize = 32;
constexpr std::uint64_t kMaxPayloadBytes = 4ull * kModelMaxSupport * kModelMaxSupport * sizeof(float);

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(std::uint8_t(v >> (8 * i)));
}
void put_u64(std::vector<std::uint8_t>& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(std::uint8_t(v >> (8 * i)));
}
std::uint32_t get_u32(const std::uint8_t* p) {
  return std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8) | (std::uint32_t(p[2]) << 16) |
         (std::uint32_t(p[3]) << 24);
}
std::uint64_t get_u64(const std::uint8_t* p) {
  return std::uint64_t(get_u32(p)) | (std::uint64_t(get_u32(p + 4)) << 32);
}

struct Header {
  std::string kind;
  std::uint32_t version = 0;
  std::uint64_t metadata_size = 0, payload_size = 0;
  std::uint64_t total_size() const { return kModelHeaderSize + metadata_size + payload_size + kChecksumSize; }
};

[[noreturn]] void bad(const std::string& what, const std::string& msg) {
  throw Error(ErrorKind::Input, "invalid model file '" + what + "': " + msg);
}

// Checks the fixed header (`size` >= available bytes, at least 8). `file_size` is the whole file's length.
Header check_header(const std::uint8_t* p, std::size_t available, std::uint64_t file_size,
                    const std::string& what) {
  if (available < sizeof kMagic || std::memcmp(p, kMagic, sizeof kMagic) != 0) {
    bad(what, "not a stex model file (magic \"STEXMDL\" not found)");
  }
  if (available < kModelHeaderSize) {
    bad(what, "truncated: " + std::to_string(file_size) + " bytes, shorter than the " +
                  std::to_string(kModelHeaderSize) + "-byte header");
  }
  Header h;
  h.version = get_u32(p + 8);
  if (h.version == 0) bad(what, "format version 0 is not valid (corrupt header)");
  if (h.version > kModelFormatVersion) {
    bad(what, "format version " + std::to_string(h.version) + " is newer than this stex supports (" +
                  std::to_string(kModelFormatVersion) + "); upgrade stex to read it");
  }
  if (get_u32(p + 12) != kEndianTag) bad(what, "endianness tag mismatch (byte-swapped or corrupt header)");
  if (get_u32(p + 16) != kModelHeaderSize) {
    bad(what, "header size " + std::to_string(get_u32(p + 16)) + " differs from " +
                  std::to_string(kModelHeaderSize));
  }
  if (get_u32(p + 20) != 0) bad(what, "unknown header flags " + std::to_string(get_u32(p + 20)));
  char kind[9] = {};
  std::memcpy(kind, p + 24, 8);
  std::size_t kind_len = std::strlen(kind);
  for (std::size_t i = kind_len; i < 8; ++i) {
    if (p[24 + i] != 0) bad(what, "model kind field is not NUL-padded (corrupt header)");
  }
  if (!valid_model_kind(kind)) bad(what, "model kind field is not 1..8 characters of [a-z0-9-] (corrupt header)");
  h.kind = kind;
  h.metadata_size = get_u64(p + 32);
  h.payload_size = get_u64(p + 40);
  if (h.metadata_size == 0 || h.metadata_size > kModelMaxMetadataBytes) {
    bad(what, "metadata size " + std::to_string(h.metadata_size) + " bytes is out of range (1.." +
                  std::to_string(kModelMaxMetadataBytes) + ")");
  }
  if (h.payload_size > kMaxPayloadBytes) {
    bad(what, "payload size " + std::to_string(h.payload_size) + " bytes exceeds the largest model payload (" +
                  std::to_string(kMaxPayloadBytes) + " bytes)");
  }
  if (file_size < h.total_size()) {
    bad(what, "truncated: the header announces " + std::to_string(h.total_size()) + " bytes, the file has " +
                  std::to_string(file_size));
  }
  if (file_size > h.total_size()) {
    bad(what, std::to_string(file_size - h.total_size()) + " unexpected trailing bytes after the checksum");
  }
  return h;
}

}  // namespace

bool valid_model_kind(const std::string& kind) {
  if (kind.empty() || kind.size() > 8) return false;
  for (char ch : kind) {
    if (!((ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '-')) return false;
  }
  return true;
}

std::vector<std::uint8_t> encode_container(const ModelContainer& c) {
  if (!valid_model_kind(c.kind)) {
    throw Error(ErrorKind::Usage, "cannot save model: kind '" + c.kind + "' is not 1..8 characters of [a-z0-9-]");
  }
  if (!c.metadata.is_object()) throw Error(ErrorKind::Usage, "cannot save model: metadata is not a JSON object");
  for (float v : c.payload) {
    if (!std::isfinite(v)) throw Error(ErrorKind::Usage, "cannot save " + c.kind + " model: payload has non-finite values");
  }
  json meta = c.metadata;
  meta["format"] = "stex-model";
  meta["kind"] = c.kind;
  // File names are bytes on POSIX: invalid UTF-8 is replaced (U+FFFD) rather than failing the save.
  const std::string text = meta.dump(2, ' ', false, json::error_handler_t::replace);
  if (text.size() > kModelMaxMetadataBytes) {
    throw Error(ErrorKind::Usage, "cannot save " + c.kind + " model: metadata exceeds 1 MiB");
  }
  const std::uint64_t payload = std::uint64_t(c.payload.size()) * sizeof(float);
  if (payload > kMaxPayloadBytes) {
    throw Error(ErrorKind::Usage, "cannot save " + c.kind + " model: payload exceeds " +
                                      std::to_string(kMaxPayloadBytes) + " bytes");
  }

  std::vector<std::uint8_t> out;
  out.reserve(kModelHeaderSize + text.size() + payload + kChecksumSize);
  out.insert(out.end(), kMagic, kMagic + sizeof kMagic);
  put_u32(out, kModelFormatVersion);
  put_u32(out, kEndianTag);
  put_u32(out, kModelHeaderSize);
  put_u32(out, 0);  // flags
  char kind[8] = {};
  std::memcpy(kind, c.kind.data(), c.kind.size());
  out.insert(out.end(), kind, kind + 8);
  put_u64(out, text.size());
  put_u64(out, payload);
  out.insert(out.end(), text.begin(), text.end());
  for (float v : c.payload) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    put_u32(out, bits);
  }
  auto digest = sha256(out.data(), out.size());
  out.insert(out.end(), digest.begin(), digest.end());
  return out;
}

ModelContainer decode_container(const std::uint8_t* data, std::size_t size, const std::string& what) {
  const Header h = check_header(data, size, size, what);
  if (h.payload_size % sizeof(float) != 0) {
    bad(what, "payload size " + std::to_string(h.payload_size) + " bytes is not a whole number of float32 values");
  }
  const std::size_t body = std::size_t(h.total_size() - kChecksumSize);
  auto digest = sha256(data, body);
  if (std::memcmp(digest.data(), data + body, kChecksumSize) != 0) {
    bad(what, "checksum mismatch (the file is corrupt)");
  }

  ModelContainer c;
  c.kind = h.kind;
  try {
    c.metadata = json::parse(data + kModelHeaderSize, data + kModelHeaderSize + h.metadata_size);
  } catch (const json::exception& e) {
    bad(what, std::string("metadata is not valid JSON (") + e.what() + ")");
  }
  if (!c.metadata.is_object()) bad(what, "metadata is not a JSON object");
  if (model_string(c.metadata, "format", what) != "stex-model")
    bad(what, "metadata 'format' is not 'stex-model'");
  if (model_string(c.metadata, "kind", what) != c.kind)
    bad(what, "metadata 'kind' differs from the header's kind '" + c.kind + "'");

  const std::uint64_t count = h.payload_size / sizeof(float);
  c.payload.resize(count);
  const std::uint8_t* payload = data + kModelHeaderSize + h.metadata_size;
  for (std::uint64_t i = 0; i < count; ++i) {
    std::uint32_t bits = get_u32(payload + 4 * i);
    float v;
    std::memcpy(&v, &bits, 4);
    if (!std::isfinite(v)) bad(what, "payload value " + std::to_string(i) + " is not finite");
    c.payload[i] = v;
  }
  return c;
}

void save_container(const ModelContainer& model, const std::string& path) {
  std::vector<std::uint8_t> bytes = encode_container(model);
  write_file_atomic(path, bytes.data(), bytes.size());
}

ModelContainer load_container(const std::string& path, std::string* file_sha256) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw Error(ErrorKind::Input, "cannot open model file '" + path + "': " + std::strerror(errno));
  struct stat st {};
  if (::fstat(::fileno(f.get()), &st) != 0 || !S_ISREG(st.st_mode)) {
    throw Error(ErrorKind::Input, "model file '" + path + "' is not a regular file");
  }
  const std::uint64_t file_size = std::uint64_t(st.st_size);
  std::uint8_t head[kModelHeaderSize];
  std::size_t got = std::fread(head, 1, sizeof head, f.get());
  // Validates the header and its sizes against the file length before the rest is read or allocated.
  check_header(head, got, file_size, path);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(file_size));
  std::memcpy(bytes.data(), head, kModelHeaderSize);
  std::size_t want = bytes.size() - kModelHeaderSize;
  if (std::fread(bytes.data() + kModelHeaderSize, 1, want, f.get()) != want) {
    throw Error(ErrorKind::Input,
                "invalid model file '" + path + "': truncated while reading (file changed?)");
  }
  if (file_sha256) *file_sha256 = sha256_hex(bytes.data(), bytes.size());
  return decode_container(bytes.data(), bytes.size(), path);
}

}  // namespace stex
