// `stex render` run as a subprocess (the real binary, STEX_CLI_PATH) on real files: EXR output equals the
// C++ reference (runtime/reference.h) bit for bit and carries its provenance metadata; PNG 8/16-bit outputs
// are the clamped, quantised reference; strategies give identical files; linear models write linear EXR and
// sRGB-encoded PNG; the adsn/dsn comparison modes; and bad input - each with its documented exit code
// (core/error.h, README "Exit codes"), a message naming the problem, and no output file (nor temp file).
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/image_io.h"
#include "model/codecs.h"
#include "cli/bad_exemplars.h"
#include "kernels/test_texton_common.h"
#include "model/loaded_model.h"
#include "runtime/gabor_params.h"
#include "runtime/reference.h"
#include "runtime/texton_filter.h"
#include "sanitizer.h"
#include "cli_run.h"

namespace stex {
namespace {

namespace fs = std::filesystem;

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

std::string read_text(const fs::path& p) { return stex::test::slurp_file(p); }

fs::path tmp_dir(const std::string& name) {
  const fs::path dir = fs::path(STEX_TEST_TMP_DIR) / ("render_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Runs `env <env_args> stex <args>` (env_args: `env` operands such as VAR=value; empty: the test's environment).
RunResult run_stex_env(const std::string& env_args, const std::string& args) {
  const stex::test::CliRun c =
      stex::test::run_stex_cli(args, "render_subprocess", "", env_args.empty() ? "" : "env " + env_args);
  return {c.code, c.out, c.err};
}

RunResult run_stex(const std::string& args) { return run_stex_env("", args); }

struct Read {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;
  OIIO::ImageSpec spec;
};

Read read_image(const fs::path& p) {
  Read r;
  auto in = OIIO::ImageInput::open(p.string());
  if (!in) {
    ADD_FAILURE() << "cannot open " << p;
    return r;
  }
  r.spec = in->spec();
  r.width = r.spec.width;
  r.height = r.spec.height;
  r.channels = r.spec.nchannels;
  r.pixels.resize(std::size_t(r.width) * r.height * r.channels);
  EXPECT_TRUE(in->read_image(0, 0, 0, r.channels, OIIO::TypeDesc::FLOAT, r.pixels.data()));
  return r;
}

std::size_t files_in(const fs::path& dir) {
  std::size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    (void)e;
    ++n;
  }
  return n;
}

// A model saved with save_model (synthetic alpha from the counter RNG; no analysis involved).
fs::path save_synthetic(const fs::path& dir, int channels, bool linear = false) {
  TextonModel m = test::synthetic_model(channels, 16, 1, 61, 0.01f);
  m.linear = linear;
  m.exemplar_name = "none.png";
  m.stex_version = STEX_VERSION_STRING;
  const fs::path p = dir / (std::to_string(channels) + (linear ? "ch_linear.stex" : "ch.stex"));
  save_model(m, p.string());
  return p;
}

TEST(RenderCli, ExrEqualsTheReferenceAndCarriesProvenance) {
  const fs::path dir = tmp_dir("exr");
  const fs::path model = save_synthetic(dir, 3);
  const fs::path out = dir / "out.exr";
  RunResult r = run_stex("render '" + model.string() + "' -o '" + out.string() +
                         "' --size 70x45 --origin -1000000000000,12 --scale 1.5 --mni 20 --seed 987654321 --cell 0.7");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("rendered 70x45 at (-1000000000000, 12)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("strategy splat"), std::string::npos) << r.out;  // auto on a CPU device
  EXPECT_NE(r.out.find("device "), std::string::npos);
  EXPECT_NE(r.out.find(" ms, wall "), std::string::npos);

  const Read img = read_image(out);
  ASSERT_EQ(img.width, 70);
  ASSERT_EQ(img.height, 45);
  ASSERT_EQ(img.channels, 3);
  RenderParams p;
  p.mni = 20;
  p.seed = 987654321;
  p.scale = 1.5;
  p.cell_factor = 0.7;
  const TextonReference reference(load_model(model.string()), p);
  EXPECT_EQ(test::count_bit_differences(img.pixels, reference.render(-1000000000000ll, 12, 70, 45)), 0u);

  EXPECT_EQ(img.spec.get_string_attribute("stex:seed"), "987654321");
  EXPECT_EQ(img.spec.get_string_attribute("stex:mni"), "20");
  EXPECT_EQ(img.spec.get_string_attribute("stex:origin"), "-1000000000000,12");
  EXPECT_EQ(img.spec.get_string_attribute("stex:scale"), "1.5");
  EXPECT_EQ(img.spec.get_string_attribute("stex:version"), STEX_VERSION_STRING);
  EXPECT_EQ(img.spec.get_string_attribute("stex:model_sha256"), sha256_file_hex(model.string()));

  // The gather strategy writes the same pixels.
  const fs::path out2 = dir / "gather.exr";
  r = run_stex("render '" + model.string() + "' -o '" + out2.string() +
               "' --size 70x45 --origin -1000000000000,12 --scale 1.5 --mni 20 --seed 987654321 --cell 0.7 "
               "--strategy gather");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("strategy gather"), std::string::npos) << r.out;
  EXPECT_EQ(test::count_bit_differences(read_image(out2).pixels, img.pixels), 0u);
}

// PNG and TIFF, 8 and 16 bits: the reference clamped to [0, 1] and quantised, and the clamp is reported.
// The model's alpha is the synthetic one times 40 around mean 0.5: the noise's standard deviation is then
// well above 0.5, so a fair share of the 2048 values lies on each side of [0, 1] (asserted, so that the
// message check below always runs).
TEST(RenderCli, PngIsTheClampedQuantisedReference) {
  const fs::path dir = tmp_dir("png");
  TextonModel m = test::synthetic_model(1, 16, 1, 61, 0.01f);
  for (float& a : m.alpha) a *= 40.0f;
  m.mean[0] = 0.5f;
  m.exemplar_name = "none.png";
  m.stex_version = STEX_VERSION_STRING;
  const fs::path model = dir / "loud.stex";
  save_model(m, model.string());
  RenderParams p;
  p.seed = 3;
  const std::vector<float> ref = TextonReference(load_model(model.string()), p).render(0, 0, 64, 32);
  std::size_t below = 0, above = 0;
  for (float v : ref) {
    below += v < 0.0f ? 1 : 0;
    above += v > 1.0f ? 1 : 0;
  }
  ASSERT_GT(below, ref.size() / 20) << "the test model must reach below 0";
  ASSERT_GT(above, ref.size() / 20) << "the test model must reach above 1";
  const std::size_t outside = below + above;
  for (const std::string ext : {"png", "tif"})
    for (int bits : {8, 16}) {
      SCOPED_TRACE(ext + " " + std::to_string(bits) + "-bit");
      const fs::path out = dir / ("out" + std::to_string(bits) + "." + ext);
      RunResult r = run_stex("render '" + model.string() + "' -o '" + out.string() +
                             "' --size 64x32 --seed 3 --bits " + std::to_string(bits));
      ASSERT_EQ(r.exit_code, 0) << r.err;
      const Read img = read_image(out);
      ASSERT_EQ(img.pixels.size(), ref.size());
      EXPECT_EQ(img.spec.format, bits == 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16);
      const double q = bits == 8 ? 255.0 : 65535.0;
      for (std::size_t i = 0; i < ref.size(); ++i)
        ASSERT_NEAR(img.pixels[i], std::min(1.0f, std::max(0.0f, ref[i])), 0.5 / q + 1e-7) << i;
      EXPECT_NE(r.out.find("note: " + std::to_string(outside) + " of " + std::to_string(ref.size()) +
                           " values were outside [0, 1] and clamped for the " + std::to_string(bits) + "-bit"),
                std::string::npos)
          << r.out;
    }
}

TEST(RenderCli, LinearModelsWriteLinearExrAndSrgbPng) {
  const fs::path dir = tmp_dir("linear");
  const fs::path model = save_synthetic(dir, 1, true);
  const std::vector<float> ref = TextonReference(load_model(model.string()), RenderParams{}).render(0, 0, 40, 20);
  ASSERT_EQ(run_stex("render '" + model.string() + "' -o '" + (dir / "l.exr").string() + "' --size 40x20").exit_code, 0);
  ASSERT_EQ(run_stex("render '" + model.string() + "' -o '" + (dir / "l.png").string() + "' --size 40x20").exit_code, 0);
  EXPECT_EQ(test::count_bit_differences(read_image(dir / "l.exr").pixels, ref), 0u);
  const Read png = read_image(dir / "l.png");
  for (std::size_t i = 0; i < ref.size(); ++i)
    ASSERT_NEAR(png.pixels[i], std::min(1.0f, std::max(0.0f, linear_to_srgb(ref[i]))), 0.5 / 255 + 1e-6) << i;
}

TEST(RenderCli, ComparisonModes) {
  const fs::path dir = tmp_dir("modes");
  // A small exemplar, analysed by the real CLI: the model names it, and it sits beside the model.
  Image ex;
  ex.width = ex.height = 48;
  ex.channels = 3;
  ex.pixels.resize(48 * 48 * 3);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 48; ++x)
      for (int c = 0; c < 3; ++c) {
        const stex_uvec4 v = stex_draw(stex_cell_key(x, y), 1, 0, std::uint32_t(c), STEX_DOMAIN_TEST);
        ex.at(x, y, c) = 0.3f + 0.4f * stex_uniform24(v.x) * (0.6f + 0.4f * std::sin(0.5f * float(x + c)));
      }
  write_image_atomic((dir / "ex.png").string(), ex);
  const fs::path model = dir / "ex.stex";
  RunResult r = run_stex("analyze '" + (dir / "ex.png").string() + "' -o '" + model.string() +
                         "' --support 8 --iterations 5");
  ASSERT_EQ(r.exit_code, 0) << r.err;

  r = run_stex("render '" + model.string() + "' -o '" + (dir / "adsn.exr").string() + "' --size 100x60 --mode adsn");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_image(dir / "adsn.exr").channels, 3);
  r = run_stex("render '" + model.string() + "' -o '" + (dir / "dsn.exr").string() + "' --size 100x60 --mode dsn");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_image(dir / "dsn.exr").width, 100);

