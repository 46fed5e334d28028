// LRU cache of encoded tiles with a byte cap (service/tile_cache.h).
#include "service/tile_cache.h"

namespace stex::service {

std::shared_ptr<const CachedBody> TileCache::get(const std::string& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = index_.find(key);
  if (it == index_.end()) {
    ++misses_;
    return nullptr;
  }
  lru_.splice(lru_.begin(), lru_, it->second);
  ++hits_;
  return it->second->second;
}

void TileCache::put(const std::string& key, std::shared_ptr<const CachedBody> value) {
  const std::size_t c = cost(key, *value);
  std::lock_guard<std::mutex> lock(mutex_);
  if (c > cap_) return;
  auto it = index_.find(key);
  if (it != index_.end()) {
    bytes_ -= cost(key, *it->second->second);
    lru_.erase(it->second);
    index_.erase(it);
  }
  while (!lru_.empty() && bytes_ + c > cap_) {
    bytes_ -= cost(lru_.back().first, *lru_.back().second);
    index_.erase(lru_.back().first);
    lru_.pop_back();
    ++evictions_;
  }
  lru_.emplace_front(key, std::move(value));
  index_[key] = lru_.begin();
  bytes_ += c;
}

std::size_t TileCache::bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return bytes_;
}
std::size_t TileCache::entries() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return lru_.size();
}
std::uint64_t TileCache::hits() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return hits_;
}
std::uint64_t TileCache::misses() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return misses_;
}
std::uint64_t TileCache::evictions() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return evictions_;
}

}  // namespace stex::service
