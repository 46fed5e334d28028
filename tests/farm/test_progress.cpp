// Progress output: the bar (terminal), flushed lines (logs), OpenJD's progress protocol, durations.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "core/error.h"
#include "farm/progress.h"

using namespace stex;
using namespace stex::farm;

namespace {

std::string read_all(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string s;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof buf, f)) s.append(buf, n);
  return s;
}

}  // namespace

TEST(Progress, ModesParse) {
  EXPECT_EQ(parse_progress_mode("auto"), ProgressMode::Auto);
  EXPECT_EQ(parse_progress_mode("bar"), ProgressMode::Bar);
  EXPECT_EQ(parse_progress_mode("lines"), ProgressMode::Lines);
  EXPECT_EQ(parse_progress_mode("openjd"), ProgressMode::OpenJD);
  EXPECT_EQ(parse_progress_mode("none"), ProgressMode::None);
  EXPECT_THROW(parse_progress_mode("fancy"), Error);
}

TEST(Progress, AutoIsLinesOffATerminal) {
  std::FILE* err = std::tmpfile();
  std::FILE* out = std::tmpfile();
  Progress p(ProgressMode::Auto, 2, err, out);
  EXPECT_EQ(p.mode(), ProgressMode::Lines);
  p.tile_finished(0, "a.exr", true);
  p.tile_finished(1, "b.exr", false);
  p.finish();
  std::string e = read_all(err);
  EXPECT_NE(e.find("stex: tile 0 skipped (1/2, 50.0%"), std::string::npos) << e;
  EXPECT_NE(e.find("stex: tile 1 done (2/2, 100.0%, ETA 0 s): b.exr\n"), std::string::npos) << e;
  EXPECT_EQ(read_all(out), "");
  std::fclose(err);
  std::fclose(out);
}

TEST(Progress, BarRedrawsOneLine) {
  std::FILE* err = std::tmpfile();
  std::FILE* out = std::tmpfile();
  Progress p(ProgressMode::Bar, 4, err, out);
  for (int i = 0; i < 4; ++i) p.tile_finished(i, "x", false);
  p.finish();
  std::string e = read_all(err);
  EXPECT_NE(e.find("\r[#######.......................] 1/4 tiles  25.0%  ETA "), std::string::npos) << e;
  EXPECT_NE(e.find("\r[##############################] 4/4 tiles 100.0%  ETA 0 s"), std::string::npos) << e;
  EXPECT_EQ(e.back(), '\n');
  EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 1);
  std::fclose(err);
  std::fclose(out);
}

TEST(Progress, OpenJDLinesOnStdout) {
  std::FILE* err = std::tmpfile();
  std::FILE* out = std::tmpfile();
  Progress p(ProgressMode::OpenJD, 3, err, out);
  for (int i = 0; i < 3; ++i) p.tile_finished(i, "x", i == 0);
  std::string o = read_all(out);
  EXPECT_EQ(o.find("openjd_progress: 0\n"), 0u) << o;
  EXPECT_NE(o.find("openjd_status: tile 0 skipped (1/3)\nopenjd_progress: 33.33\n"), std::string::npos) << o;
  EXPECT_NE(o.find("openjd_progress: 100.00\n"), std::string::npos) << o;
  EXPECT_EQ(read_all(err), "");
  std::fclose(err);
  std::fclose(out);
}

TEST(Progress, Durations) {
  EXPECT_EQ(format_duration(0), "0 s");
  EXPECT_EQ(format_duration(42.4), "42 s");
  EXPECT_EQ(format_duration(125), "2:05");
  EXPECT_EQ(format_duration(3723), "1:02:03");
  EXPECT_EQ(format_duration(-1), "?");
}
