// Farm output files: parameter hash, per-tile atomic writes with metadata and data window, inspection of
// valid/truncated/foreign files, and the out-of-core tiled writer compared bit for bit with a whole-image
// write (EXR and TIFF tiled, PNG through the scanline path).
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include "core/error.h"
#include "farm/output_file.h"
#include "farm/tiled_image_writer.h"
#include "tests/farm/farm_test_util.h"
#include "tests/farm/synth_pattern.h"

using namespace stex;
using namespace stex::farm;
using namespace stex::farm::test;

namespace {

RenderIdentity identity_for(const TileGrid& g, int channels, std::uint64_t seed = 7) {
  RenderIdentity id;
  id.stex_version = "test";
  id.model_hash = "model-abc";
  id.seed = seed;
  id.mni = 30.5;
  id.origin_x = -5;
  id.origin_y = 1000000000000LL;
  id.param_hash =
      compute_param_hash(id.model_hash, id.seed, id.mni, id.origin_x, id.origin_y, {{"mode", "x"}});
  id.full_width = g.width();
  id.full_height = g.height();
  id.tile_size = g.tile_size();
  id.channels = channels;
  return id;
}

std::vector<float> synth_tile(const RenderIdentity& id, const TileRect& t) {
  std::vector<float> px;
  synth_region(id.seed, id.channels, id.origin_x + t.x0, id.origin_y + t.y0, t.width, t.height, px);
  return px;
}

// Writes the whole image as one tile of a 1x1 grid: the reference for the tiled writer.
std::vector<float> whole_reference(const std::string& path, const RenderIdentity& tiled_id) {
  TileGrid one(tiled_id.full_width, tiled_id.full_height,
               std::max(tiled_id.full_width, tiled_id.full_height));
  RenderIdentity id = tiled_id;
  id.tile_size = one.tile_size();
  TileRect t = one.tile(0);
  write_tile_file(path, synth_tile(id, t), t, id, {});
  return read_output_pixels(path);
}

}  // namespace

TEST(ParamHash, Fnv1aTestVectors) {
  // FNV-1a 64 reference values (Fowler/Noll/Vo test suite).
  EXPECT_EQ(fnv1a64_hex(""), "cbf29ce484222325");
  EXPECT_EQ(fnv1a64_hex("a"), "af63dc4c8601ec8c");
  EXPECT_EQ(fnv1a64_hex("foobar"), "85944171f73967e8");
}

TEST(ParamHash, DependsOnEveryPixelParameterAndNothingElse) {
  KeyValues p = {{"mode", "texton"}, {"scale", "1"}, {"cell_factor", "0.625"}};
  std::string h = compute_param_hash("m", 1, 30, 0, 0, p);
  EXPECT_EQ(h.size(), 16u);
  KeyValues reordered = {{"scale", "1"}, {"cell_factor", "0.625"}, {"mode", "texton"}};
  EXPECT_EQ(compute_param_hash("m", 1, 30, 0, 0, reordered), h);
  EXPECT_NE(compute_param_hash("n", 1, 30, 0, 0, p), h);
  EXPECT_NE(compute_param_hash("m", 2, 30, 0, 0, p), h);
  EXPECT_NE(compute_param_hash("m", 1, 30.000001, 0, 0, p), h);
  EXPECT_NE(compute_param_hash("m", 1, 30, 1, 0, p), h);
  EXPECT_NE(compute_param_hash("m", 1, 30, 0, 1, p), h);
  KeyValues scaled = {{"mode", "texton"}, {"scale", "2"}, {"cell_factor", "0.625"}};
  EXPECT_NE(compute_param_hash("m", 1, 30, 0, 0, scaled), h);
  EXPECT_THROW(compute_param_hash("m", 1, 30, 0, 0, {{"a=b", "1"}}), Error);
  EXPECT_THROW(compute_param_hash("m", 1, 30, 0, 0, {{"a", "1"}, {"a", "2"}}), Error);
}

