// Output name templates: placeholders, padding, UDIM, literal braces, and the errors for unknown or
// ambiguous templates.
#include <gtest/gtest.h>

#include <set>

#include "core/error.h"
#include "farm/name_template.h"

using namespace stex;
using namespace stex::farm;

namespace {

template <class F>
void expect_usage(F&& f, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage) << e.what();
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what() << " lacks " << needle;
  }
}

}  // namespace

TEST(NameTemplate, Placeholders) {
  TileGrid g(1000, 1000, 100);  // 10x10
  TileRect t = g.tile(3, 2);    // index 23
  EXPECT_EQ(NameTemplate("out/gravel_{tx}_{ty}.exr").format(t), "out/gravel_3_2.exr");
  EXPECT_EQ(NameTemplate("t{index}.exr").format(t), "t23.exr");
  EXPECT_EQ(NameTemplate("t_{tx:03}_{ty:02}.tif").format(t), "t_003_02.tif");
  EXPECT_EQ(NameTemplate("t_{index:05}.png").format(t), "t_00023.png");
  EXPECT_EQ(NameTemplate("tex.<UDIM>.exr").format(t), "tex.1024.exr");  // 1001 + 3 + 10*2
  EXPECT_EQ(NameTemplate("{{x}}_{index}_}}.exr").format(t), "{x}_23_}.exr");
  EXPECT_EQ(NameTemplate("a<b.exr").format(t), "a<b.exr");  // not a tag: kept literally
  EXPECT_EQ(NameTemplate("{tx:02}").format(g.tile(123 % 100)), "03");
  TileGrid wide(200000, 1, 1);
  EXPECT_EQ(NameTemplate("{tx:03}").format(wide.tile(123456)), "123456");  // padding is a minimum
}

TEST(NameTemplate, DetectsSingleImage) {
  EXPECT_FALSE(NameTemplate("out/big.exr").has_placeholders());
  EXPECT_FALSE(NameTemplate("out/{{literal}}.exr").has_placeholders());
  EXPECT_TRUE(NameTemplate("out/{tx}_{ty}.exr").has_placeholders());
  EXPECT_TRUE(NameTemplate("out/{index}.exr").has_placeholders());
  EXPECT_TRUE(NameTemplate("out/t.<UDIM>.exr").has_placeholders());
  EXPECT_TRUE(NameTemplate("out/t.<UDIM>.exr").uses_udim());
}

TEST(NameTemplate, Udim) {
  EXPECT_EQ(udim_number(0, 0), 1001);
  EXPECT_EQ(udim_number(9, 0), 1010);
  EXPECT_EQ(udim_number(0, 1), 1011);
  EXPECT_EQ(udim_number(9, 9), 1100);
  expect_usage([] { udim_number(10, 0); }, "u < 10");
  expect_usage([] { udim_number(-1, 0); }, "u < 10");
  NameTemplate udim("t.<UDIM>.exr");
  TileGrid eleven(1100, 100, 100);
  expect_usage([&] { udim.check_grid(eleven); }, "at most 10 tiles per row");
  expect_usage([&] { udim.format(eleven.tile(10)); }, "u < 10");
  TileGrid ten(1000, 300, 100);
  udim.check_grid(ten);
  std::set<std::string> names;
  for (std::int64_t i = 0; i < ten.count(); ++i) names.insert(udim.format(ten.tile(i)));
  EXPECT_EQ(names.size(), 30u);
  EXPECT_EQ(*names.begin(), "t.1001.exr");
  EXPECT_EQ(*names.rbegin(), "t.1030.exr");
}

TEST(NameTemplate, RejectsUnknownAndMalformed) {
  expect_usage([] { NameTemplate("out/{x}.exr"); }, "'{x}'");
  expect_usage([] { NameTemplate("out/{tile}.exr"); }, "'{tile}'");
  expect_usage([] { NameTemplate("out/{TX}.exr"); }, "'{TX}'");
  expect_usage([] { NameTemplate("out/{}.exr"); }, "'{}'");
  expect_usage([] { NameTemplate("out/<UVTILE>.exr"); }, "'<UVTILE>'");
  expect_usage([] { NameTemplate("out/<udim>.exr"); }, "'<udim>'");
  expect_usage([] { NameTemplate("out/{tx:3}.exr"); }, "padding");
  expect_usage([] { NameTemplate("out/{tx:00}.exr"); }, "padding");
  expect_usage([] { NameTemplate("out/{tx:021}.exr"); }, "padding");
  expect_usage([] { NameTemplate("out/{tx:0x}.exr"); }, "padding");
  expect_usage([] { NameTemplate("out/{tx.exr"); }, "unmatched '{'");
  expect_usage([] { NameTemplate("out/tx}.exr"); }, "unmatched '}'");
  expect_usage([] { NameTemplate(""); }, "empty");
}

TEST(NameTemplate, MustNameEveryTileDistinctly) {
  TileGrid grid(400, 300, 100);  // 4x3
  expect_usage([&] { NameTemplate("{tx}.exr").check_grid(grid); }, "same name");
  expect_usage([&] { NameTemplate("{ty}.exr").check_grid(grid); }, "same name");
  NameTemplate("{tx}_{ty}.exr").check_grid(grid);
  NameTemplate("{index}.exr").check_grid(grid);
  NameTemplate("{tx}.exr").check_grid(TileGrid(400, 100, 100));  // one row: {tx} suffices
  NameTemplate("{ty}.exr").check_grid(TileGrid(100, 400, 100));  // one column: {ty} suffices
  std::set<std::string> names;
  NameTemplate t("{tx:02}-{ty}.exr");
  for (std::int64_t i = 0; i < grid.count(); ++i) names.insert(t.format(grid.tile(i)));
  EXPECT_EQ(names.size(), std::size_t(grid.count()));
}
