// The tile grid of a farm render and the ways a process is told which tiles to render: a `--tiles` spec
// (`0-15`, `3,7,9-12`, steps `1-10x2` as OIIO/OpenCue write them and `1-10:2` as Slurm/OpenJD do), a single
// `--tile-index`, or a task index (`--task-index`, else the scheduler's environment) with a tiles-per-task
// chunk. Everything here is integer bookkeeping; it never touches pixels or files (docs/farm.md).
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace stex::farm {

// One tile: its index (ty * nx + tx), grid position, and pixel window inside the full image.
struct TileRect {
  std::int64_t index = 0;
  int tx = 0, ty = 0;
  int x0 = 0, y0 = 0;
  int width = 0, height = 0;
};

// An image of width x height pixels cut into tile_size x tile_size tiles; the last column and row are
// ragged (narrower/shorter) when the size is not a multiple of the tile size. Tiles are numbered row by
// row: index = ty * nx + tx.
class TileGrid {
 public:
  // Most tiles a grid may have: 2^22 (4 194 304, e.g. 131072 x 131072 px in 64 px tiles). Tile lists,
  // manifests and selections are O(tiles); a grid beyond this (a huge image in tiny tiles) is refused
  // before anything of that size is allocated.
  static constexpr std::int64_t kMaxTiles = std::int64_t(1) << 22;

  // Error(Usage) unless 1 <= width, height <= 2^31-1 and 1 <= tile_size <= 2^31-1; Error(Limit) when the
  // grid would have more than kMaxTiles tiles (the message names the count and the smallest tile size
  // that fits).
  TileGrid(std::int64_t width, std::int64_t height, std::int64_t tile_size);

  int width() const { return width_; }
  int height() const { return height_; }
  int tile_size() const { return tile_size_; }
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  std::int64_t count() const { return std::int64_t(nx_) * ny_; }

  // Error(Usage) naming the grid when index is outside [0, count).
  TileRect tile(std::int64_t index) const;
  TileRect tile(int tx, int ty) const { return tile(std::int64_t(ty) * nx_ + tx); }

  // "8x8 tiles of 512 px over 4096x4096 (indices 0-63)": used in error messages.
  std::string describe() const;

 private:
  int width_, height_, tile_size_, nx_, ny_;
};

// Parses a tile spec against a grid: comma-separated items, each `N`, `A-B`, `A-BxS` or `A-B:S` (inclusive,
// step S >= 1), whitespace allowed around every number and operator; the word `all` selects every tile.
// Returns the selected indices sorted and without duplicates. Error(Usage) naming the offending item for
// anything else: empty items, descending ranges, zero steps, signs, numbers that overflow, and indices
// outside the grid (the message gives the grid size).
std::vector<std::int64_t> parse_tile_spec(const std::string& spec, const TileGrid& grid);

// Reads a variable from the environment; empty or unset -> nullopt. Replaceable for tests.
using EnvLookup = std::function<std::optional<std::string>(const std::string& name)>;
EnvLookup process_env();

// Scheduler variables that carry a task index, in order of precedence (first set one wins):
// SLURM_ARRAY_TASK_ID (Slurm array jobs), JOB_COMPLETION_INDEX (Kubernetes Indexed Jobs).
const std::vector<std::string>& scheduler_task_variables();

struct TileSelectionRequest {
  std::string tiles;                       // --tiles SPEC ("" = not given)
  std::optional<std::int64_t> tile_index;  // --tile-index N
  std::optional<std::int64_t> task_index;  // --task-index N
  std::int64_t tiles_per_task = 1;         // --tiles-per-task K: task i renders tiles [i*K, (i+1)*K)
};

struct TileSelection {
  std::vector<std::int64_t> tiles;  // sorted, unique
  std::string source;  // how they were chosen: "--tiles 0-3", "SLURM_ARRAY_TASK_ID=2", "all tiles"
  std::optional<std::int64_t> task_index;
  bool all = false;  // every tile of the grid
};

// Chooses this process's tiles. Precedence: --tiles, --tile-index and --task-index (at most one of them,
// else Error(Usage)); then the first scheduler variable set (scheduler_task_variables()); else every
// tile. A task index i selects tiles [i*K, min((i+1)*K, count)); Error(Usage) when it starts past the last
// tile (the message says which task indices the grid has) or when K < 1, when a variable is not a
// non-negative integer, or when --tiles-per-task > 1 is combined with --tiles/--tile-index.
TileSelection select_tiles(const TileGrid& grid, const TileSelectionRequest& request,
                           const EnvLookup& env = process_env());

// Number of tasks a grid needs with K tiles per task: ceil(count / K).
std::int64_t task_count(const TileGrid& grid, std::int64_t tiles_per_task);

// "0-3,7,9-12": a compact spec for a sorted index list (for logs and dry runs).
std::string format_index_list(const std::vector<std::int64_t>& sorted_indices);

}  // namespace stex::farm
