// Farm batch rendering, independent of the model kind: a RenderJob (size, channels, output name, what
// identifies the pixels) plus a RegionRenderer callback that computes any rectangle of the image. This is
// what `stex render --tile-size T ...` runs (docs/farm.md), and what an embedding application or a test
// runs with its own callback.
//
// farm::run(options, job, renderer):
//   1. cuts the image into a TileGrid and picks this process's tiles (farm/tile_grid.h: --tiles,
//      --tile-index, --task-index or the scheduler's environment, --tiles-per-task);
//   2. plans each tile against what is on disk: missing -> render; existing -> refuse (default),
//      skip if valid and from the same render (--skip-existing; a different render is an error),
//      re-render if invalid or stale (--update), or always re-render (--force);
//   3. with --dry-run prints the plan; otherwise renders tile by tile, writing each tile atomically
//      (farm/output_file.h) or, when the output name has no placeholder, the whole image through the
//      out-of-core tiled writer (farm/tiled_image_writer.h);
//   4. stops at the next tile boundary on SIGINT/SIGTERM (Error(Interrupted), exit 130), reports
//      progress (farm/progress.h) and, with --json, prints a summary on stdout.
#pragma once
#include <cstdint>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "farm/output_file.h"
#include "farm/progress.h"
#include "farm/tile_grid.h"

namespace stex::farm {

// Computes the pixels of the rectangle [x0, x0+w) x [y0, y0+h) in noise space (the job's origin already
// added) as interleaved floats, row-major: out[(y*w + x)*channels + c]. `out` arrives sized
// w*h*channels. Must be a pure function of its arguments (docs/ARCHITECTURE.md "Invariants"): that is what
// makes tiles rendered anywhere join bit for bit. Throws stex::Error on failure (its kind becomes the
// exit code).
using RegionRenderer =
    std::function<void(std::int64_t x0, std::int64_t y0, int w, int h, std::vector<float>& out)>;

enum class ExistingPolicy {
  Refuse,        // default: an existing output is an error (exit 2), nothing is rendered
  SkipExisting,  // --skip-existing: keep valid outputs of this render; re-render invalid/partial ones
  Update,        // --update: like SkipExisting, and re-render outputs of a different render
  Force,         // --force: re-render everything
};

struct FarmOptions {
  int tile_size = 0;                       // --tile-size T (0: no farm mode)
  std::string tiles;                       // --tiles SPEC
  std::optional<std::int64_t> tile_index;  // --tile-index N
  std::optional<std::int64_t> task_index;  // --task-index N
  std::int64_t tiles_per_task = 1;         // --tiles-per-task K
  bool skip_existing = false, update = false, force = false;
  bool dry_run = false;           // --dry-run
  std::string progress = "auto";  // --progress auto|bar|lines|openjd|none
  bool json = false;              // --json: summary on stdout
  std::string compression;        // --compression: OIIO compression of the outputs ("" = format default)
  bool quiet = false;             // no progress, no messages (errors still reported)
};

struct RenderJob {
  std::int64_t width = 0, height = 0;
  int channels = 0;
  std::int64_t origin_x = 0, origin_y = 0;  // noise-space coordinates of image pixel (0, 0)
  std::string output;                       // name template or a single image path
  std::string model_hash;                   // identifies the model (e.g. SHA-256 of the model file)
  std::uint64_t seed = 0;
  double mni = 0.0;
  KeyValues params;         // other pixel-affecting parameters (mode, scale, ...)
  OutputSettings settings;  // pixel type, compression, extra metadata
};

enum class TileAction { Render, Skip };

struct PlannedTile {
  TileRect tile;
  std::string path;
  TileAction action = TileAction::Render;
  std::string reason;  // "missing", "up to date", "invalid: ...", "stale: ...", "--force"
  bool exists = false;
};

struct BatchPlan {
  TileGrid grid{1, 1, 1};
  RenderIdentity identity;
  OutputSettings settings;
  ExistingPolicy policy = ExistingPolicy::Refuse;
  bool single_image = false;  // one large image (no placeholder in the output name)
  std::string output;         // the template / image path
  TileSelection selection;
  std::vector<PlannedTile> tiles;     // per-tile mode: the selected tiles; single image: exactly one entry
                                      // (tile = the whole image) deciding the file's fate
  std::vector<std::string> problems;  // with Refuse: existing outputs (run() throws unless dry-run)
};

struct BatchSummary {
  std::int64_t tiles_selected = 0, tiles_done = 0, tiles_skipped = 0, tiles_failed = 0;
  std::int64_t pixels_rendered = 0;
  double seconds = 0.0;
  double pixels_per_second = 0.0;
  bool dry_run = false;
  bool interrupted = false;
  int exit_code = 0;
  std::string error;
  std::vector<std::string> written;  // outputs written by this run
};

// Policy from the three flags; Error(Usage) when more than one is given.
ExistingPolicy existing_policy(const FarmOptions& options);

// The RenderIdentity of a job on a grid (param hash included).
RenderIdentity make_identity(const RenderJob& job, const TileGrid& grid);

// Steps 1-2 above. Error(Usage) for bad options, or a single-image output with a partial tile selection.
BatchPlan plan_batch(const FarmOptions& options, const RenderJob& job, const EnvLookup& env = process_env());

// Step 3 (without --dry-run): executes a plan. Throws stex::Error on the first failure (after removing
// temp files) and Error(Interrupted) on SIGINT/SIGTERM; `summary` is filled in either case.
void execute_plan(const BatchPlan& plan, const RegionRenderer& renderer, Progress& progress,
                  BatchSummary& summary);

// Prints a plan (dry run) on `out`: the grid, the selection and one line per tile with its path and action.
void print_plan(const BatchPlan& plan, std::int64_t tiles_per_task, std::FILE* out);

// The JSON summary: {"tiles_selected", "tiles_done", "tiles_skipped", "tiles_failed", "seconds",
// "pixels_rendered", "pixels_per_second", "interrupted", "exit_code", "error", "outputs"}.
std::string summary_json(const BatchSummary& summary);

// Steps 1-4. Returns the summary on success; throws stex::Error (after printing the JSON summary when
// asked) on failure. Progress goes to stderr (OpenJD lines to stdout).
BatchSummary run(const FarmOptions& options, const RenderJob& job, const RegionRenderer& renderer);

}  // namespace stex::farm
