// farm::run in-process with the synthetic region callback: per-tile outputs, tiles in any order equal one
// render bit for bit, the existing-output policies (default refuse, --skip-existing, --update, --force),
// dry runs, failures and SIGINT/SIGTERM at tile boundaries, and stex assemble's checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <csignal>
#include <nlohmann/json.hpp>
#include <random>

#include "core/error.h"
#include "farm/assemble.h"
#include "farm/batch.h"
#include "farm/interrupt.h"
#include "tests/farm/farm_test_util.h"
#include "tests/farm/synth_pattern.h"

using namespace stex;
using namespace stex::farm;
using namespace stex::farm::test;

namespace {

struct Fixture {
  RenderJob job;
  FarmOptions opts;
  int calls = 0;
  RegionRenderer renderer() {
    return [this](std::int64_t x0, std::int64_t y0, int w, int h, std::vector<float>& out) {
      ++calls;
      synth_region(job.seed, job.channels, x0, y0, w, h, out);
    };
  }
};

Fixture make(const std::string& output, std::int64_t w = 300, std::int64_t h = 200, int tile = 64) {
  clear_scheduler_env();
  Fixture f;
  f.job.width = w;
  f.job.height = h;
  f.job.channels = 3;
  f.job.origin_x = 1000;
  f.job.origin_y = -77;
  f.job.output = output;
  f.job.model_hash = "model-1";
  f.job.seed = 42;
  f.job.mni = 16;
  f.job.params = {{"mode", "synthetic"}};
  f.opts.tile_size = tile;
  f.opts.quiet = true;
  return f;
}

std::vector<float> expected_whole(const RenderJob& job) {
  std::vector<float> px;
  synth_region(job.seed, job.channels, job.origin_x, job.origin_y, int(job.width), int(job.height), px);
  return px;
}

template <class F>
Error expect_error(F&& f, ErrorKind kind) {
  try {
    f();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), kind) << e.what();
    return e;
  }
  ADD_FAILURE() << "no error";
  return Error(ErrorKind::Internal, "none");
}

}  // namespace

TEST(Batch, PerTileFilesHoldTheirWindow) {
  std::string dir = fresh_dir();
  Fixture f = make(dir + "/t_{tx}_{ty}.exr");
  BatchSummary s = run(f.opts, f.job, f.renderer());
  TileGrid g(300, 200, 64);
  EXPECT_EQ(s.tiles_selected, g.count());
  EXPECT_EQ(s.tiles_done, g.count());
  EXPECT_EQ(s.tiles_skipped, 0);
  EXPECT_EQ(s.pixels_rendered, 300 * 200);
  EXPECT_EQ(f.calls, g.count());
  for (std::int64_t i = 0; i < g.count(); ++i) {
    TileRect t = g.tile(i);
    std::string path = dir + "/t_" + std::to_string(t.tx) + "_" + std::to_string(t.ty) + ".exr";
    std::vector<float> want;
    synth_region(42, 3, 1000 + t.x0, -77 + t.y0, t.width, t.height, want);
    EXPECT_EQ(read_output_pixels(path), want) << path;
    OutputInspection ins = inspect_output(path);
    ASSERT_EQ(ins.state, OutputState::Valid);
    EXPECT_EQ(ins.info.tile_index, i);
    EXPECT_EQ(ins.info.id.origin_x, 1000);
  }
  EXPECT_EQ(count_temp_files(dir), 0);
  nlohmann::json j = nlohmann::json::parse(summary_json(s));
  EXPECT_EQ(j["tiles_done"], g.count());
  EXPECT_EQ(j["tiles_failed"], 0);
  EXPECT_EQ(j["outputs"].size(), std::size_t(g.count()));
}