TEST(OutputFile, TileRoundTripWithMetadataAndDataWindow) {
  std::string dir = fresh_dir();
  TileGrid g(300, 200, 128);
  RenderIdentity id = identity_for(g, 3);
  TileRect t = g.tile(2, 1);  // ragged corner: 44 x 72 at (256, 128)
  ASSERT_EQ(t.width, 44);
  ASSERT_EQ(t.height, 72);
  std::vector<float> px = synth_tile(id, t);
  std::string path = dir + "/sub/dir/t.exr";  // parent directories are created
  write_tile_file(path, px, t, id, {});
  EXPECT_EQ(count_temp_files(dir + "/sub/dir"), 0);
  EXPECT_EQ(read_output_pixels(path), px);  // bit for bit

  OutputInspection ins = inspect_output(path);
  ASSERT_EQ(ins.state, OutputState::Valid) << ins.problem;
  EXPECT_EQ(ins.info.id.param_hash, id.param_hash);
  EXPECT_EQ(ins.info.id.model_hash, id.model_hash);
  EXPECT_EQ(ins.info.id.seed, id.seed);
  EXPECT_EQ(ins.info.id.mni, id.mni);
  EXPECT_EQ(ins.info.id.origin_x, id.origin_x);
  EXPECT_EQ(ins.info.id.origin_y, id.origin_y);
  EXPECT_EQ(ins.info.id.full_width, 300);
  EXPECT_EQ(ins.info.id.full_height, 200);
  EXPECT_EQ(ins.info.id.tile_size, 128);
  EXPECT_EQ(ins.info.id.channels, 3);
  EXPECT_EQ(ins.info.tile_index, t.index);
  EXPECT_EQ(ins.info.x, 256);
  EXPECT_EQ(ins.info.y, 128);
  EXPECT_EQ(ins.info.pixel_type, "float");

  // What other tools see: the EXR data window in place inside the full (display) window.
  auto in = OIIO::ImageInput::open(path);
  ASSERT_TRUE(in);
  const OIIO::ImageSpec& spec = in->spec();
  EXPECT_EQ(spec.x, 256);
  EXPECT_EQ(spec.y, 128);
  EXPECT_EQ(spec.full_x, 0);
  EXPECT_EQ(spec.full_width, 300);
  EXPECT_EQ(spec.full_height, 200);
  EXPECT_EQ(spec.get_string_attribute("stex:window"), "256,128,44,72");
  EXPECT_EQ(spec.get_string_attribute("stex:full_size"), "300x200");
  EXPECT_EQ(spec.get_string_attribute("stex:grid"), "3x2");
  EXPECT_EQ(spec.get_int_attribute("stex:tile_index"), 5);
  EXPECT_EQ(spec.get_string_attribute("stex:version"), "test");
  EXPECT_EQ(spec.get_string_attribute("stex:seed"), "7");
}

TEST(OutputFile, PixelTypesAndFormats) {
  std::string dir = fresh_dir();
  TileGrid g(40, 30, 16);
  RenderIdentity id = identity_for(g, 1);
  TileRect t = g.tile(4);
  std::vector<float> px = synth_tile(id, t);
  OutputSettings half;
  half.bits = 16;
  write_tile_file(dir + "/h.exr", px, t, id, half);
  EXPECT_EQ(inspect_output(dir + "/h.exr").info.pixel_type, "half");
  write_tile_file(dir + "/t.tif", px, t, id, {});
  EXPECT_EQ(read_output_pixels(dir + "/t.tif"), px);
  write_tile_file(dir + "/p.png", px, t, id, {});
  OutputInspection png = inspect_output(dir + "/p.png");
  ASSERT_EQ(png.state, OutputState::Valid) << png.problem;
  EXPECT_EQ(png.info.pixel_type, "uint8");
  EXPECT_EQ(png.info.x, t.x0);  // PNG has no data window: stex:window carries it
  std::vector<float> back = read_output_pixels(dir + "/p.png");
  ASSERT_EQ(back.size(), px.size());
  for (std::size_t i = 0; i < px.size(); ++i) EXPECT_NEAR(back[i], px[i], 0.5 / 255 + 1e-6);
  EXPECT_THROW(write_tile_file(dir + "/x.bmpx", px, t, id, {}), Error);
  OutputSettings bad;
  bad.bits = 32;
  try {
    write_tile_file(dir + "/p32.png", px, t, id, bad);
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
  }
  EXPECT_EQ(count_temp_files(dir), 0);
}

TEST(OutputFile, InspectionFindsMissingTruncatedAndForeignFiles) {
  std::string dir = fresh_dir();
  TileGrid g(256, 256, 256);
  RenderIdentity id = identity_for(g, 3);
  TileRect t = g.tile(0);
  std::string path = dir + "/t.exr";
  EXPECT_EQ(inspect_output(path).state, OutputState::Missing);
  write_tile_file(path, synth_tile(id, t), t, id, {});
  ASSERT_EQ(inspect_output(path).state, OutputState::Valid);
  // Truncated copies at several lengths: all Invalid with verify_pixels.
  std::string bytes = slurp(path);
  for (double frac : {0.0, 0.01, 0.3, 0.6, 0.95}) {
    std::string cut = dir + "/cut.exr";
    {
      std::ofstream f(cut, std::ios::binary | std::ios::trunc);
      f.write(bytes.data(), std::streamsize(bytes.size() * frac));
    }
    OutputInspection ins = inspect_output(cut);
    EXPECT_EQ(ins.state, OutputState::Invalid) << "truncated to " << frac;
    EXPECT_FALSE(ins.problem.empty());
  }
  // An image without stex metadata.
  {
    auto out = OIIO::ImageOutput::create(dir + "/foreign.exr");
    OIIO::ImageSpec spec(8, 8, 3, OIIO::TypeDesc::FLOAT);
    std::vector<float> zeros(8 * 8 * 3, 0.0f);
    ASSERT_TRUE(out->open(dir + "/foreign.exr", spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, zeros.data()));
    out->close();
  }
  OutputInspection foreign = inspect_output(dir + "/foreign.exr");
  EXPECT_EQ(foreign.state, OutputState::Invalid);
  EXPECT_NE(foreign.problem.find("not a stex farm output"), std::string::npos) << foreign.problem;
  // Garbage bytes.
  { std::ofstream(dir + "/junk.exr") << "not an image at all"; }
  EXPECT_EQ(inspect_output(dir + "/junk.exr").state, OutputState::Invalid);
}

