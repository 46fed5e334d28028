// Tile grid, tile specs and scheduler task indices (farm/tile_grid.h). The spec parser is a small
// hand-written scanner so that every error can name the item it stopped at, and all arithmetic is checked
// against int64 overflow before it happens.
#include "farm/tile_grid.h"

#include <algorithm>
#include <cctype>
#include <climits>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "core/error.h"

namespace stex::farm {

namespace {

constexpr std::int64_t kMaxDim = std::numeric_limits<int>::max();

std::string trim(const std::string& s) {
  std::size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

// Scans one spec item: number [ '-' number [ ('x'|':') number ] ], whitespace between any two parts.
class ItemScanner {
 public:
  ItemScanner(const std::string& item, const std::string& spec) : s_(item), spec_(spec) {}

  void skip_space() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  bool at_end() {
    skip_space();
    return pos_ >= s_.size();
  }
  bool accept(char c) {
    skip_space();
    if (pos_ < s_.size() && s_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  char peek() {
    skip_space();
    return pos_ < s_.size() ? s_[pos_] : '\0';
  }
  std::int64_t number(const char* what) {
    skip_space();
    if (pos_ >= s_.size() || !std::isdigit(static_cast<unsigned char>(s_[pos_]))) {
      if (pos_ < s_.size() && (s_[pos_] == '-' || s_[pos_] == '+'))
        fail(std::string("expected ") + what + ", found a sign (indices are non-negative)");
      fail(std::string("expected ") + what +
           (pos_ < s_.size() ? " at '" + s_.substr(pos_) + "'" : " at the end"));
    }
    std::int64_t v = 0;
    while (pos_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[pos_]))) {
      int d = s_[pos_] - '0';
      if (v > (std::numeric_limits<std::int64_t>::max() - d) / 10) fail("number too large");
      v = v * 10 + d;
      ++pos_;
    }
    return v;
  }
  [[noreturn]] void fail(const std::string& why) const {
    throw Error(ErrorKind::Usage, "bad tile spec '" + spec_ + "': item '" + trim(s_) + "': " + why);
  }

 private:
  const std::string& s_;
  const std::string& spec_;
  std::size_t pos_ = 0;
};

std::int64_t parse_env_index(const std::string& name, const std::string& value) {
  std::string v = trim(value);
  bool ok = !v.empty() && v.size() <= 18;
  for (char c : v) ok = ok && std::isdigit(static_cast<unsigned char>(c));
  if (!ok)
    throw Error(ErrorKind::Usage, name + "='" + value + "' is not a task index (a non-negative integer)");
  return std::strtoll(v.c_str(), nullptr, 10);
}

}  // namespace

TileGrid::TileGrid(std::int64_t width, std::int64_t height, std::int64_t tile_size) {
  if (width < 1 || height < 1 || width > kMaxDim || height > kMaxDim) {
    throw Error(ErrorKind::Usage, "image size " + std::to_string(width) + "x" + std::to_string(height) +
                                      " is out of range (1 to " + std::to_string(kMaxDim) + " per side)");
  }
  if (tile_size < 1 || tile_size > kMaxDim)
    throw Error(ErrorKind::Usage, "tile size " + std::to_string(tile_size) + " is out of range (>= 1)");
  width_ = int(width);
  height_ = int(height);
  tile_size_ = int(tile_size);
  nx_ = int((width + tile_size - 1) / tile_size);
  ny_ = int((height + tile_size - 1) / tile_size);
  // nx, ny <= 2^31-1: the product fits in int64.
  if (count() > kMaxTiles) {
    std::int64_t fit = tile_size;  // smallest tile size whose grid fits (doubling search, <= 2^31-1)
    auto tiles_of = [&](std::int64_t t) { return ((width + t - 1) / t) * ((height + t - 1) / t); };
    while (fit < kMaxDim && tiles_of(fit) > kMaxTiles) fit = std::min<std::int64_t>(fit * 2, kMaxDim);
    std::int64_t lo = tile_size + 1, hi = fit;  // tiles_of is non-increasing in t: bisect for the smallest
    while (lo < hi) {
      std::int64_t mid = lo + (hi - lo) / 2;
      if (tiles_of(mid) > kMaxTiles) lo = mid + 1; else hi = mid;
    }
    throw Error(ErrorKind::Limit, "tile size " + std::to_string(tile_size) + " over " + std::to_string(width) +
                                      "x" + std::to_string(height) + " gives " + std::to_string(count()) +
                                      " tiles, more than the limit of " + std::to_string(kMaxTiles) +
                                      ": use --tile-size " + std::to_string(lo) + " or larger");
  }
}

TileRect TileGrid::tile(std::int64_t index) const {
  if (index < 0 || index >= count()) {
    throw Error(ErrorKind::Usage,
                "tile " + std::to_string(index) + " is out of range: the grid has " + describe());
  }
  TileRect r;
  r.index = index;
  r.tx = int(index % nx_);
  r.ty = int(index / nx_);
  r.x0 = int(std::int64_t(r.tx) * tile_size_);
  r.y0 = int(std::int64_t(r.ty) * tile_size_);
  r.width = int(std::min<std::int64_t>(tile_size_, width_ - std::int64_t(r.x0)));
  r.height = int(std::min<std::int64_t>(tile_size_, height_ - std::int64_t(r.y0)));
  return r;
}

std::string TileGrid::describe() const {
  std::ostringstream os;
  os << nx_ << "x" << ny_ << " tiles of " << tile_size_ << " px over " << width_ << "x" << height_
     << " (indices 0-" << count() - 1 << ")";
  return os.str();
}

std::vector<std::int64_t> parse_tile_spec(const std::string& spec, const TileGrid& grid) {
  const std::int64_t count = grid.count();
  if (trim(spec).empty()) throw Error(ErrorKind::Usage, "bad tile spec '" + spec + "': it is empty");
  if (trim(spec) == "all") {
    std::vector<std::int64_t> all(static_cast<std::size_t>(count));
    for (std::int64_t i = 0; i < count; ++i) all[std::size_t(i)] = i;
    return all;
  }
  // A bitmap of the grid (count <= TileGrid::kMaxTiles: at most 512 KiB): repeated or overlapping items
  // ("0-999,0-999,...") cost time linear in their length and no memory beyond it (found by fuzz_tile_spec:
  // a list of indices grew by the grid size per item; folding it by sorting was slow under load).
  std::vector<bool> selected(static_cast<std::size_t>(count), false);
  std::size_t start = 0;
  while (true) {
    std::size_t comma = spec.find(',', start);
    std::string item = spec.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    ItemScanner sc(item, spec);
    if (sc.at_end()) sc.fail("empty item (two commas, or a comma at an end)");
    std::int64_t a = sc.number("a tile index");
    std::int64_t b = a, step = 1;
    if (sc.accept('-')) {
      b = sc.number("the end of the range");
      char op = sc.peek();
      if (op == 'x' || op == 'X' || op == ':') {
        sc.accept(op);
        step = sc.number("a step");
        if (step < 1) sc.fail("the step must be at least 1");
      }
    }
    if (!sc.at_end()) sc.fail("unexpected text (expected N, A-B, A-BxS or A-B:S)");
    if (b < a) sc.fail("descending range (" + std::to_string(a) + " > " + std::to_string(b) + ")");
    if (a >= count || b >= count) {
      sc.fail("tile " + std::to_string(b >= count && a < count ? b : a) + " is out of range: the grid has " +
              grid.describe());
    }
    for (std::int64_t i = a;; i += step) {  // b - i < step checked first: i + step never overflows
      selected[static_cast<std::size_t>(i)] = true;
      if (b - i < step) break;
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  std::vector<std::int64_t> out;
  for (std::int64_t i = 0; i < count; ++i)
    if (selected[static_cast<std::size_t>(i)]) out.push_back(i);
  return out;
}

EnvLookup process_env() {
  return [](const std::string& name) -> std::optional<std::string> {
    const char* v = std::getenv(name.c_str());
    if (!v || !*v) return std::nullopt;
    return std::string(v);
  };
}

const std::vector<std::string>& scheduler_task_variables() {
  static const std::vector<std::string> vars = {"SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"};
  return vars;
}

std::int64_t task_count(const TileGrid& grid, std::int64_t tiles_per_task) {
  if (tiles_per_task < 1)
    throw Error(ErrorKind::Usage,
                "--tiles-per-task must be at least 1, got " + std::to_string(tiles_per_task));
  return (grid.count() + tiles_per_task - 1) / tiles_per_task;
}

TileSelection select_tiles(const TileGrid& grid, const TileSelectionRequest& request, const EnvLookup& env) {
  const std::int64_t k = request.tiles_per_task;
  const std::int64_t tasks = task_count(grid, k);  // validates k
  int explicit_count =
      int(!request.tiles.empty()) + int(request.tile_index.has_value()) + int(request.task_index.has_value());
  if (explicit_count > 1)
    throw Error(ErrorKind::Usage, "give at most one of --tiles, --tile-index and --task-index");
  TileSelection sel;
  if (!request.tiles.empty() || request.tile_index) {
    if (k != 1)
      throw Error(
          ErrorKind::Usage,
          "--tiles-per-task applies to a task index (--task-index or the scheduler's), not to --tiles or "
          "--tile-index");
    if (!request.tiles.empty()) {
      sel.tiles = parse_tile_spec(request.tiles, grid);
      sel.source = "--tiles " + trim(request.tiles);
      sel.all = std::int64_t(sel.tiles.size()) == grid.count();
    } else {
      sel.tiles = {grid.tile(*request.tile_index).index};
      sel.source = "--tile-index " + std::to_string(*request.tile_index);
      sel.all = grid.count() == 1;
    }
    return sel;
  }
  std::optional<std::int64_t> task = request.task_index;
  std::string source = task ? "--task-index " + std::to_string(*task) : "";
  if (!task) {
    for (const std::string& name : scheduler_task_variables()) {
      if (auto v = env(name)) {
        task = parse_env_index(name, *v);
        source = name + "=" + trim(*v);
        break;
      }
    }
  }
  if (!task) {
    sel.tiles.resize(static_cast<std::size_t>(grid.count()));
    for (std::int64_t i = 0; i < grid.count(); ++i) sel.tiles[std::size_t(i)] = i;
    sel.source = "all tiles";
    sel.all = true;
    return sel;
  }
  if (*task < 0 || *task >= tasks) {
    throw Error(ErrorKind::Usage, "task " + std::to_string(*task) + " (" + source + ") with " +
                                      std::to_string(k) + " tile(s) per task is out of range: the grid has " +
                                      grid.describe() + ", i.e. tasks 0-" + std::to_string(tasks - 1));
  }
  std::int64_t first = *task * k;  // < count, no overflow: task < tasks = ceil(count / k)
  std::int64_t last = std::min(grid.count(), first + k);
  for (std::int64_t i = first; i < last; ++i) sel.tiles.push_back(i);
  sel.source = source;
  sel.task_index = task;
  sel.all = std::int64_t(sel.tiles.size()) == grid.count();
  return sel;
}

std::string format_index_list(const std::vector<std::int64_t>& v) {
  std::ostringstream os;
  for (std::size_t i = 0; i < v.size();) {
    std::size_t j = i;
    while (j + 1 < v.size() && v[j + 1] == v[j] + 1) ++j;
    if (i) os << ",";
    os << v[i];
    if (j > i) os << "-" << v[j];
    i = j + 1;
  }
  return os.str();
}

}  // namespace stex::farm