TEST(Batch, TilesInAnyOrderAssembleToTheSingleRender) {
  std::string dir = fresh_dir();
  Fixture tiles = make(dir + "/tiles/t{index:03}.exr");
  TileGrid g(300, 200, 64);
  std::vector<std::int64_t> order(std::size_t(g.count()));
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = std::int64_t(i);
  std::shuffle(order.begin(), order.end(), std::mt19937(5));
  for (std::int64_t i : order) {  // one "process" per tile, shuffled
    Fixture one = tiles;
    one.opts.tile_index = i;
    run(one.opts, one.job, one.renderer());
  }
  Fixture whole = make(dir + "/whole.exr");
  run(whole.opts, whole.job, whole.renderer());
  std::vector<std::string> inputs = template_inputs(dir + "/tiles/t{index:03}.exr");
  std::shuffle(inputs.begin(), inputs.end(), std::mt19937(6));  // assemble does not care about order
  AssembleResult r = assemble(inputs, dir + "/assembled.exr", {});
  EXPECT_EQ(r.tiles, g.count());
  std::vector<float> want = expected_whole(whole.job);
  EXPECT_EQ(read_output_pixels(dir + "/whole.exr"), want);
  EXPECT_EQ(read_output_pixels(dir + "/assembled.exr"), want);
  OutputInspection a = inspect_output(dir + "/assembled.exr"), w = inspect_output(dir + "/whole.exr");
  ASSERT_EQ(a.state, OutputState::Valid);
  EXPECT_EQ(a.info.id.param_hash, w.info.id.param_hash);
  EXPECT_EQ(a.info.tile_index, -1);
  EXPECT_TRUE(a.info.tiled);
}

TEST(Batch, ExistingOutputPolicies) {
  std::string dir = fresh_dir();
  Fixture f = make(dir + "/t_{tx}_{ty}.exr", 256, 256, 64);  // 16 tiles
  run(f.opts, f.job, f.renderer());
  std::string t00 = dir + "/t_0_0.exr", t11 = dir + "/t_1_1.exr", t22 = dir + "/t_2_2.exr";
  ino_t ino00 = inode_of(t00);

  // Default: refuse, render nothing.
  f.calls = 0;
  Error e = expect_error([&] { run(f.opts, f.job, f.renderer()); }, ErrorKind::Usage);
  EXPECT_NE(std::string(e.what()).find("--skip-existing"), std::string::npos) << e.what();
  EXPECT_EQ(f.calls, 0);

  // --skip-existing: everything up to date; a truncated and a deleted tile are rendered again.
  f.opts.skip_existing = true;
  BatchSummary s = run(f.opts, f.job, f.renderer());
  EXPECT_EQ(s.tiles_skipped, 16);
  EXPECT_EQ(s.tiles_done, 0);
  EXPECT_EQ(inode_of(t00), ino00);
  std::string bytes = slurp(t11);
  {
    std::ofstream(t11, std::ios::binary | std::ios::trunc)
        .write(bytes.data(), std::streamsize(bytes.size() / 2));
  }
  ASSERT_EQ(std::remove(t22.c_str()), 0);
  s = run(f.opts, f.job, f.renderer());
  EXPECT_EQ(s.tiles_done, 2);
  EXPECT_EQ(s.tiles_skipped, 14);
  EXPECT_EQ(s.written, (std::vector<std::string>{t11, t22}));
  EXPECT_EQ(inspect_output(t11).state, OutputState::Valid);
  EXPECT_EQ(inode_of(t00), ino00);

  // --skip-existing refuses to mix renders: another seed finds files of a different render.
  Fixture other = f;
  other.job.seed = 43;
  other.calls = 0;
  e = expect_error([&] { run(other.opts, other.job, other.renderer()); }, ErrorKind::Usage);
  EXPECT_NE(std::string(e.what()).find("param hash"), std::string::npos) << e.what();
  EXPECT_EQ(other.calls, 0);

  // --update re-renders stale files (all of them for a new seed), then nothing.
  other.opts.skip_existing = false;
  other.opts.update = true;
  s = run(other.opts, other.job, other.renderer());
  EXPECT_EQ(s.tiles_done, 16);
  std::vector<float> want;
  synth_region(43, 3, 1000, -77, 64, 64, want);
  EXPECT_EQ(read_output_pixels(t00), want);
  s = run(other.opts, other.job, other.renderer());
  EXPECT_EQ(s.tiles_done, 0);
  EXPECT_EQ(s.tiles_skipped, 16);
  // --update also catches a changed output type or grid.
  other.job.settings.bits = 16;
  s = run(other.opts, other.job, other.renderer());
  EXPECT_EQ(s.tiles_done, 16);
  EXPECT_EQ(inspect_output(t00).info.pixel_type, "half");

  // --force re-renders everything, replacing the files.
  ino_t before = inode_of(t00);
  other.opts.update = false;
  other.opts.force = true;
  s = run(other.opts, other.job, other.renderer());
  EXPECT_EQ(s.tiles_done, 16);
  EXPECT_NE(inode_of(t00), before);

  // The flags are exclusive.
  other.opts.skip_existing = true;
  expect_error([&] { run(other.opts, other.job, other.renderer()); }, ErrorKind::Usage);
  EXPECT_EQ(count_temp_files(dir), 0);
}

