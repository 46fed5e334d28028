// Tile grid geometry, --tiles spec parsing (valid and invalid), and task selection from options and the
// scheduler environment (precedence, chunks, errors).
#include <gtest/gtest.h>

#include <map>

#include "core/error.h"
#include "farm/tile_grid.h"

using namespace stex;
using namespace stex::farm;

namespace {

using V = std::vector<std::int64_t>;

// Expects Error(Usage) whose message contains every string of `needles`.
template <class F>
void expect_usage(F&& f, std::vector<std::string> needles) {
  try {
    f();
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage) << e.what();
    for (const auto& n : needles)
      EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what() << " lacks " << n;
  }
}

EnvLookup fake_env(std::map<std::string, std::string> vars) {
  return [vars](const std::string& name) -> std::optional<std::string> {
    auto it = vars.find(name);
    if (it == vars.end() || it->second.empty()) return std::nullopt;
    return it->second;
  };
}

}  // namespace

TEST(TileGrid, GeometryWithRaggedEdges) {
  TileGrid g(1000, 700, 256);
  EXPECT_EQ(g.nx(), 4);
  EXPECT_EQ(g.ny(), 3);
  EXPECT_EQ(g.count(), 12);
  std::int64_t area = 0;
  for (std::int64_t i = 0; i < g.count(); ++i) {
    TileRect t = g.tile(i);
    EXPECT_EQ(t.index, i);
    EXPECT_EQ(t.ty * g.nx() + t.tx, i);
    EXPECT_EQ(t.x0, t.tx * 256);
    EXPECT_EQ(t.y0, t.ty * 256);
    EXPECT_EQ(t.width, t.tx == 3 ? 1000 - 768 : 256);
    EXPECT_EQ(t.height, t.ty == 2 ? 700 - 512 : 256);
    area += std::int64_t(t.width) * t.height;
  }
  EXPECT_EQ(area, 1000 * 700);
  EXPECT_EQ(g.tile(2, 1).index, 6);
  TileGrid exact(512, 512, 256);
  EXPECT_EQ(exact.count(), 4);
  EXPECT_EQ(exact.tile(3).width, 256);
}

TEST(TileGrid, RejectsBadSizes) {
  expect_usage([] { TileGrid(0, 10, 4); }, {"image size"});
  expect_usage([] { TileGrid(10, -1, 4); }, {"image size"});
  expect_usage([] { TileGrid(std::int64_t(1) << 31, 10, 4); }, {"out of range"});
  expect_usage([] { TileGrid(10, 10, 0); }, {"tile size"});
  TileGrid g(64, 64, 8);
  expect_usage([&] { g.tile(64); }, {"tile 64", "8x8", "0-63"});
  expect_usage([&] { g.tile(-1); }, {"tile -1"});
}

// Issue #12: a huge image in tiny tiles is refused as Error(Limit) when the grid is built, before any
// per-tile list (selection, manifest, names) is allocated; the message says which tile size fits.
TEST(TileGrid, CapsTheTileCountBeforeAllocating) {
  TileGrid at_cap(131072, 131072, 64);  // 2048 x 2048 tiles: exactly the cap
  EXPECT_EQ(at_cap.count(), TileGrid::kMaxTiles);
  EXPECT_EQ(select_tiles(at_cap, {}, [](const std::string&) { return std::optional<std::string>(); })
                .tiles.size(),
            std::size_t(TileGrid::kMaxTiles));
  auto expect_limit = [](std::int64_t w, std::int64_t h, std::int64_t t, const std::string& fit) {
    try {
      TileGrid g(w, h, t);
      ADD_FAILURE() << "no error for " << w << "x" << h << " in tiles of " << t;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Limit) << e.what();
      EXPECT_NE(std::string(e.what()).find("more than the limit of 4194304"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("--tile-size " + fit + " or larger"), std::string::npos) << e.what();
    }
  };
  expect_limit(131072, 131072, 63, "64");  // 2081^2 tiles
  expect_limit(131073, 131072, 64, "65");  // one pixel more: 2049 x 2048
  const std::int64_t max = (std::int64_t(1) << 31) - 1;
  expect_limit(max, max, 1, "1048576");        // ~2^62 tiles would be 32 EiB of indices
  expect_limit(max, max, 1048575, "1048576");  // 2049 x 2049
  EXPECT_EQ(TileGrid(max, max, 1048576).count(), 2048 * 2048);
}

