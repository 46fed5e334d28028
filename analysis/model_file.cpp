// Model file encoding, decoding and validation (layout: docs/model-format.md). Every field is checked in a
// fixed order — magic, header, sizes against the file length (before anything is allocated from them),
// checksum, metadata, payload — and each failure is an Error(Input) that names the check.
#include "analysis/model_file.h"

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
#include "runtime/texton_params.h"

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

template <class T>
T field(const json& j, const char* key, const std::string& what) {
  if (!j.contains(key)) bad(what, std::string("metadata field '") + key + "' is missing");
  try {
    return j.at(key).get<T>();
  } catch (const json::exception&) {
    bad(what, std::string("metadata field '") + key + "' has the wrong type");
  }
}

int int_field(const json& j, const char* key, long long lo, long long hi, const std::string& what) {
  if (!j.contains(key)) bad(what, std::string("metadata field '") + key + "' is missing");
  const json& v = j.at(key);
  if (!v.is_number_integer()) bad(what, std::string("metadata field '") + key + "' is not an integer");
  long long x;
  if (v.is_number_unsigned()) {
    unsigned long long u = v.get<unsigned long long>();
    x = u > static_cast<unsigned long long>(hi) ? hi + 1 : static_cast<long long>(u);
  } else {
    x = v.get<long long>();
  }
  if (x < lo || x > hi) {
    bad(what, std::string("metadata field '") + key + "' = " + v.dump() + " is out of range [" +
                  std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return int(x);
}

double finite_field(const json& j, const char* key, const std::string& what) {
  if (!j.contains(key) || !j.at(key).is_number()) {
    bad(what, std::string("metadata field '") + key + "' is missing or not a number");
  }
  double v = j.at(key).get<double>();
  if (!std::isfinite(v) || v < 0.0)
    bad(what, std::string("metadata field '") + key + "' is not a finite value >= 0");
  return v;
}

void validate_model(const TextonModel& m) {
  auto fail = [](const std::string& msg) {
    throw Error(ErrorKind::Usage, "cannot save texton model: " + msg);
  };
  if (m.channels < 1 || m.channels > 4) fail("channels must be 1..4");
  if (m.support < 1 || m.support > kModelMaxSupport) fail("support must be 1..4096");
  if (!valid_texton_order(m.order)) fail("order must be 0, 1, 3 or 5");
  if (m.alpha.size() != std::size_t(m.channels) * m.support * m.support) fail("alpha size mismatch");
  for (float v : m.alpha) {
    if (!std::isfinite(v)) fail("alpha has non-finite values");
  }
  for (int c = 0; c < m.channels; ++c) {
    if (!std::isfinite(m.mean[c])) fail("mean has non-finite values");
  }
  if (!std::isfinite(m.rme) || !std::isfinite(m.variance_kept)) fail("report values are not finite");
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
  if (field<std::string>(c.metadata, "format", what) != "stex-model")
    bad(what, "metadata 'format' is not 'stex-model'");
  if (field<std::string>(c.metadata, "kind", what) != c.kind)
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

ModelContainer load_container(const std::string& path) {
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
  return decode_container(bytes.data(), bytes.size(), path);
}

ModelContainer to_container(const TextonModel& m) {
  validate_model(m);
  ModelContainer c;
  c.kind = "texton";
  json& meta = c.metadata;
  meta["format"] = "stex-model";
  meta["kind"] = "texton";
  meta["channels"] = m.channels;
  meta["support"] = m.support;
  meta["order"] = m.order;
  json mean = json::array();
  for (int ch = 0; ch < m.channels; ++ch) mean.push_back(double(m.mean[ch]));
  meta["mean"] = mean;
  meta["linear"] = m.linear;
  meta["alpha"] = {{"type", "float32le"},
                   {"layout", "planar: channel, row, column"},
                   {"count", std::uint64_t(m.alpha.size())}};
  meta["exemplar"] = {{"name", m.exemplar_name},
                      {"sha256", m.exemplar_hash},
                      {"width", m.exemplar_width},
                      {"height", m.exemplar_height}};
  meta["analysis"] = {{"iterations", m.iterations}, {"seed", m.analysis_seed}};
  meta["report"] = {{"rme", m.rme}, {"variance_kept", m.variance_kept}};
  meta["stex_version"] = m.stex_version;
  c.payload = m.alpha;
  return c;
}

std::vector<std::uint8_t> encode_model(const TextonModel& m) { return encode_container(to_container(m)); }

TextonModel decode_model(const std::uint8_t* data, std::size_t size, const std::string& what) {
  return texton_from_container(decode_container(data, size, what), what);
}

TextonModel texton_from_container(const ModelContainer& c, const std::string& what) {
  if (c.kind != "texton") {
    bad(what, "model kind '" + c.kind + "' is not a texton model (this command needs kind 'texton')");
  }
  const json& meta = c.metadata;
  TextonModel m;
  m.channels = int_field(meta, "channels", 1, 4, what);
  m.support = int_field(meta, "support", 1, kModelMaxSupport, what);
  m.order = int_field(meta, "order", 0, 5, what);
  if (!valid_texton_order(m.order)) bad(what, "metadata 'order' must be 0, 1, 3 or 5, got " + std::to_string(m.order));
  const std::uint64_t count = std::uint64_t(m.channels) * m.support * m.support;
  if (c.payload.size() * sizeof(float) != count * sizeof(float)) {
    bad(what, "payload is " + std::to_string(c.payload.size() * sizeof(float)) +
                  " bytes, but channels x support^2 x 4 = " + std::to_string(count * sizeof(float)));
  }
  const json& alpha_meta = meta.contains("alpha") ? meta.at("alpha") : json();
  if (!alpha_meta.is_object() || field<std::string>(alpha_meta, "type", what) != "float32le" ||
      !alpha_meta.contains("count") || !alpha_meta.at("count").is_number_unsigned() ||
      alpha_meta.at("count").get<std::uint64_t>() != count) {
    bad(what, "metadata 'alpha' does not describe " + std::to_string(count) + " float32le values");
  }
  const json& mean = meta.contains("mean") ? meta.at("mean") : json();
  if (!mean.is_array() || mean.size() != std::size_t(m.channels)) {
    bad(what, "metadata 'mean' is not an array of " + std::to_string(m.channels) + " numbers");
  }
  for (int c = 0; c < m.channels; ++c) {
    if (!mean[c].is_number()) bad(what, "metadata 'mean' has a non-number");
    double v = mean[c].get<double>();
    if (!std::isfinite(v) || std::fabs(v) > 3.4e38) bad(what, "metadata 'mean' has a non-finite value");
    m.mean[c] = float(v);
  }
  m.linear = field<bool>(meta, "linear", what);

  const json& ex = meta.contains("exemplar") ? meta.at("exemplar") : json();
  if (!ex.is_object()) bad(what, "metadata field 'exemplar' is missing or not an object");
  m.exemplar_name = field<std::string>(ex, "name", what);
  m.exemplar_hash = field<std::string>(ex, "sha256", what);
  if (!m.exemplar_hash.empty()) {
    bool hex = m.exemplar_hash.size() == 64;
    for (char ch : m.exemplar_hash) hex = hex && ((ch >= '0' && ch <= '9') || (ch >= 'a' && ch <= 'f'));
    if (!hex) bad(what, "metadata 'exemplar.sha256' is not 64 lowercase hex digits");
  }
  m.exemplar_width = int_field(ex, "width", 0, 1 << 30, what);
  m.exemplar_height = int_field(ex, "height", 0, 1 << 30, what);

  const json& an = meta.contains("analysis") ? meta.at("analysis") : json();
  if (!an.is_object()) bad(what, "metadata field 'analysis' is missing or not an object");
  m.iterations = int_field(an, "iterations", 0, 1 << 30, what);
  if (!an.contains("seed") || !an.at("seed").is_number_unsigned()) {
    bad(what, "metadata 'analysis.seed' is not an unsigned integer");
  }
  m.analysis_seed = an.at("seed").get<std::uint64_t>();

  const json& rep = meta.contains("report") ? meta.at("report") : json();
  if (!rep.is_object()) bad(what, "metadata field 'report' is missing or not an object");
  m.rme = finite_field(rep, "rme", what);
  m.variance_kept = finite_field(rep, "variance_kept", what);
  m.stex_version = field<std::string>(meta, "stex_version", what);

  m.alpha = c.payload;
  return m;
}

void save_model(const TextonModel& model, const std::string& path) {
  std::vector<std::uint8_t> bytes = encode_model(model);
  write_file_atomic(path, bytes.data(), bytes.size());
}

TextonModel load_model(const std::string& path) { return texton_from_container(load_container(path), path); }

void bad_model_field(const std::string& what, const std::string& msg) {
  throw Error(ErrorKind::Input, "model '" + what + "': " + msg);
}

double model_number(const json& j, const char* key, const std::string& what) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number())
    bad_model_field(what, std::string("metadata field '") + key + "' is missing or not a number");
  const double v = it->get<double>();
  if (!std::isfinite(v)) bad_model_field(what, std::string("metadata field '") + key + "' is not finite");
  return v;
}

long long model_integer(const json& j, const char* key, long long lo, long long hi, const std::string& what) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number_integer())
    bad_model_field(what, std::string("metadata field '") + key + "' is missing or not an integer");
  const long long v = it->get<long long>();
  if (v < lo || v > hi)
    bad_model_field(what, std::string("metadata field '") + key + "' must be in [" + std::to_string(lo) + ", " +
                              std::to_string(hi) + "], got " + std::to_string(v));
  return v;
}

std::string model_string(const json& j, const char* key, const std::string& what) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_string())
    bad_model_field(what, std::string("metadata field '") + key + "' is missing or not a string");
  return it->get<std::string>();
}

}  // namespace stex