  // The exemplar is needed for ADSN: moved away -> Input error naming it; --exemplar fixes it.
  fs::create_directories(dir / "elsewhere");
  fs::rename(dir / "ex.png", dir / "elsewhere" / "ex.png");
  const fs::path missing_out = dir / "adsn2.exr";
  r = run_stex("render '" + model.string() + "' -o '" + missing_out.string() + "' --size 100x60 --mode adsn");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("ex.png"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--exemplar"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(missing_out));
  r = run_stex("render '" + model.string() + "' -o '" + missing_out.string() + "' --size 100x60 --mode adsn --exemplar '" +
               (dir / "elsewhere" / "ex.png").string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// --scale < 1 filters a texton model of order 1 by default (S1 §5: the filtered reference's pixels, as with
// --filter); --no-filter point-samples it, with a warning that it aliases.
TEST(RenderCli, ScaleBelowOneFiltersByDefault) {
  const fs::path dir = tmp_dir("warn");
  const fs::path model = save_synthetic(dir, 1);
  const fs::path out = dir / "o.exr", explicit_out = dir / "e.exr", point = dir / "p.exr";
  RunResult r = run_stex("render '" + model.string() + "' -o '" + out.string() + "' --size 32x32 --scale 0.5");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("aliases"), std::string::npos) << r.err;
  EXPECT_EQ(read_image(out).spec.get_string_attribute("stex:filter"), "box-prefilter");
  r = run_stex("render '" + model.string() + "' -o '" + explicit_out.string() + "' --size 32x32 --scale 0.5 --filter");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(test::count_bit_differences(read_image(out).pixels, read_image(explicit_out).pixels), 0u);
  r = run_stex("render '" + model.string() + "' -o '" + point.string() + "' --size 32x32 --scale 0.5 --no-filter");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("--no-filter point-samples the texton: the render aliases"), std::string::npos) << r.err;
  EXPECT_EQ(read_image(point).spec.get_string_attribute("stex:filter"), "none");
  EXPECT_GT(test::count_bit_differences(read_image(out).pixels, read_image(point).pixels), 0u);
  // Where nothing is filtered by default, --no-filter is a usage error.
  r = run_stex("render '" + model.string() + "' -o '" + (dir / "n.exr").string() + "' --size 32x32 --no-filter");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--no-filter applies where stex filters by default"), std::string::npos) << r.err;
}

// S1 §5: --filter and --camera write the filtered reference's pixels; bad uses exit 2 naming the problem.
TEST(RenderCli, FilterAndCamera) {
  const fs::path dir = tmp_dir("filter");
  const fs::path model = save_synthetic(dir, 3);
  const fs::path out = dir / "f.exr";
  RunResult r = run_stex("render '" + model.string() + "' -o '" + out.string() +
                         "' --size 40x24 --origin 5,-3 --scale 0.2 --filter --seed 11");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("aliases"), std::string::npos) << r.err;
  RenderParams p;
  p.seed = 11;
  p.scale = 0.2;
  const FilteredTextonReference ref(load_model(model.string()), p);
  const Read img = read_image(out);
  EXPECT_EQ(test::count_bit_differences(img.pixels, ref.render_scaled(5, -3, 40, 24)), 0u);
  EXPECT_EQ(img.spec.get_string_attribute("stex:filter"), "box-prefilter");