TEST(Batch, SelectionAndDryRun) {
  std::string dir = fresh_dir();
  Fixture f = make(dir + "/t_{index}.exr", 256, 256, 64);
  f.opts.tiles = "1-10:3";
  f.opts.dry_run = true;
  BatchSummary s = run(f.opts, f.job, f.renderer());
  EXPECT_TRUE(s.dry_run);
  EXPECT_EQ(s.tiles_selected, 4);
  EXPECT_EQ(f.calls, 0);
  EXPECT_TRUE(list_dir(dir).empty());
  BatchPlan plan = plan_batch(f.opts, f.job);
  ASSERT_EQ(plan.tiles.size(), 4u);
  EXPECT_EQ(plan.tiles[1].path, dir + "/t_4.exr");
  EXPECT_EQ(plan.tiles[1].reason, "missing");
  f.opts.dry_run = false;
  s = run(f.opts, f.job, f.renderer());
  EXPECT_EQ(s.tiles_done, 4);
  EXPECT_TRUE(exists(dir + "/t_10.exr"));
  EXPECT_FALSE(exists(dir + "/t_2.exr"));
  // Task chunks through --task-index.
  f.opts.tiles.clear();
  f.opts.task_index = 1;
  f.opts.tiles_per_task = 5;
  f.opts.skip_existing = true;
  s = run(f.opts, f.job, f.renderer());
  EXPECT_EQ(s.tiles_selected, 5);  // tiles 5-9, of which 7 exists
  EXPECT_EQ(s.tiles_skipped, 1);
  EXPECT_EQ(s.tiles_done, 4);
  // A single image cannot be rendered by a task that holds only some tiles.
  Fixture single = make(dir + "/big.exr", 256, 256, 64);
  single.opts.tiles = "0-3";
  Error e = expect_error([&] { run(single.opts, single.job, single.renderer()); }, ErrorKind::Usage);
  EXPECT_NE(std::string(e.what()).find("name template"), std::string::npos) << e.what();
  single.opts.tiles = "all";
  EXPECT_EQ(run(single.opts, single.job, single.renderer()).tiles_done, 16);
  // Ambiguous templates and bad extensions are refused before anything is rendered.
  Fixture amb = make(dir + "/t_{tx}.exr", 256, 256, 64);
  expect_error([&] { run(amb.opts, amb.job, amb.renderer()); }, ErrorKind::Usage);
  Fixture ext = make(dir + "/t_{index}.xyz", 256, 256, 64);
  expect_error([&] { run(ext.opts, ext.job, ext.renderer()); }, ErrorKind::Usage);
}

TEST(Batch, RendererFailureStopsCleanly) {
  std::string dir = fresh_dir();
  Fixture f = make(dir + "/t_{index}.exr", 256, 256, 64);
  int n = 0;
  RegionRenderer failing = [&](std::int64_t x0, std::int64_t y0, int w, int h, std::vector<float>& out) {
    if (++n == 4) throw Error(ErrorKind::Retryable, "device lost");
    synth_region(42, 3, x0, y0, w, h, out);
  };
  f.opts.json = false;
  expect_error([&] { run(f.opts, f.job, failing); }, ErrorKind::Retryable);
  EXPECT_EQ(list_dir(dir).size(), 3u);
  EXPECT_EQ(count_temp_files(dir), 0);
  RegionRenderer wrong_size = [](std::int64_t, std::int64_t, int, int, std::vector<float>& out) {
    out.resize(5);
  };
  f.opts.force = true;
  expect_error([&] { run(f.opts, f.job, wrong_size); }, ErrorKind::Internal);
}