TEST(TiledImageWriter, MatchesWholeImageBitForBit) {
  std::string dir = fresh_dir();
  for (std::string ext : {"exr", "tif", "png"}) {
    SCOPED_TRACE(ext);
    TileGrid g(300, 200, 64);  // ragged last column (44) and row (8)
    RenderIdentity id = identity_for(g, 3);
    std::string path = dir + "/tiled." + ext;
    {
      TiledImageWriter w(path, g, id, {});
      EXPECT_EQ(w.tiled_file(), ext != "png");
      for (std::int64_t i = 0; i < g.count(); ++i) w.write_tile(g.tile(i), synth_tile(id, g.tile(i)));
      EXPECT_FALSE(exists(path));  // nothing under the name before finish()
      w.finish();
    }
    EXPECT_EQ(count_temp_files(dir), 0);
    std::vector<float> ref = whole_reference(dir + "/whole." + ext, id);
    EXPECT_EQ(read_output_pixels(path), ref);
    auto in = OIIO::ImageInput::open(path);
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().tile_width, ext == "png" ? 0 : 64);
    OutputInspection ins = inspect_output(path);  // metadata through every format (TIFF: ImageDescription)
    ASSERT_EQ(ins.state, OutputState::Valid) << ins.problem;
    EXPECT_EQ(ins.info.tile_index, -1);
    EXPECT_EQ(ins.info.id.param_hash, id.param_hash);
    EXPECT_EQ(ins.info.id.origin_y, id.origin_y);
    EXPECT_EQ(ins.info.width, 300);
    EXPECT_EQ(ins.info.tiled, ext != "png");
    // A tile-aligned region read back equals that tile.
    TileRect t = g.tile(3, 2);
    if (ext != "png") {
      EXPECT_EQ(read_output_region(path, t.x0, t.y0, t.width, t.height), synth_tile(id, t));
    }
    // An unaligned region goes through scanlines.
    std::vector<float> part = read_output_region(path, 10, 20, 5, 3);
    ASSERT_EQ(part.size(), 5u * 3 * 3);
    if (ext != "png") {
      EXPECT_EQ(part[0], synth_value(id.seed, id.origin_x + 10, id.origin_y + 20, 0));
      EXPECT_EQ(part.back(), synth_value(id.seed, id.origin_x + 14, id.origin_y + 22, 2));
    }
  }
}

TEST(TiledImageWriter, OrderAndAbandonment) {
  std::string dir = fresh_dir();
  TileGrid g(128, 128, 64);
  RenderIdentity id = identity_for(g, 1);
  std::string path = dir + "/img.exr";
  {
    TiledImageWriter w(path, g, id, {});
    w.write_tile(g.tile(0), synth_tile(id, g.tile(0)));
    EXPECT_THROW(w.write_tile(g.tile(2), synth_tile(id, g.tile(2))), Error);  // skipped tile 1
    EXPECT_THROW(w.finish(), Error);                                          // tiles missing
    EXPECT_EQ(count_temp_files(dir), 1);
  }  // abandoned: temp removed, nothing under the name
  EXPECT_EQ(count_temp_files(dir), 0);
  EXPECT_FALSE(exists(path));
  try {
    TiledImageWriter w(dir + "/bad.tif", TileGrid(100, 100, 40), identity_for(TileGrid(100, 100, 40), 1), {});
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("multiple of 16"), std::string::npos);
  }
  EXPECT_EQ(count_temp_files(dir), 0);
}

TEST(AtomicOutput, TempNamesAndCommit) {
  std::string dir = fresh_dir();
  TempOutput tmp(dir + "/a.exr");
  EXPECT_TRUE(is_temp_name(tmp.path().substr(dir.size() + 1)));
  EXPECT_EQ(tmp.path().substr(tmp.path().size() - 4), ".exr");
  tmp.commit();
  EXPECT_TRUE(exists(dir + "/a.exr"));
  EXPECT_EQ(count_temp_files(dir), 0);
  EXPECT_FALSE(is_temp_name("a.exr"));
  EXPECT_FALSE(is_temp_name(".hidden.exr"));
  try {
    TempOutput t(dir + "/no/such/dir/x.exr");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Output);
    EXPECT_NE(std::string(e.what()).find("no/such/dir"), std::string::npos) << e.what();
  }
}