  const fs::path cam = dir / "c.exr";
  r = run_stex("render '" + model.string() + "' -o '" + cam.string() + "' --size 48x32 --camera 50,70,60 --seed 11");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  RenderParams unit;
  unit.seed = 11;
  const FilteredTextonReference cref(load_model(model.string()), unit);
  EXPECT_EQ(test::count_bit_differences(read_image(cam).pixels,
                                        cref.render_camera(parse_camera("50,70,60", 48, 32), 0, 0, 48, 32)),
            0u);

  for (const std::string& bad : {std::string("--camera 50,70"), std::string("--camera 50,95,60"),
                                 std::string("--camera -1,70,60"), std::string("--scale 2 --no-filter")}) {
    r = run_stex("render '" + model.string() + "' -o '" + (dir / "bad.exr").string() + "' --size 16x16 " + bad);
    EXPECT_EQ(r.exit_code, 2) << bad << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir / "bad.exr")) << bad;
  }
}

// A filtered render and a camera view in farm tiles (--tile-size): every tile is the filtered reference's
// window, bit for bit, so the tiles join into the single image (ragged last row and column included).
TEST(RenderCli, FilteredAndCameraTilesJoinBitForBit) {
  const fs::path dir = tmp_dir("filter_tiles");
  const fs::path model = save_synthetic(dir, 3);
  RenderParams p;
  p.seed = 11;
  p.scale = 0.2;
  const FilteredTextonReference ref(load_model(model.string()), p);
  RunResult r = run_stex("render '" + model.string() + "' -o '" + (dir / "f_{tx}_{ty}.exr").string() +
                         "' --size 40x24 --origin 5,-3 --scale 0.2 --filter --seed 11 --tile-size 16");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  RenderParams unit;
  unit.seed = 11;
  const FilteredTextonReference cref(load_model(model.string()), unit);
  RunResult c = run_stex("render '" + model.string() + "' -o '" + (dir / "c_{tx}_{ty}.exr").string() +
                         "' --size 48x32 --camera 50,70,60 --seed 11 --tile-size 20");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const PerspectiveCamera cam = parse_camera("50,70,60", 48, 32);
  for (int ty = 0; ty < 2; ++ty)
    for (int tx = 0; tx < 3; ++tx) {
      const int w = std::min(16, 40 - 16 * tx), h = std::min(16, 24 - 16 * ty);
      const Read img = read_image(dir / ("f_" + std::to_string(tx) + "_" + std::to_string(ty) + ".exr"));
      EXPECT_EQ(test::count_bit_differences(img.pixels, ref.render_scaled(5 + 16 * tx, -3 + 16 * ty, w, h)), 0u)
          << tx << "," << ty;
      EXPECT_EQ(img.spec.get_string_attribute("stex:filter"), "box-prefilter");
      const int cw = std::min(20, 48 - 20 * tx), ch = std::min(20, 32 - 20 * ty);
      EXPECT_EQ(test::count_bit_differences(read_image(dir / ("c_" + std::to_string(tx) + "_" + std::to_string(ty) + ".exr")).pixels,
                                            cref.render_camera(cam, 20 * tx, 20 * ty, cw, ch)),
                0u)
          << "camera " << tx << "," << ty;
    }
  // A UV map is the image: no tiles.
  r = run_stex("render '" + model.string() + "' -o '" + (dir / "u_{tx}_{ty}.exr").string() +
               "' --uv-map '" + (dir / "f_0_0.exr").string() + "' --tile-size 8");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--uv-map renders single images"), std::string::npos) << r.err;
}