TEST(Batch, SignalsStopAtTheNextTileBoundary) {
  for (int sig : {SIGINT, SIGTERM}) {
    std::string dir = fresh_dir(sig == SIGINT ? "_int" : "_term");
    Fixture f = make(dir + "/t_{index}.exr", 256, 256, 64);
    int n = 0;
    // A real signal arrives in the middle of tile 3: the tile is finished, then the run stops.
    RegionRenderer r = [&](std::int64_t x0, std::int64_t y0, int w, int h, std::vector<float>& out) {
      if (++n == 3) ::raise(sig);
      synth_region(42, 3, x0, y0, w, h, out);
    };
    Error e = expect_error([&] { run(f.opts, f.job, r); }, ErrorKind::Interrupted);
    EXPECT_EQ(e.exit_code(), 130);
    EXPECT_NE(std::string(e.what()).find(sig == SIGINT ? "SIGINT" : "SIGTERM"), std::string::npos)
        << e.what();
    EXPECT_EQ(n, 3);
    EXPECT_EQ(list_dir(dir).size(), 3u);
    EXPECT_EQ(count_temp_files(dir), 0);
    for (const auto& name : list_dir(dir))
      EXPECT_EQ(inspect_output(dir + "/" + name).state, OutputState::Valid);
    // The single-image writer removes its temp file and leaves no output.
    Fixture single = make(dir + "/big.exr", 256, 256, 64);
    n = 0;
    expect_error([&] { run(single.opts, single.job, r); }, ErrorKind::Interrupted);
    EXPECT_FALSE(exists(dir + "/big.exr"));
    EXPECT_EQ(count_temp_files(dir), 0);
    // Resume.
    f.opts.skip_existing = true;
    BatchSummary s = run(f.opts, f.job, f.renderer());
    EXPECT_EQ(s.tiles_skipped, 3);
    EXPECT_EQ(s.tiles_done, 13);
  }
  // The handlers were restored: SIGINT is back to its default disposition.
  struct sigaction sa {};
  sigaction(SIGINT, nullptr, &sa);
  EXPECT_EQ(sa.sa_handler, SIG_DFL);
}

TEST(Assemble, RejectsMixedRendersMissingAndDuplicateTiles) {
  std::string dir = fresh_dir();
  Fixture a = make(dir + "/a/t_{index}.exr", 256, 256, 64);
  run(a.opts, a.job, a.renderer());
  Fixture b = a;  // same grid, other seed
  b.job.output = dir + "/b/t_{index}.exr";
  b.job.seed = 99;
  run(b.opts, b.job, b.renderer());
  Fixture c = make(dir + "/c/t_{index}.exr", 256, 256, 128);  // other grid
  run(c.opts, c.job, c.renderer());

  std::vector<std::string> good = template_inputs(dir + "/a/t_{index}.exr");
  ASSERT_EQ(good.size(), 16u);
  auto assemble_error = [&](std::vector<std::string> inputs, const std::string& needle) {
    Error e = expect_error([&] { assemble(inputs, dir + "/out.exr", {}); }, ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    EXPECT_FALSE(exists(dir + "/out.exr"));
  };
  std::vector<std::string> mixed = good;
  mixed[5] = dir + "/b/t_5.exr";
  assemble_error(mixed, "param hash");
  std::vector<std::string> regrid = good;
  regrid[1] = dir + "/c/t_1.exr";
  assemble_error(regrid, "different render");
  std::vector<std::string> missing(good.begin(), good.end());
  missing.erase(missing.begin() + 7);
  missing.erase(missing.begin() + 2);
  assemble_error(missing, "2 tile(s) missing: 2,7");
  std::vector<std::string> dup = good;
  dup[3] = good[4];
  assemble_error(dup, "given twice");
  std::vector<std::string> absent = good;
  absent[0] = dir + "/nope.exr";
  assemble_error(absent, "does not exist");
  std::vector<std::string> truncated = good;
  std::string bytes = slurp(good[9]);
  std::string cut = dir + "/a/cut.exr";
  { std::ofstream(cut, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size() * 2 / 3)); }
  truncated[9] = cut;
  try {
    assemble(truncated, dir + "/out.exr", {});
    ADD_FAILURE() << "truncated tile accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
  }
  EXPECT_FALSE(exists(dir + "/out.exr"));
  EXPECT_EQ(count_temp_files(dir), 0);
  // Template mode with a missing first tile.
  Error e = expect_error([&] { template_inputs(dir + "/none/t_{index}.exr"); }, ErrorKind::Input);
  EXPECT_NE(std::string(e.what()).find("first tile"), std::string::npos);
  // And the good set works, to PNG too (scanline path).
  assemble(good, dir + "/ok.png", {});
  EXPECT_EQ(inspect_output(dir + "/ok.png").state, OutputState::Valid);
}