TEST(TileSpec, ValidSpecs) {
  TileGrid g(64, 64, 8);  // 64 tiles
  EXPECT_EQ(parse_tile_spec("0-15", g).size(), 16u);
  EXPECT_EQ(parse_tile_spec("0-15", g).back(), 15);
  EXPECT_EQ(parse_tile_spec("3,7,9-12", g), (V{3, 7, 9, 10, 11, 12}));
  EXPECT_EQ(parse_tile_spec("1-10x2", g), (V{1, 3, 5, 7, 9}));
  EXPECT_EQ(parse_tile_spec("1-10:2", g), (V{1, 3, 5, 7, 9}));
  EXPECT_EQ(parse_tile_spec("1-10X3", g), (V{1, 4, 7, 10}));
  EXPECT_EQ(parse_tile_spec(" 3 , 7 ,9 - 12 ", g), (V{3, 7, 9, 10, 11, 12}));
  EXPECT_EQ(parse_tile_spec("\t1 - 10 : 4\n", g), (V{1, 5, 9}));
  EXPECT_EQ(parse_tile_spec("12,3,3,1-4", g), (V{1, 2, 3, 4, 12}));  // sorted, duplicates merged
  EXPECT_EQ(parse_tile_spec("63", g), (V{63}));
  EXPECT_EQ(parse_tile_spec("5-5", g), (V{5}));
  EXPECT_EQ(parse_tile_spec("all", g).size(), 64u);
  // Huge steps and leading zeros do not overflow.
  EXPECT_EQ(parse_tile_spec("0-63x9223372036854775807", g), (V{0}));
  EXPECT_EQ(parse_tile_spec("0-63:60", g), (V{0, 60}));
  EXPECT_EQ(parse_tile_spec("007", g), (V{7}));
}

TEST(TileSpec, InvalidSpecsNameTheItem) {
  TileGrid g(64, 64, 8);
  auto bad = [&](const std::string& spec, std::vector<std::string> needles) {
    SCOPED_TRACE(spec);
    expect_usage([&] { parse_tile_spec(spec, g); }, needles);
  };
  bad("", {"empty"});
  bad("   ", {"empty"});
  bad(",", {"empty item"});
  bad("3,", {"empty item"});
  bad(",3", {"empty item"});
  bad("3,,4", {"empty item"});
  bad("a", {"item 'a'"});
  bad("3,x7", {"item 'x7'"});
  bad("3-", {"item '3-'", "end of the range"});
  bad("-3", {"item '-3'", "sign"});
  bad("+3", {"item '+3'", "sign"});
  bad("12-9", {"item '12-9'", "descending"});
  bad("1-10x0", {"item '1-10x0'", "step"});
  bad("1-10x", {"item '1-10x'", "step"});
  bad("1-10y2", {"item '1-10y2'", "unexpected"});
  bad("1 2", {"item '1 2'", "unexpected"});
  bad("3x2", {"item '3x2'", "unexpected"});
  bad("1.5", {"item '1.5'"});
  bad("0-15,all", {"item 'all'"});
  bad("99999999999999999999", {"too large"});
  bad("3-99999999999999999999", {"too large"});
  bad("1-10x99999999999999999999", {"too large"});
  bad("64", {"tile 64", "out of range", "8x8", "0-63"});
  bad("60-70", {"item '60-70'", "tile 70", "8x8"});
  bad("9223372036854775807", {"out of range", "0-63"});
}

TEST(TileSelection, ExplicitOptions) {
  TileGrid g(64, 64, 8);
  auto env = fake_env({{"SLURM_ARRAY_TASK_ID", "9"}});
  TileSelectionRequest r;
  r.tiles = "1,2";
  TileSelection s = select_tiles(g, r, env);
  EXPECT_EQ(s.tiles, (V{1, 2}));  // --tiles wins over the environment
  EXPECT_FALSE(s.task_index);
  r = {};
  r.tile_index = 17;
  EXPECT_EQ(select_tiles(g, r, env).tiles, (V{17}));
  r = {};
  r.task_index = 4;
  r.tiles_per_task = 3;
  s = select_tiles(g, r, env);
  EXPECT_EQ(s.tiles, (V{12, 13, 14}));
  EXPECT_EQ(*s.task_index, 4);
  r = {};
  r.tile_index = 64;
  expect_usage([&] { select_tiles(g, r, env); }, {"tile 64", "8x8"});
  r = {};
  r.tiles = "1";
  r.tile_index = 2;
  expect_usage([&] { select_tiles(g, r, env); }, {"at most one"});
  r = {};
  r.tiles = "1";
  r.tiles_per_task = 2;
  expect_usage([&] { select_tiles(g, r, env); }, {"--tiles-per-task"});
  r = {};
  r.tiles_per_task = 0;
  expect_usage([&] { select_tiles(g, r, env); }, {"at least 1"});
}