// Gabor models filter minified views by default too (the kernels convolved with the footprint,
// runtime/gabor_params.h): the C++ reference's pixels, as farm tiles as well; --no-filter point-samples with
// a warning; --filter at scale 1 and --camera exit 2.
TEST(RenderCli, GaborMinifiedViewsAreFilteredAndTile) {
  const fs::path dir = tmp_dir("gabor_filter");
  const fs::path model = dir / "g.stex";
  RunResult r = run_stex("gabor -o '" + model.string() + "' --frequency 0.1 --orientation 20 --bandwidth 0.06");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const LoadedModel loaded = load_model_file(model.string());
  ASSERT_NE(loaded.as<GaborModel>(), nullptr);
  const GaborModel gm = *loaded.as<GaborModel>();
  RenderParams p;
  p.seed = 5;
  p.scale = 0.25;
  p.filter = true;
  const std::vector<float> ref = GaborReference(gm, p).render(3, -2, 24, 20);
  r = run_stex("render '" + model.string() + "' -o '" + (dir / "f.exr").string() +
               "' --size 24x20 --origin 3,-2 --scale 0.25 --seed 5");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("aliases"), std::string::npos) << r.err;
  const Read img = read_image(dir / "f.exr");
  EXPECT_EQ(test::count_bit_differences(img.pixels, ref), 0u);
  EXPECT_EQ(img.spec.get_string_attribute("stex:filter"), "gaussian-footprint");
  r = run_stex("render '" + model.string() + "' -o '" + (dir / "t_{tx}_{ty}.exr").string() +
               "' --size 24x20 --origin 3,-2 --scale 0.25 --seed 5 --tile-size 16");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (int ty = 0; ty < 2; ++ty)
    for (int tx = 0; tx < 2; ++tx) {
      const int w = tx ? 8 : 16, h = ty ? 4 : 16;
      const Read t = read_image(dir / ("t_" + std::to_string(tx) + "_" + std::to_string(ty) + ".exr"));
      std::vector<float> expect;
      for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) expect.push_back(ref[std::size_t(16 * ty + j) * 24 + 16 * tx + i]);
      EXPECT_EQ(test::count_bit_differences(t.pixels, expect), 0u) << tx << "," << ty;
      EXPECT_EQ(t.spec.get_string_attribute("stex:filter"), "gaussian-footprint");
    }
  r = run_stex("render '" + model.string() + "' -o '" + (dir / "p.exr").string() +
               "' --size 24x20 --origin 3,-2 --scale 0.25 --seed 5 --no-filter");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("--no-filter point-samples the kernels: the render aliases"), std::string::npos) << r.err;
  p.filter = false;
  EXPECT_EQ(test::count_bit_differences(read_image(dir / "p.exr").pixels, GaborReference(gm, p).render(3, -2, 24, 20)),
            0u);
  r = run_stex("render '" + model.string() + "' -o '" + (dir / "s.exr").string() + "' --size 8x8 --filter");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("filters minified views only"), std::string::npos) << r.err;
  r = run_stex("render '" + model.string() + "' -o '" + (dir / "c.exr").string() + "' --size 8x8 --camera 50,70,60");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--camera and --uv-map apply to texton models"), std::string::npos) << r.err;
}

