// Models by name with reload on change (service/model_store.h).
#include "service/model_store.h"

#include <sys/stat.h>

#include <algorithm>
#include <filesystem>

#include "model/kinds.h"
#include "core/error.h"

namespace stex::service {

bool valid_model_name(const std::string& n) {
  if (n.empty() || n.size() > 128 || n[0] == '.') return false;
  return std::all_of(n.begin(), n.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
           c == '-';
  });
}

std::shared_ptr<const ServedModel> ModelStore::get(const std::string& name) {
  if (!valid_model_name(name)) return nullptr;
  const std::string path = dir_ + "/" + name + ".stex";
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
    std::lock_guard<std::mutex> lock(mutex_);
    loaded_.erase(name);
    return nullptr;
  }
  const std::int64_t mtime_ns = std::int64_t(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
  std::uint64_t generation = 1;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = loaded_.find(name);
    if (it != loaded_.end()) {
      const ServedModel& m = *it->second;
      if (m.file_size == std::uint64_t(st.st_size) && m.mtime_ns == mtime_ns) return it->second;
      generation = m.generation + 1;
    }
  }
  // (Re)load outside the lock: a big model does not stall requests for the others.
  auto m = std::make_shared<ServedModel>();
  static_cast<LoadedModel&>(*m) = load_model_file(path);
  m->name = name;
  m->file_size = std::uint64_t(st.st_size);
  m->mtime_ns = mtime_ns;
  m->generation = generation;
  std::lock_guard<std::mutex> lock(mutex_);
  if (generation > 1) ++reloads_;
  loaded_[name] = m;
  return m;
}

std::vector<std::string> ModelStore::names() const {
  std::vector<std::string> out;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    const auto& p = it->path();
    if (p.extension() != ".stex") continue;
    std::error_code ec2;
    if (!it->is_regular_file(ec2)) continue;
    const std::string stem = p.stem().string();
    if (valid_model_name(stem)) out.push_back(stem);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::uint64_t ModelStore::reloads() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return reloads_;
}

}  // namespace stex::service
