// The model-kind registry (analysis/noise_kinds.h): a texton container renders through the NoiseRenderer
// interface exactly as through TextonRenderer; unknown kinds and wrong options are refused by name.
#include <gtest/gtest.h>

#include <memory>

#include "model/codecs.h"
#include "model/kinds.h"
#include "core/error.h"
#include "runtime/context.h"
#include "runtime/texton_renderer.h"
#include "test_device.h"

namespace stex {
namespace {

Context& ctx() {
  static std::unique_ptr<Context> c = Context::create(stex::test::test_device_spec());
  return *c;
}

TextonModel small_model() {
  TextonModel m;
  m.channels = 3;
  m.support = 8;
  m.alpha.resize(3 * 8 * 8);
  for (std::size_t i = 0; i < m.alpha.size(); ++i) m.alpha[i] = float((i * 37) % 11) / 11.0f - 0.45f;
  m.mean = {0.5f, 0.4f, 0.3f, 0.0f};
  m.stex_version = "test";
  return m;
}

TEST(NoiseKinds, TextonContainerRendersLikeTheTextonRenderer) {
  const TextonModel m = small_model();
  // Through the file bytes, as `stex render` does.
  const std::vector<std::uint8_t> bytes = encode_model(m);
  const ModelContainer c = decode_container(bytes.data(), bytes.size(), "t");
  NoiseRendererOptions opts;
  opts.strategy = "gather";
  std::unique_ptr<NoiseRenderer> r = make_noise_renderer(ctx(), c, opts);
  EXPECT_EQ(r->kind(), "texton");
  EXPECT_EQ(r->channels(), 3);
  RenderParams p;
  p.seed = 99;
  p.mni = 12;
  std::vector<float> a(3 * 37 * 21), b;
  const NoiseRenderStats st = r->render(p, -13, 1000, 37, 21, a.data());
  EXPECT_EQ(st.strategy, "gather");
  TextonRenderer direct(ctx(), m);
  b = direct.render(p, -13, 1000, 37, 21);
  EXPECT_EQ(a, b);
}

TEST(NoiseKinds, UnknownKindAndBadStrategyAreRefused) {
  ModelContainer c;
  c.kind = "nope";
  try {
    make_noise_renderer(ctx(), c, {}, "x.stex");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("kind 'nope'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("texton"), std::string::npos) << e.what();
  }
  const TextonModel m = small_model();
  NoiseRendererOptions opts;
  opts.strategy = "warp";
  try {
    make_noise_renderer(ctx(), to_container(m), opts);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
  }
}

TEST(NoiseKinds, MetadataHelpers) {
  TextonModel m = small_model();
  m.exemplar_name = "gravel.png";
  m.linear = true;
  const ModelContainer c = to_container(m);
  EXPECT_TRUE(model_is_linear(c));
  EXPECT_EQ(model_exemplar_name(c), "gravel.png");
  ModelContainer bare;
  bare.kind = "x";
  EXPECT_FALSE(model_is_linear(bare));
  EXPECT_EQ(model_exemplar_name(bare), "");
}

}  // namespace
}  // namespace stex
