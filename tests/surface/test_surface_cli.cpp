// `stex surface`: the real binary on a real model and mesh; outputs, and exit codes for bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "analysis/mesh.h"
#include "model/codecs.h"
#include "kernels/test_texton_common.h"
#include "cli_run.h"

namespace stex {
namespace {

namespace fs = std::filesystem;

struct RunResult {
  int exit_code = -1;
  std::string err;
};

fs::path dir_for(const std::string& name) {
  const fs::path d = fs::path(STEX_TEST_TMP_DIR) / ("surface_cli_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

RunResult run_stex(const fs::path& dir, const std::string& args) {
  const stex::test::CliRun c = stex::test::run_stex_cli(args, fs::relative(dir, STEX_TEST_TMP_DIR).string() + "/run");
  return {c.code, c.err};
}

void write_quad_obj(const fs::path& p) {
  std::ofstream out(p);
  out << "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n";
}

TEST(SurfaceCli, VertexColoursBakeAndPreview) {
  const fs::path d = dir_for("ok");
  save_model(test::synthetic_model(3, 8, 1, 3), (d / "m.stex").string());
  write_quad_obj(d / "quad.obj");
  const RunResult r = run_stex(d, "surface '" + (d / "m.stex").string() + "' --mesh '" + (d / "quad.obj").string() +
                                      "' -o '" + (d / "out.ply").string() + "' --bake '" + (d / "tex.png").string() +
                                      "' --bake-size 64x64 --preview '" + (d / "view.png").string() +
                                      "' --preview-size 48x32 --texel 0.05 --mni 20");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Mesh back = load_mesh((d / "out.ply").string());
  EXPECT_EQ(back.vertex_count(), 4u);
  EXPECT_TRUE(fs::exists(d / "tex.png"));
  EXPECT_TRUE(fs::exists(d / "view.png"));
}

TEST(SurfaceCli, BadInputExitCodes) {
  const fs::path d = dir_for("bad");
  save_model(test::synthetic_model(1, 4, 1, 3), (d / "m.stex").string());
  write_quad_obj(d / "quad.obj");
  {
    std::ofstream out(d / "bad.ply", std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\nend_header\n";
  }
  const std::string m = "'" + (d / "m.stex").string() + "'";
  // Usage (2): nothing to write, wrong output extension, bad size.
  EXPECT_EQ(run_stex(d, "surface " + m + " --mesh '" + (d / "quad.obj").string() + "'").exit_code, 2);
  EXPECT_EQ(run_stex(d, "surface " + m + " --mesh '" + (d / "quad.obj").string() + "' -o x.obj").exit_code, 2);
  EXPECT_EQ(run_stex(d, "surface " + m + " --mesh '" + (d / "quad.obj").string() + "' --bake t.png --bake-size 0x5")
                .exit_code,
            2);
  // Input (3): missing mesh, truncated PLY, a model file that is not one.
  const RunResult missing = run_stex(d, "surface " + m + " --mesh '" + (d / "nope.ply").string() + "' -o a.ply");
  EXPECT_EQ(missing.exit_code, 3);
  EXPECT_NE(missing.err.find("nope.ply"), std::string::npos) << missing.err;
  EXPECT_EQ(run_stex(d, "surface " + m + " --mesh '" + (d / "bad.ply").string() + "' -o '" +
                            (d / "a.ply").string() + "'")
                .exit_code,
            3);
  EXPECT_EQ(run_stex(d, "surface '" + (d / "quad.obj").string() + "' --mesh '" + (d / "quad.obj").string() +
                            "' -o '" + (d / "a.ply").string() + "'")
                .exit_code,
            3);
  EXPECT_FALSE(fs::exists(d / "a.ply"));
}

}  // namespace
}  // namespace stex