// Writes a UV map image (float EXR unless `bits` says otherwise) of a camera view's plane points, `channels`
// channels (u, v, then zeros), and returns the map as the renderer sees it (float-rounded values).
UvMap write_camera_uv_map(const fs::path& path, const PerspectiveCamera& cam, int channels, int bits = 32) {
  Image img;
  img.width = int(cam.image_width);
  img.height = int(cam.image_height);
  img.channels = channels;
  UvMap map;
  map.width = img.width;
  map.height = img.height;
  for (int j = 0; j < img.height; ++j)
    for (int i = 0; i < img.width; ++i) {
      double u, v, jac[4];
      EXPECT_TRUE(camera_map(cam, i, j, &u, &v, jac));
      img.pixels.push_back(float(u));
      img.pixels.push_back(float(v));
      for (int c = 2; c < channels; ++c) img.pixels.push_back(0.0f);
      map.uv.push_back(double(float(u)));
      map.uv.push_back(double(float(v)));
    }
  WriteOptions wo;
  wo.bits = bits;
  write_image_atomic(path.string(), img, wo);
  return map;
}

// S1 §5 with a UV map: --uv-map writes the filtered reference's pixels for the map (2 or 3 channels, size from
// the map); bad maps exit 3 and bad combinations exit 2, naming the problem, writing nothing.
TEST(RenderCli, UvMap) {
  const fs::path dir = tmp_dir("uvmap");
  const fs::path model = save_synthetic(dir, 3);
  const PerspectiveCamera cam = parse_camera("50,50,60", 48, 32);  // no sky: the top ray is 80 degrees down
  RenderParams unit;
  unit.seed = 11;
  const FilteredTextonReference ref(load_model(model.string()), unit);
  for (int channels : {2, 3}) {
    const fs::path uv = dir / ("uv" + std::to_string(channels) + ".exr");
    const UvMap map = write_camera_uv_map(uv, cam, channels);
    const fs::path out = dir / ("u" + std::to_string(channels) + ".exr");
    RunResult r = run_stex("render '" + model.string() + "' -o '" + out.string() + "' --uv-map '" + uv.string() +
                           "' --seed 11");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Read img = read_image(out);
    EXPECT_EQ(img.width, 48);
    EXPECT_EQ(img.height, 32);
    EXPECT_EQ(test::count_bit_differences(img.pixels, ref.render_uv_map(map)), 0u) << channels << " channels";
    EXPECT_EQ(img.spec.get_string_attribute("stex:filter"), "mip-aniso");
    EXPECT_EQ(img.spec.get_string_attribute("stex:uv_map"), uv.string());
  }
  // --size equal to the map's is accepted; --no-filter point-samples (a different image).
  const fs::path uv = dir / "uv2.exr";
  RunResult r = run_stex("render '" + model.string() + "' -o '" + (dir / "n.exr").string() + "' --uv-map '" +
                         uv.string() + "' --size 48x32 --no-filter --seed 11");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GT(test::count_bit_differences(read_image(dir / "n.exr").pixels, read_image(dir / "u2.exr").pixels), 1000u);

  // Bad maps: exit 3 with a message naming the problem.
  Image nan_map;
  nan_map.width = 8;
  nan_map.height = 6;
  nan_map.channels = 2;
  nan_map.pixels.assign(8 * 6 * 2, 1.0f);
  nan_map.pixels[2 * (3 * 8 + 5) + 1] = std::nanf("");
  WriteOptions f32;
  f32.bits = 32;
  write_image_atomic((dir / "nan.exr").string(), nan_map, f32);
  Image one = nan_map;
  one.channels = 1;
  one.pixels.assign(8 * 6, 1.0f);
  write_image_atomic((dir / "one.exr").string(), one, f32);
  Image thin = nan_map;
  thin.width = 1;
  thin.pixels.assign(6 * 2, 1.0f);
  write_image_atomic((dir / "thin.exr").string(), thin, f32);
  write_camera_uv_map(dir / "eight.png", parse_camera("50,50,60", 8, 8), 3, 8);
  struct Bad {
    std::string map, needle;
  };
  for (const Bad& b : {Bad{"nan.exr", "pixel (5, 3) v"}, Bad{"one.exr", "1 channel"}, Bad{"thin.exr", "at least 2x2"},
                       Bad{"eight.png", "floating-point"}, Bad{"missing.exr", "cannot open"}}) {
    r = run_stex("render '" + model.string() + "' -o '" + (dir / "bad.exr").string() + "' --uv-map '" +
                 (dir / b.map).string() + "'");
    EXPECT_EQ(r.exit_code, 3) << b.map << ": " << r.err;
    EXPECT_NE(r.err.find(b.needle), std::string::npos) << b.map << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir / "bad.exr")) << b.map;
  }
  // Bad combinations: exit 2.
  for (const std::string& bad : {std::string("--camera 50,70,60"), std::string("--scale 0.5"),
                                 std::string("--origin 3,4"), std::string("--size 16x16"),
                                 std::string("--tile-size 16"), std::string("--mode dsn")}) {
    r = run_stex("render '" + model.string() + "' -o '" + (dir / "bad.exr").string() + "' --uv-map '" + uv.string() +
                 "' " + bad);
    EXPECT_EQ(r.exit_code, 2) << bad << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir / "bad.exr")) << bad;
  }
  r = run_stex("render '" + model.string() + "' -o '" + (dir / "bad.exr").string() + "'");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--size is required"), std::string::npos) << r.err;
}

