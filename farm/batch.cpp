// Farm batch rendering: plan, execute, report (farm/batch.h).
#include "farm/batch.h"

#include <sys/stat.h>

#include <chrono>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "farm/interrupt.h"
#include "farm/name_template.h"
#include "farm/tiled_image_writer.h"

namespace stex::farm {

namespace {

bool file_exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

// "" when `info` describes exactly the output this plan would write, else why not.
std::string mismatch(const OutputInfo& info, const RenderIdentity& id, std::int64_t tile_index, int x, int y,
                     int w, int h, const std::string& pixel_type) {
  if (info.id.model_hash != id.model_hash) return "model hash " + info.id.model_hash + " != " + id.model_hash;
  if (info.id.param_hash != id.param_hash) return "param hash " + info.id.param_hash + " != " + id.param_hash;
  if (info.id.full_width != id.full_width || info.id.full_height != id.full_height)
    return "full size " + std::to_string(info.id.full_width) + "x" + std::to_string(info.id.full_height) +
           " != " + std::to_string(id.full_width) + "x" + std::to_string(id.full_height);
  if (info.id.tile_size != id.tile_size)
    return "tile size " + std::to_string(info.id.tile_size) + " != " + std::to_string(id.tile_size);
  if (info.tile_index != tile_index)
    return "tile index " + std::to_string(info.tile_index) + " != " + std::to_string(tile_index);
  if (info.x != x || info.y != y || info.width != w || info.height != h) return "data window differs";
  if (info.id.channels != id.channels)
    return "channels " + std::to_string(info.id.channels) + " != " + std::to_string(id.channels);
  if (info.pixel_type != pixel_type) return "pixel type " + info.pixel_type + " != " + pixel_type;
  return "";
}

void plan_one(PlannedTile& pt, const BatchPlan& plan, std::int64_t tile_index, const std::string& pixel_type,
              std::vector<std::string>& problems) {
  const TileRect& t = pt.tile;
  switch (plan.policy) {
    case ExistingPolicy::Force:
      pt.exists = file_exists(pt.path);
      pt.reason = pt.exists ? "--force" : "missing";
      return;
    case ExistingPolicy::Refuse:
      pt.exists = file_exists(pt.path);
      pt.reason = "missing";
      if (pt.exists) {
        pt.reason = "exists (use --skip-existing, --update or --force)";
        problems.push_back(pt.path);
      }
      return;
    case ExistingPolicy::SkipExisting:
    case ExistingPolicy::Update:
      break;
  }
  OutputInspection ins = inspect_output(pt.path, true);
  pt.exists = ins.state != OutputState::Missing;
  if (ins.state == OutputState::Missing) {
    pt.reason = "missing";
  } else if (ins.state == OutputState::Invalid) {
    pt.reason = "invalid: " + ins.problem;
  } else {
    std::string why =
        mismatch(ins.info, plan.identity, tile_index, t.x0, t.y0, t.width, t.height, pixel_type);
    if (why.empty()) {
      pt.action = TileAction::Skip;
      pt.reason = "up to date";
    } else if (plan.policy == ExistingPolicy::Update) {
      pt.reason = "stale: " + why;
    } else {
      pt.reason = "holds a different render: " + why + " (use --update or --force)";
      problems.push_back(pt.path + ": " + why);
    }
  }
}

std::string join_problems(const std::vector<std::string>& p, std::size_t max) {
  std::string s;
  for (std::size_t i = 0; i < p.size() && i < max; ++i) s += (i ? ", " : "") + p[i];
  if (p.size() > max) s += ", ... (" + std::to_string(p.size()) + " in all)";
  return s;
}

}  // namespace

ExistingPolicy existing_policy(const FarmOptions& o) {
  if (int(o.skip_existing) + int(o.update) + int(o.force) > 1)
    throw Error(ErrorKind::Usage, "give at most one of --skip-existing, --update and --force");
  if (o.skip_existing) return ExistingPolicy::SkipExisting;
  if (o.update) return ExistingPolicy::Update;
  if (o.force) return ExistingPolicy::Force;
  return ExistingPolicy::Refuse;
}

RenderIdentity make_identity(const RenderJob& job, const TileGrid& grid) {
  RenderIdentity id;
  id.stex_version = STEX_VERSION_STRING;
  id.model_hash = job.model_hash;
  id.param_hash =
      compute_param_hash(job.model_hash, job.seed, job.mni, job.origin_x, job.origin_y, job.params);
  id.seed = job.seed;
  id.mni = job.mni;
  id.origin_x = job.origin_x;
  id.origin_y = job.origin_y;
  id.full_width = grid.width();
  id.full_height = grid.height();
  id.tile_size = grid.tile_size();
  id.channels = job.channels;
  return id;
}

BatchPlan plan_batch(const FarmOptions& options, const RenderJob& job, const EnvLookup& env) {
  if (options.tile_size < 1) throw Error(ErrorKind::Usage, "--tile-size must be at least 1");
  if (job.channels < 1 || job.channels > 4)
    throw Error(ErrorKind::Usage,
                "farm render: " + std::to_string(job.channels) + " channels (1 to 4 supported)");
  if (job.model_hash.empty()) throw Error(ErrorKind::Internal, "farm render: the job has no model hash");
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  if ((job.origin_x > 0 && job.origin_x > kMax - job.width) ||
      (job.origin_y > 0 && job.origin_y > kMax - job.height))
    throw Error(ErrorKind::Usage, "--origin plus the image size overflows 64-bit pixel coordinates");
  BatchPlan plan;
  plan.grid = TileGrid(job.width, job.height, options.tile_size);
  plan.policy = existing_policy(options);
  plan.identity = make_identity(job, plan.grid);
  plan.settings = job.settings;
  if (!options.compression.empty()) plan.settings.compression = options.compression;
  plan.output = job.output;
  NameTemplate name(job.output);
  plan.single_image = !name.has_placeholders();
  if (!plan.single_image) name.check_grid(plan.grid);
  const std::string pixel_type = output_pixel_type(job.output, job.settings.bits);  // validates the extension
  TileSelectionRequest req;
  req.tiles = options.tiles;
  req.tile_index = options.tile_index;
  req.task_index = options.task_index;
  req.tiles_per_task = options.tiles_per_task;
  plan.selection = select_tiles(plan.grid, req, env);
  if (plan.single_image) {
    if (!plan.selection.all) {
      throw Error(ErrorKind::Usage,
                  "output '" + job.output +
                      "' is one image (no placeholder), which one process writes whole, but " +
                      plan.selection.source +
                      " selects only some tiles: use a name template such as "
                      "'out/tile_{tx}_{ty}.exr' for per-task tiles (then `stex assemble`), or --tiles all");
    }
    PlannedTile pt;
    pt.tile = TileRect{-1, 0, 0, 0, 0, plan.grid.width(), plan.grid.height()};
    pt.path = job.output;
    plan_one(pt, plan, -1, pixel_type, plan.problems);
    plan.tiles.push_back(pt);
    return plan;
  }
  for (std::int64_t index : plan.selection.tiles) {
    PlannedTile pt;
    pt.tile = plan.grid.tile(index);
    pt.path = name.format(pt.tile);
    plan_one(pt, plan, index, pixel_type, plan.problems);
    plan.tiles.push_back(pt);
  }
  return plan;
}

void execute_plan(const BatchPlan& plan, const RegionRenderer& renderer, Progress& progress,
                  BatchSummary& s) {
  const RenderIdentity& id = plan.identity;
  const int nch = id.channels;
  std::vector<float> px;
  auto render = [&](const TileRect& t) {
    px.assign(std::size_t(t.width) * t.height * nch, 0.0f);
    renderer(id.origin_x + t.x0, id.origin_y + t.y0, t.width, t.height, px);
    if (px.size() != std::size_t(t.width) * t.height * nch) {
      throw Error(ErrorKind::Internal, "renderer returned " + std::to_string(px.size()) + " values for a " +
                                           std::to_string(t.width) + "x" + std::to_string(t.height) + "x" +
                                           std::to_string(nch) + " region");
    }
  };
  auto check_interrupt = [&](std::int64_t done, std::int64_t total) {
    if (int sig = interrupt_signal()) {
      s.interrupted = true;
      throw Error(ErrorKind::Interrupted,
                  std::string("interrupted by ") + (sig == 2 ? "SIGINT" : "SIGTERM") + " after " +
                      std::to_string(done) + " of " + std::to_string(total) +
                      " tiles; temp files removed; rerun with --skip-existing to resume");
    }
  };
  s.tiles_selected = plan.single_image ? plan.grid.count() : std::int64_t(plan.tiles.size());
  if (plan.single_image) {
    const PlannedTile& whole = plan.tiles.at(0);
    if (whole.action == TileAction::Skip) {
      s.tiles_skipped = plan.grid.count();
      progress.tile_finished(-1, whole.path + " (up to date)", true);
      return;
    }
    check_interrupt(0, plan.grid.count());
    TiledImageWriter writer(whole.path, plan.grid, id, plan.settings);
    for (std::int64_t i = 0; i < plan.grid.count(); ++i) {
      check_interrupt(i, plan.grid.count());
      TileRect t = plan.grid.tile(i);
      try {
        render(t);
        writer.write_tile(t, px);
      } catch (...) {
        s.tiles_failed = 1;
        throw;
      }
      ++s.tiles_done;
      s.pixels_rendered += std::int64_t(t.width) * t.height;
      progress.tile_finished(i, whole.path, false);
    }
    writer.finish();
    s.written.push_back(whole.path);
    return;
  }
  std::int64_t k = 0;
  for (const PlannedTile& pt : plan.tiles) {
    check_interrupt(k, std::int64_t(plan.tiles.size()));
    ++k;
    if (pt.action == TileAction::Skip) {
      ++s.tiles_skipped;
      progress.tile_finished(pt.tile.index, pt.path, true);
      continue;
    }
    try {
      render(pt.tile);
      write_tile_file(pt.path, px, pt.tile, id, plan.settings);
    } catch (...) {
      s.tiles_failed = 1;
      throw;
    }
    ++s.tiles_done;
    s.pixels_rendered += std::int64_t(pt.tile.width) * pt.tile.height;
    s.written.push_back(pt.path);
    progress.tile_finished(pt.tile.index, pt.path, false);
  }
}

void print_plan(const BatchPlan& plan, std::int64_t tiles_per_task, std::FILE* out) {
  std::fprintf(out, "grid: %s\n", plan.grid.describe().c_str());
  std::fprintf(out, "selection: %s -> tiles %s (%zu of %lld)", plan.selection.source.c_str(),
               format_index_list(plan.selection.tiles).c_str(), plan.selection.tiles.size(),
               static_cast<long long>(plan.grid.count()));
  if (tiles_per_task > 1 || plan.selection.task_index) {
    std::fprintf(out, "; %lld tile(s) per task, tasks 0-%lld", static_cast<long long>(tiles_per_task),
                 static_cast<long long>(task_count(plan.grid, tiles_per_task) - 1));
  }
  std::fprintf(out, "\noutput: %s (%s)\nparam hash: %s  model hash: %s\n", plan.output.c_str(),
               plan.single_image ? "one image written tile by tile" : "one file per tile",
               plan.identity.param_hash.c_str(), plan.identity.model_hash.c_str());
  for (const PlannedTile& pt : plan.tiles) {
    const TileRect& t = pt.tile;
    const char* action = pt.action == TileAction::Skip ? "skip" : "render";
    if (plan.single_image) {
      std::fprintf(out, "image %dx%d (%lld tiles) -> %s: %s (%s)\n", t.width, t.height,
                   static_cast<long long>(plan.grid.count()), pt.path.c_str(), action, pt.reason.c_str());
    } else {
      std::fprintf(out, "task %lld tile %lld (tx %d, ty %d) window %d,%d %dx%d -> %s: %s (%s)\n",
                   static_cast<long long>(t.index / tiles_per_task), static_cast<long long>(t.index), t.tx,
                   t.ty, t.x0, t.y0, t.width, t.height, pt.path.c_str(), action, pt.reason.c_str());
    }
  }
  std::fflush(out);
}

std::string summary_json(const BatchSummary& s) {
  nlohmann::json j;
  j["tiles_selected"] = s.tiles_selected;
  j["tiles_done"] = s.tiles_done;
  j["tiles_skipped"] = s.tiles_skipped;
  j["tiles_failed"] = s.tiles_failed;
  j["pixels_rendered"] = s.pixels_rendered;
  j["seconds"] = s.seconds;
  j["pixels_per_second"] = s.pixels_per_second;
  j["dry_run"] = s.dry_run;
  j["interrupted"] = s.interrupted;
  j["exit_code"] = s.exit_code;
  j["error"] = s.error;
  j["outputs"] = s.written;
  return j.dump();
}

BatchSummary run(const FarmOptions& options, const RenderJob& job, const RegionRenderer& renderer) {
  ProgressMode mode = parse_progress_mode(options.progress);
  if (options.quiet) mode = ProgressMode::None;
  BatchPlan plan = plan_batch(options, job);
  BatchSummary s;
  if (options.dry_run) {
    s.dry_run = true;
    s.tiles_selected = plan.single_image ? plan.grid.count() : std::int64_t(plan.tiles.size());
    print_plan(plan, options.tiles_per_task, stdout);
    if (options.json) {
      nlohmann::json j = nlohmann::json::parse(summary_json(s));
      nlohmann::json tiles = nlohmann::json::array();
      for (const PlannedTile& pt : plan.tiles) {
        tiles.push_back({{"tile", pt.tile.index},
                         {"tx", pt.tile.tx},
                         {"ty", pt.tile.ty},
                         {"path", pt.path},
                         {"action", pt.action == TileAction::Skip ? "skip" : "render"},
                         {"reason", pt.reason}});
      }
      j["plan"] = tiles;
      std::printf("%s\n", j.dump().c_str());
      std::fflush(stdout);
    }
    return s;
  }
  if (!plan.problems.empty()) {
    throw Error(ErrorKind::Usage,
                std::to_string(plan.problems.size()) +
                    " output(s) in the way: " + join_problems(plan.problems, 4) +
                    ". Use --skip-existing to resume, --update to re-render outputs of other "
                    "renders, or --force to overwrite");
  }
  InterruptGuard guard;
  s.tiles_selected = plan.single_image ? plan.grid.count() : std::int64_t(plan.tiles.size());
  Progress progress(mode, s.tiles_selected);
  auto t0 = std::chrono::steady_clock::now();
  auto finish = [&] {
    progress.finish();
    s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    s.pixels_per_second = s.seconds > 0 ? double(s.pixels_rendered) / s.seconds : 0.0;
  };
  auto report_failure = [&](int code, const std::string& what) {
    finish();
    s.exit_code = code;
    s.error = what;
    if (options.json) {
      std::printf("%s\n", summary_json(s).c_str());
      std::fflush(stdout);
    }
  };
  try {
    execute_plan(plan, renderer, progress, s);
  } catch (const Error& e) {
    report_failure(e.exit_code(), e.what());
    throw;
  } catch (const std::bad_alloc&) {
    report_failure(int(ErrorKind::Limit), "out of memory");
    throw;
  } catch (const std::exception& e) {
    report_failure(int(ErrorKind::Internal), e.what());
    throw;
  }
  finish();
  if (!options.quiet) {
    std::fprintf(stderr, "stex: %lld tile(s) rendered, %lld skipped in %.2f s (%.3g Mpx/s)\n",
                 static_cast<long long>(s.tiles_done), static_cast<long long>(s.tiles_skipped), s.seconds,
                 s.pixels_per_second / 1e6);
  }
  if (options.json) {
    std::printf("%s\n", summary_json(s).c_str());
    std::fflush(stdout);
  }
  return s;
}

}  // namespace stex::farm
