// The models of stex serve: `DIR/NAME.stex` is model NAME. A lookup stats the file and reloads it when its
// identity (inode, size, modification time) changed since the last load, so a model re-analysed in place
// (stex analyze writes atomically: temp file + rename) is served from the next request on; the loaded
// model carries its file's SHA-256, which keys the tile cache and the device's renderers. Thread-safe.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "model/loaded_model.h"

namespace stex::service {

// A model file as the service holds it: the loaded model (decoded once; `what` is its path, `sha256` that of
// its bytes, the CLI's stex:model_sha256) and the file identity a lookup compares.
struct ServedModel : LoadedModel {
  std::string name;
  std::uint64_t file_size = 0;
  std::int64_t mtime_ns = 0;
  std::uint64_t generation = 0;  // 1 for the first load, +1 per reload
};

// Model names: 1-128 of [A-Za-z0-9._-], not starting with '.' (no paths).
bool valid_model_name(const std::string& name);

class ModelStore {
 public:
  explicit ModelStore(std::string dir) : dir_(std::move(dir)) {}
  // nullptr when DIR/NAME.stex does not exist (or the name is invalid); Error(Input) when it exists but
  // cannot be loaded (corrupt, unknown kind, invalid fields).
  std::shared_ptr<const ServedModel> get(const std::string& name);
  // The names of DIR/*.stex, sorted.
  std::vector<std::string> names() const;
  std::uint64_t reloads() const;
  const std::string& dir() const { return dir_; }

 private:
  const std::string dir_;
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<const ServedModel>> loaded_;
  std::uint64_t reloads_ = 0;
};

}  // namespace stex::service