// Bad input: documented exit code, a message naming the problem, no output file and no temp file.
TEST(RenderCli, BadInputFailsCleanly) {
  const fs::path dir = tmp_dir("bad");
  const fs::path model = save_synthetic(dir, 1);
  const fs::path corrupt = dir / "corrupt.stex";
  {
    std::string bytes = read_text(model);
    bytes[bytes.size() / 2] ^= 0x5a;  // flips payload bits: the checksum fails
    std::ofstream(corrupt, std::ios::binary) << bytes;
  }
  const fs::path truncated = dir / "truncated.stex";
  {
    const std::string bytes = read_text(model);
    std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 3);
  }
  // A well-formed model file of a kind this stex does not render.
  const fs::path foreign = dir / "foreign.stex";
  {
    stex::ModelContainer c;
    c.kind = "zz-test";
    c.payload = {1.0f, 2.0f};
    stex::save_container(c, foreign.string());
  }
  const fs::path outdir = dir / "out";
  fs::create_directories(outdir);
  const std::string o = (outdir / "x.exr").string();
  const std::string m = "'" + model.string() + "'";
  struct BadCase {
    std::string args;
    int code;
    std::string needle;
  };
  const std::vector<BadCase> cases = {
      {"render " + m + " -o '" + o + "' --size 0x0", 2, "--size"},
      {"render " + m + " -o '" + o + "' --size 64", 2, "--size"},
      {"render " + m + " -o '" + o + "' --size -5x10", 2, "--size"},
      {"render " + m + " -o '" + o + "' --size 64x64 --mni -1", 2, "--mni"},
      {"render " + m + " -o '" + o + "' --size 64x64 --mni 0", 2, "--mni"},
      {"render " + m + " -o '" + o + "' --size 64x64 --scale 0", 2, "--scale"},
      {"render " + m + " -o '" + o + "' --size 64x64 --cell 5", 2, "--cell"},
      {"render " + m + " -o '" + o + "' --size 100000x100000", 5, "pixel budget"},
      {"render " + m + " -o '" + o + "' --size 64x64 --strategy fast", 2, "fast"},
      {"render " + m + " -o '" + o + "' --size 64x64 --mode magic", 2, "magic"},
      {"render " + m + " -o '" + o + "' --size 64x64 --origin 1,2,3", 2, "--origin"},
      {"render " + m + " -o '" + o + "' --size 64x64 --origin 99999999999999999999,0", 2, "--origin"},
      {"render " + m + " -o '" + o + "' --size 64x64 --origin 70368744177664,0", 2, "2^46"},
      {"render " + m + " -o '" + o + "' --size 64x64 --mode dsn --scale 2", 2, "--scale"},
      {"render " + m + " -o '" + (outdir / "x.bmp").string() + "' --size 64x64", 2, "extension"},
      {"render " + m + " -o '" + o + "' --size 64x64 --bits 8", 2, "--bits"},
      {"render '" + (dir / "missing.stex").string() + "' -o '" + o + "' --size 64x64", 3, "missing.stex"},
      {"render '" + corrupt.string() + "' -o '" + o + "' --size 64x64", 3, "corrupt.stex"},
      {"render '" + truncated.string() + "' -o '" + o + "' --size 64x64", 3, "truncated.stex"},
      {"render '" + foreign.string() + "' -o '" + o + "' --size 64x64", 3, "kind 'zz-test'"},
      {"render '" + foreign.string() + "' -o '" + o + "' --size 64x64 --mode dsn", 2, "applies to texton models"},
      {"render " + m + " -o '" + (dir / "no_such_dir" / "x.exr").string() + "' --size 16x16", 6, "no_such_dir"},
  };
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.args);
    RunResult r = run_stex(c.args);
    EXPECT_EQ(r.exit_code, c.code) << r.err;
    EXPECT_NE(r.err.find(c.needle), std::string::npos) << r.err;
    EXPECT_EQ(files_in(outdir), 0u) << "an output or temp file was left behind";
  }
}

