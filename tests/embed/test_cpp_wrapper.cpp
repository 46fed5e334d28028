// Tests of the header-only C++ wrapper (include/stex/stex.hpp): exceptions carry the status and the
// library's message, RAII handles, library defaults in the parameter structs, progress lambdas that cancel
// or throw (the exception reaches the caller unchanged), and equality with the C API's results.
#include <stdexcept>
#include <string>
#include <vector>

#include "embed_test_util.h"
#include "stex/stex.hpp"

using namespace stex_embed_test;

namespace {

stex::Model gravel16() {
  stex::AnalysisParams a;
  a.support = 16;
  a.iterations = 8;
  return stex::Model::analyse(gravel_path(), a);
}

}  // namespace

TEST(CppWrapper, ExceptionsCarryStatusAndMessage) {
  try {
    stex::Model::load(tmp_dir() + "/no-such-model.stex");
    FAIL() << "no exception";
  } catch (const stex::Error& e) {
    EXPECT_EQ(e.status(), STEX_INPUT);
    EXPECT_STREQ(e.status_name(), "STEX_INPUT");
    EXPECT_NE(std::string(e.what()).find("no-such-model.stex"), std::string::npos) << e.what();
  }
  try {
    stex::Context ctx("no-such-device-xyz");
    FAIL() << "no exception";
  } catch (const stex::Error& e) {
    EXPECT_EQ(e.status(), STEX_DEVICE);
  }
  stex::Context ctx(device_spec());
  stex::RenderParams p;
  p.mni = 0.0;
  EXPECT_THROW(ctx.render(gravel16(), p, 0, 0, 4, 4), stex::Error);
}

TEST(CppWrapper, DefaultsAndResultsMatchTheCApi) {
  stex::RenderParams p;
  EXPECT_EQ(p.mni, 30.0);
  EXPECT_EQ(p.cell_factor, 0.6);
  EXPECT_EQ(p.struct_size, sizeof(stex_render_params));
  stex::AnalysisParams a;
  EXPECT_EQ(a.support, 64);

  stex::Context ctx(device_spec());
  EXPECT_FALSE(ctx.device_name().empty());
  const stex::Model model = gravel16();
  const stex::Model copy = model;  // shares the handle
  EXPECT_EQ(copy.get(), model.get());
  EXPECT_EQ(model.channels(), 1);
  EXPECT_EQ(model.info().support, 16);
  p.seed = 8;
  const std::vector<float> img = ctx.render(model, p, -9, 4, 30, 20);
  ASSERT_EQ(img.size(), 30u * 20u);
  stex_render_params c = render_params(30.0, 8);
  EXPECT_EQ(bit_differences(img, render(ctx.get(), copy.get(), c, -9, 4, 30, 20)), 0u);

  std::vector<double> xy;
  for (int j = 0; j < 20; ++j)
    for (int i = 0; i < 30; ++i) xy.insert(xy.end(), {-9 + i + 0.5, 4 + j + 0.5});
  EXPECT_EQ(bit_differences(ctx.eval_points(model, p, xy), img), 0u);

  // Save + load through the wrapper.
  const std::string path = tmp_dir() + "/wrapper.stex";
  model.save(path);
  EXPECT_EQ(bit_differences(ctx.render(stex::Model::load(path), p, -9, 4, 30, 20), img), 0u);

  // Analysis from memory.
  const std::vector<float> px = colour_exemplar(48, 40);
  stex::AnalysisParams ca;
  ca.support = 8;
  ca.iterations = 6;
  const stex::Model colour = stex::Model::analyse(px.data(), 48, 40, 3, 0, ca);
  EXPECT_EQ(colour.channels(), 3);
  EXPECT_EQ(bit_differences(ctx.render(colour, p, 0, 0, 16, 16),
                            render(ctx.get(), colour_model(), c, 0, 0, 16, 16)),
            0u);
}

TEST(CppWrapper, ProgressLambdasCancelAndPropagateExceptions) {
  stex::Context ctx(device_spec());
  const stex::Model model = gravel16();
  stex::RenderParams p;
  std::vector<double> seen;
  ctx.render(model, p, 0, 0, 64, 160, [&](double f) {
    seen.push_back(f);
    return false;
  });
  ASSERT_GE(seen.size(), 3u);
  EXPECT_EQ(seen.back(), 1.0);

  try {
    ctx.render(model, p, 0, 0, 64, 160, [](double f) { return f > 0.3; });
    FAIL() << "no exception";
  } catch (const stex::Error& e) {
    EXPECT_EQ(e.status(), STEX_CANCELLED);
  }

  struct Custom : std::runtime_error {
    using std::runtime_error::runtime_error;
  };
  int calls = 0;
  try {
    ctx.render(model, p, 0, 0, 64, 160, [&](double f) -> bool {
      ++calls;
      if (f > 0.0) throw Custom("stop here");
      return false;
    });
    FAIL() << "no exception";
  } catch (const Custom& e) {
    EXPECT_STREQ(e.what(), "stop here");
  }
  EXPECT_EQ(calls, 2);  // the throw cancelled the render: no further calls
  // The context still works afterwards.
  EXPECT_EQ(ctx.render(model, p, 0, 0, 8, 8).size(), 64u);
}

TEST(CppWrapper, SurfacePointsAndKindsMatchTheCApi) {
  stex::Context ctx(device_spec());
  const stex::Model model = gravel16();
  EXPECT_EQ(model.kind(), "texton");
  stex::SurfaceParams sp;
  EXPECT_EQ(sp.mni, 60.0);
  EXPECT_EQ(sp.texel, 1.0);
  EXPECT_EQ(sp.struct_size, sizeof(stex_surface_eval_params));
  sp.seed = 3;
  sp.texel = 0.5;
  std::vector<double> pos, nrm, tan;
  for (int k = 0; k < 50; ++k) {
    pos.insert(pos.end(), {0.37 * k, -1.3 * k + 2.0, 0.05 * k * k});
    nrm.insert(nrm.end(), {0.1 * k - 2.0, 1.0, 0.3});
    tan.insert(tan.end(), {0.0, 0.2, 1.0});
  }
  const std::vector<float> with = ctx.eval_surface_points(model, sp, pos, nrm, tan);
  const std::vector<float> without = ctx.eval_surface_points(model, sp, pos, nrm);
  ASSERT_EQ(with.size(), 50u);
  std::vector<float> c_with(50), c_without(50);
  ASSERT_STEX_OK(stex_eval_surface_points(ctx.get(), model.get(), &sp, 50, pos.data(), nrm.data(), tan.data(),
                                          c_with.data()));
  ASSERT_STEX_OK(stex_eval_surface_points(ctx.get(), model.get(), &sp, 50, pos.data(), nrm.data(), nullptr,
                                          c_without.data()));
  EXPECT_EQ(bit_differences(with, c_with), 0u);
  EXPECT_EQ(bit_differences(without, c_without), 0u);
  EXPECT_GT(bit_differences(with, without), 25u);  // the tangent turns the texton
  // Mismatched arrays are refused before the C call; C errors carry their status.
  nrm.pop_back();
  EXPECT_THROW(ctx.eval_surface_points(model, sp, pos, nrm), stex::Error);
  nrm.push_back(0.0);
  nrm[nrm.size() - 3] = nrm[nrm.size() - 2] = 0.0;
  try {
    ctx.eval_surface_points(model, sp, pos, nrm);
    FAIL() << "a zero normal was accepted";
  } catch (const stex::Error& e) {
    EXPECT_EQ(e.status(), STEX_USAGE);
    EXPECT_NE(std::string(e.what()).find("point 49"), std::string::npos) << e.what();
  }
}
