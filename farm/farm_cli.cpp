// Farm command-line options (farm/farm_cli.h).
#include "farm/farm_cli.h"

#include "core/error.h"

namespace stex::farm {

void add_farm_options(CLI::App* app, FarmOptions& o) {
  const char* g = "Farm (docs/farm.md)";
  app->add_option("--tile-size", o.tile_size,
                  "Render as a grid of TxT tiles (last row/column ragged); tile index = ty*nx + tx")
      ->group(g)
      ->check(CLI::Range(1, 1 << 30));
  app->add_option("--tiles", o.tiles,
                  "Tiles this process renders: '0-15', '3,7,9-12', steps '1-10x2' or '1-10:2', or 'all'")
      ->group(g);
  app->add_option("--tile-index", o.tile_index, "Render this one tile")->group(g);
  app->add_option("--task-index", o.task_index,
                  "Render the tiles of task N: [N*K, (N+1)*K) with K = --tiles-per-task (default: "
                  "$SLURM_ARRAY_TASK_ID, else $JOB_COMPLETION_INDEX, else all tiles)")
      ->group(g);
  app->add_option("--tiles-per-task", o.tiles_per_task, "Tiles per task index (default 1)")
      ->group(g)
      ->check(CLI::PositiveNumber);
  app->add_flag("--skip-existing", o.skip_existing,
                "Keep valid outputs of this same render (resume); re-render invalid or partial ones")
      ->group(g);
  app->add_flag("--update", o.update,
                "Like --skip-existing, and re-render outputs whose parameter hash differs")
      ->group(g);
  app->add_flag("--force", o.force, "Overwrite existing outputs")->group(g);
  app->add_flag("--dry-run", o.dry_run, "List the tasks, tiles and output paths with what would be done")
      ->group(g);
  app->add_option("--progress", o.progress,
                  "Progress: auto (bar on a terminal, else lines), bar, lines, openjd, none")
      ->group(g)
      ->check(CLI::IsMember({"auto", "bar", "lines", "openjd", "none"}));
  app->add_option(
         "--compression", o.compression,
         "Compression of the farm outputs (OIIO names): EXR zip (default), zips, piz, dwaa, none; TIFF "
         "zip, lzw, none. Float EXR with zip is CPU-bound; none or piz write several times faster")
      ->group(g);
  app->add_flag("--json", o.json,
                "Print a JSON summary on stdout (tiles done/skipped/failed, seconds, pixels per second)")
      ->group(g);
}

bool farm_requested(const FarmOptions& o) {
  bool any = !o.tiles.empty() || o.tile_index || o.task_index || o.tiles_per_task != 1 || o.skip_existing ||
             o.update || o.force || o.dry_run;
  if (o.tile_size > 0) return true;
  if (any) throw Error(ErrorKind::Usage, "farm options (--tiles, --skip-existing, ...) need --tile-size");
  return false;
}

const char* exit_code_help() {
  return "Exit codes: 0 success; 2 usage error; 3 bad input (not retryable); 4 no/unsuitable OpenCL device; "
         "5 size or resource limit; 6 output I/O failure (retryable); 75 transient device failure "
         "(retryable); 130 interrupted by SIGINT/SIGTERM (retryable, resume with --skip-existing); "
         "1 internal error. See docs/farm.md.";
}

}  // namespace stex::farm