// The exemplar a comparison mode reads (--mode adsn --exemplar, S2 §2.1) damaged as in
// tests/cli/bad_exemplars.h: the documented code, stderr naming the file and the problem, no output.
TEST(RenderCli, DamagedExemplarFailsCleanly) {
  const fs::path dir = tmp_dir("bad_exemplar");
  const fs::path model = save_synthetic(dir, 3);
  const fs::path outdir = dir / "out";
  fs::create_directories(outdir);
  const auto bad = test::make_bad_exemplars(dir.string());
  ASSERT_EQ(bad.size(), 5u);
  for (const auto& b : bad) {
    SCOPED_TRACE(b.name);
    RunResult r = run_stex("render '" + model.string() + "' -o '" + (outdir / "x.exr").string() +
                           "' --size 32x32 --mode adsn --exemplar '" + b.path + "'");
    EXPECT_EQ(r.exit_code, b.code) << r.err;
    for (const std::string& n : b.needles) EXPECT_NE(r.err.find(n), std::string::npos) << n << " in: " << r.err;
    EXPECT_EQ(files_in(outdir), 0u) << "an output or temp file was left behind";
  }
}

// Same bits on every device: PoCL with POCL_DEVICES='pthread basic' exposes two CPU devices,
// whose drivers compile and schedule the kernels differently (pthread: work-groups on a thread pool; basic:
// one thread). A colour texton model rendered with each strategy on each (--device 0 and --device 1, far from
// the origin, scale != 1 for the per-pixel taps) writes identical EXR pixels, equal to the C++ reference.
// A kernel cache of its own (kept between runs, so only the first run compiles): PoCL's cache key ignores
// the environment (measured on PoCL 3.1).
TEST(RenderCli, SameBitsOnBothPoclDevices) {
  // What differs between the two runs is the driver, not the host code: the normal tree checks it.
  if (test::k_under_asan) GTEST_SKIP() << "sanitizer tree: the normal tree compares the two PoCL drivers";
  const fs::path dir = tmp_dir("two_devices");
  const fs::path model = save_synthetic(dir, 3);
  const fs::path cache = fs::path(STEX_TEST_TMP_DIR) / "pocl_cache_two_devices";
  fs::create_directories(cache);
  const std::string env = "POCL_DEVICES='pthread basic' POCL_CACHE_DIR='" + cache.string() + "'";
  RenderParams p;
  p.seed = 77;
  p.scale = 1.3;
  p.mni = 12;
  const std::int64_t ox = -1000000000000ll - 5, oy = 333;
  const std::vector<float> ref = TextonReference(load_model(model.string()), p).render(ox, oy, 48, 40);
  std::string names[2];
  for (int device : {0, 1})
    for (const char* strategy : {"splat", "gather", "gather-local"}) {
      SCOPED_TRACE("device " + std::to_string(device) + " " + strategy);
      const fs::path out = dir / ("d" + std::to_string(device) + "_" + strategy + ".exr");
      RunResult r = run_stex_env(env, "--device " + std::to_string(device) + " render '" + model.string() + "' -o '" +
                                          out.string() + "' --size 48x40 --origin=" + std::to_string(ox) + "," +
                                          std::to_string(oy) + " --seed 77 --scale 1.3 --mni 12 --strategy " + strategy);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      EXPECT_NE(r.out.find(std::string("strategy ") + strategy), std::string::npos) << r.out;
      const std::size_t at = r.out.find(": device ");
      ASSERT_NE(at, std::string::npos) << r.out;
      const std::string name = r.out.substr(at + 9, r.out.find(", strategy", at) - at - 9);
      if (names[device].empty()) names[device] = name;
      EXPECT_EQ(name, names[device]);
      const Read img = read_image(out);
      EXPECT_EQ(test::count_bit_differences(img.pixels, ref), 0u) << "vs the C++ reference";
    }
  // Two different devices really ran (PoCL puts the driver, pthread or basic, in the device name).
  EXPECT_NE(names[0], names[1]) << names[0];
}

}  // namespace
}  // namespace stex
