// The cache of recent encoded tiles and regions of stex serve: least recently used entries go first once
// the bytes held (bodies plus keys plus a fixed per-entry overhead) would exceed the cap, so the memory the
// cache holds never exceeds the cap. Keys name the model by its file's SHA-256, so a reloaded model never
// serves a stale tile. Thread-safe.
#pragma once
#include <cstddef>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

namespace stex::service {

struct CachedBody {
  std::string content_type;
  std::string body;
  std::string strategy;  // how it was rendered (X-Stex-Strategy)
};

class TileCache {
 public:
  explicit TileCache(std::size_t cap_bytes) : cap_(cap_bytes) {}
  std::shared_ptr<const CachedBody> get(const std::string& key);
  // Entries larger than the cap are not stored.
  void put(const std::string& key, std::shared_ptr<const CachedBody> value);

  static constexpr std::size_t k_entry_overhead = 256;  // list/map nodes, shared_ptr control block
  std::size_t cap() const { return cap_; }
  std::size_t bytes() const;
  std::size_t entries() const;
  std::uint64_t hits() const;
  std::uint64_t misses() const;
  std::uint64_t evictions() const;

 private:
  static std::size_t cost(const std::string& key, const CachedBody& v) {
    return key.size() + v.body.size() + v.content_type.size() + v.strategy.size() + k_entry_overhead;
  }
  const std::size_t cap_;
  mutable std::mutex mutex_;
  using Lru = std::list<std::pair<std::string, std::shared_ptr<const CachedBody>>>;
  Lru lru_;  // front: most recent
  std::unordered_map<std::string, Lru::iterator> index_;
  std::size_t bytes_ = 0;
  std::uint64_t hits_ = 0, misses_ = 0, evictions_ = 0;
};

}  // namespace stex::service