TEST(TileSelection, SchedulerEnvironmentPrecedence) {
  TileGrid g(64, 64, 8);
  TileSelectionRequest r;
  // Slurm first, then Kubernetes.
  TileSelection s =
      select_tiles(g, r, fake_env({{"SLURM_ARRAY_TASK_ID", "3"}, {"JOB_COMPLETION_INDEX", "5"}}));
  EXPECT_EQ(s.tiles, (V{3}));
  EXPECT_EQ(s.source, "SLURM_ARRAY_TASK_ID=3");
  s = select_tiles(g, r, fake_env({{"JOB_COMPLETION_INDEX", "5"}}));
  EXPECT_EQ(s.tiles, (V{5}));
  EXPECT_EQ(s.source, "JOB_COMPLETION_INDEX=5");
  // Empty variables count as unset.
  s = select_tiles(g, r, fake_env({{"SLURM_ARRAY_TASK_ID", ""}, {"JOB_COMPLETION_INDEX", "6"}}));
  EXPECT_EQ(s.tiles, (V{6}));
  // Nothing: every tile.
  s = select_tiles(g, r, fake_env({}));
  EXPECT_EQ(s.tiles.size(), 64u);
  EXPECT_TRUE(s.all);
  // --task-index beats the environment.
  r.task_index = 2;
  EXPECT_EQ(select_tiles(g, r, fake_env({{"SLURM_ARRAY_TASK_ID", "3"}})).tiles, (V{2}));
  // Whitespace around the value is tolerated; anything else is not.
  r = {};
  EXPECT_EQ(select_tiles(g, r, fake_env({{"SLURM_ARRAY_TASK_ID", " 7\n"}})).tiles, (V{7}));
  expect_usage(
      [&] {
        select_tiles(g, r, fake_env({{"SLURM_ARRAY_TASK_ID", "abc"}}));
      },
      {"SLURM_ARRAY_TASK_ID", "abc"});
  expect_usage(
      [&] {
        select_tiles(g, r, fake_env({{"JOB_COMPLETION_INDEX", "-1"}}));
      },
      {"JOB_COMPLETION_INDEX"});
  expect_usage(
      [&] {
        select_tiles(g, r, fake_env({{"SLURM_ARRAY_TASK_ID", "99999999999999999999"}}));
      },
      {"SLURM_ARRAY_TASK_ID"});
  expect_usage(
      [&] {
        select_tiles(g, r, fake_env({{"SLURM_ARRAY_TASK_ID", "64"}}));
      },
      {"task 64", "SLURM_ARRAY_TASK_ID", "tasks 0-63"});
}

TEST(TileSelection, TilesPerTaskChunks) {
  TileGrid g(100, 20, 10);  // 10x2 = 20 tiles
  TileSelectionRequest r;
  r.tiles_per_task = 6;  // tasks 0-3, the last one ragged
  EXPECT_EQ(task_count(g, 6), 4);
  std::vector<std::int64_t> seen;
  for (int task = 0; task < 4; ++task) {
    auto s = select_tiles(g, r, fake_env({{"SLURM_ARRAY_TASK_ID", std::to_string(task)}}));
    EXPECT_EQ(s.tiles.front(), task * 6);
    EXPECT_EQ(s.tiles.size(), task == 3 ? 2u : 6u);
    seen.insert(seen.end(), s.tiles.begin(), s.tiles.end());
  }
  ASSERT_EQ(seen.size(), 20u);  // every tile exactly once over all tasks
  for (int i = 0; i < 20; ++i) EXPECT_EQ(seen[i], i);
  expect_usage(
      [&] {
        select_tiles(g, r, fake_env({{"JOB_COMPLETION_INDEX", "4"}}));
      },
      {"task 4", "tasks 0-3"});
  // A huge chunk: one task holds everything, no overflow.
  r.tiles_per_task = std::int64_t(1) << 62;
  EXPECT_EQ(select_tiles(g, r, fake_env({{"SLURM_ARRAY_TASK_ID", "0"}})).tiles.size(), 20u);
  expect_usage([&] { select_tiles(g, r, fake_env({{"SLURM_ARRAY_TASK_ID", "1"}})); }, {"task 1"});
}

TEST(TileSelection, FormatIndexList) {
  EXPECT_EQ(format_index_list({}), "");
  EXPECT_EQ(format_index_list({4}), "4");
  EXPECT_EQ(format_index_list({0, 1, 2, 3, 7, 9, 10, 11, 12}), "0-3,7,9-12");
  TileGrid g(64, 64, 8);
  EXPECT_EQ(parse_tile_spec(format_index_list({0, 1, 2, 3, 7, 9, 10}), g), (V{0, 1, 2, 3, 7, 9, 10}));
}
