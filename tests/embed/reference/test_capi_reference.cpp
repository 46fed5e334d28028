// The C API (include/stex/stex.h) against stex's internal C++ references, in one binary linked with both
// libstex.so (for the C API only: stex.h, never stex.hpp) and the static libraries (for the references).
// libstex.so exports only the stex_* C functions, so its internal copies never meet the static ones.
//  - SurfaceCApi: stex_eval_surface_points equals SurfaceReference (runtime/surface.h, the C++ evaluator on
//    kernels/shared/surface.h) bit for bit, for 1 and 3 channels, orders 0 and 1, given and derived
//    tangents, far from the origin; batch independence; every error status.
//  - KindsCApi: a gabor model file loads through stex_model_load (the kind registry) and renders through the
//    same handle as the registry's renderer (make_noise_renderer) bit for bit, into host memory and into a
//    cl_mem; info, kind, save round trip; texton-only calls refuse it with STEX_INPUT.
#include <CL/cl.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "analysis/cs_rpn_model.h"
#include "analysis/gabor_model.h"
#include "analysis/image_io.h"
#include "analysis/lrp.h"
#include "model/codecs.h"
#include "model/kinds.h"
#include "model/loaded_model.h"
#include "model/render_request.h"
#include "kernels/shared/rng.h"
#include "kernels/test_texton_common.h"
#include "runtime/context.h"
#include "runtime/gabor_renderer.h"
#include "runtime/surface.h"
#include "stex/stex.h"
#include "test_device.h"

#define ASSERT_STEX_OK(call)                                                               \
  do {                                                                                     \
    const stex_status status_ = (call);                                                    \
    ASSERT_EQ(status_, STEX_OK) << stex_status_name(status_) << ": " << stex_last_error(); \
  } while (0)

#define EXPECT_STEX_STATUS(call, expected)                                                            \
  do {                                                                                                \
    const stex_status status_ = (call);                                                               \
    EXPECT_EQ(status_, expected) << "got " << stex_status_name(status_) << ": " << stex_last_error(); \
  } while (0)

namespace {

using stex::test::count_bit_differences;
using stex::test::synthetic_model;

stex_context* capi_context() {
  static stex_context* ctx = [] {
    stex_context* c = nullptr;
    EXPECT_EQ(stex_context_create(stex::test::test_device_spec().c_str(), &c), STEX_OK) << stex_last_error();
    return c;
  }();
  return ctx;
}

std::string tmp_path(const std::string& name) { return std::string(STEX_TEST_TMP_DIR) + "/" + name; }

struct ModelHandle {
  stex_model* m = nullptr;
  ~ModelHandle() { stex_model_destroy(m); }
};

// A random unit vector from the counter RNG (uniform on the sphere).
std::array<double, 3> random_unit(std::uint32_t i, std::uint32_t stream) {
  const stex_uvec4 v = stex_draw(stex_cell_key(i, stream), 23u, 0u, 0u, STEX_DOMAIN_TEST);
  const double z = 2.0 * stex_uniform24(v.x) - 1.0, phi = 6.283185307179586 * stex_uniform24(v.y);
  const double rxy = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {rxy * std::cos(phi), rxy * std::sin(phi), z};
}

struct SurfacePoints {
  std::vector<double> pos, nrm, tan;
  std::size_t size() const { return pos.size() / 3; }
};

// n points scattered in a cube of side `extent` about `offset` (sub-texel detail: positions are not on a
// lattice), random normals and tangents; every fourth normal is (anti)parallel to X, where the derived
// tangent takes its fallback branch.
SurfacePoints scattered_points(int n, double extent, double offset) {
  SurfacePoints p;
  for (int k = 0; k < n; ++k) {
    const auto j = random_unit(std::uint32_t(k), 3), nn = random_unit(std::uint32_t(k), 1),
               tt = random_unit(std::uint32_t(k), 2);
    const double r = extent * 0.5 * stex_uniform24(stex_draw(stex_cell_key(k, 9), 1u, 0u, 0u, STEX_DOMAIN_TEST).x);
    for (int a = 0; a < 3; ++a) p.pos.push_back(offset + r * j[std::size_t(a)]);
    if (k % 4 == 3)
      p.nrm.insert(p.nrm.end(), {k % 8 == 3 ? 2.0 : -0.5, 0.0, 0.0});
    else
      p.nrm.insert(p.nrm.end(), nn.begin(), nn.end());
    p.tan.insert(p.tan.end(), tt.begin(), tt.end());
  }
  return p;
}

// The C++ reference at the same points: positions rounded to float, frames from surface_frame.
std::vector<float> reference_values(const stex::TextonModel& model, const stex::SurfaceParams& sp,
                                    const SurfacePoints& p, bool tangents) {
  const stex::SurfaceReference ref(model, sp);
  std::vector<float> out(p.size() * std::size_t(model.channels));
  for (std::size_t k = 0; k < p.size(); ++k) {
    const float pos[3] = {float(p.pos[3 * k]), float(p.pos[3 * k + 1]), float(p.pos[3 * k + 2])};
    const auto f = stex::surface_frame(&p.nrm[3 * k], tangents ? &p.tan[3 * k] : nullptr, k);
    ref.eval(pos, f.data(), &out[k * std::size_t(model.channels)]);
  }
  return out;
}

stex_surface_eval_params capi_surface_params(const stex::SurfaceParams& sp) {
  stex_surface_eval_params p;
  stex_surface_eval_params_init(&p, sizeof p);
  p.mni = sp.mni;
  p.cell_factor = sp.cell_factor;
  p.texel = sp.texel;
  p.seed = sp.seed;
  return p;
}

// The model through a file, as an application gets it (stex_model_load), and the reference's copy decoded
// from the same file.
void load_both(const stex::TextonModel& model, const std::string& name, ModelHandle* handle,
               stex::TextonModel* decoded) {
  const std::string path = tmp_path(name);
  stex::save_model(model, path);
  *decoded = stex::load_model(path);
  ASSERT_STEX_OK(stex_model_load(path.c_str(), &handle->m));
}

TEST(SurfaceCApi, EqualsTheCppReferenceBitForBit) {
  struct Case {
    int channels, support, order;
    double texel, offset;
    std::uint64_t seed;
  };
  for (const Case& c : {Case{3, 8, 1, 0.5, 0.0, 7}, Case{1, 6, 0, 2.0, -3.0e5, 11}, Case{3, 5, 1, 1.0, 1.5e6, 3}}) {
    ModelHandle h;
    stex::TextonModel model;
    load_both(synthetic_model(c.channels, c.support, c.order, c.seed), "surface.stex", &h, &model);
    stex::SurfaceParams sp;
    sp.seed = c.seed * 1000 + 1;
    sp.texel = c.texel;
    sp.mni = 40.0;
    const SurfacePoints pts = scattered_points(300, 40.0 * c.texel * c.support, c.offset);
    const stex_surface_eval_params p = capi_surface_params(sp);
    for (bool tangents : {true, false}) {
      std::vector<float> out(pts.size() * std::size_t(c.channels), -1.0f);
      ASSERT_STEX_OK(stex_eval_surface_points(capi_context(), h.m, &p, pts.size(), pts.pos.data(), pts.nrm.data(),
                                              tangents ? pts.tan.data() : nullptr, out.data()));
      const std::vector<float> ref = reference_values(model, sp, pts, tangents);
      EXPECT_EQ(count_bit_differences(out, ref), 0u)
          << "channels " << c.channels << " order " << c.order << " tangents " << tangents;
      // Not trivially equal: the values vary, and another seed changes them.
      double lo = out[0], hi = out[0];
      for (float v : out) lo = std::min(lo, double(v)), hi = std::max(hi, double(v));
      EXPECT_GT(hi - lo, 1e-3);
      stex_surface_eval_params other = p;
      other.seed += 1;
      std::vector<float> out2(out.size());
      ASSERT_STEX_OK(stex_eval_surface_points(capi_context(), h.m, &other, pts.size(), pts.pos.data(),
                                              pts.nrm.data(), tangents ? pts.tan.data() : nullptr, out2.data()));
      EXPECT_GT(count_bit_differences(out, out2), out.size() / 2);
    }
  }
}

TEST(SurfaceCApi, ValuesDoNotDependOnTheCallsSplit) {
  ModelHandle h;
  stex::TextonModel model;
  load_both(synthetic_model(3, 8, 1, 5), "split.stex", &h, &model);
  const SurfacePoints pts = scattered_points(200, 300.0, 10.0);
  const stex_surface_eval_params p = capi_surface_params(stex::SurfaceParams{});
  std::vector<float> whole(pts.size() * 3), parts(pts.size() * 3);
  ASSERT_STEX_OK(stex_eval_surface_points(capi_context(), h.m, &p, pts.size(), pts.pos.data(), pts.nrm.data(),
                                          pts.tan.data(), whole.data()));
  const std::size_t split = 77;
  ASSERT_STEX_OK(stex_eval_surface_points(capi_context(), h.m, &p, split, pts.pos.data(), pts.nrm.data(),
                                          pts.tan.data(), parts.data()));
  ASSERT_STEX_OK(stex_eval_surface_points(capi_context(), h.m, &p, pts.size() - split, pts.pos.data() + 3 * split,
                                          pts.nrm.data() + 3 * split, pts.tan.data() + 3 * split,
                                          parts.data() + 3 * split));
  EXPECT_EQ(count_bit_differences(whole, parts), 0u);
  // NULL parameters are the defaults (mni 60, cell 0.6, texel 1, seed 0).
  std::vector<float> defaults(whole.size());
  ASSERT_STEX_OK(stex_eval_surface_points(capi_context(), h.m, nullptr, pts.size(), pts.pos.data(), pts.nrm.data(),
                                          pts.tan.data(), defaults.data()));
  EXPECT_EQ(count_bit_differences(whole, defaults), 0u);
}

TEST(SurfaceCApi, RejectsBadInputWithStatusAndIndex) {
  ModelHandle h;
  stex::TextonModel model;
  load_both(synthetic_model(1, 6, 1, 2), "bad.stex", &h, &model);
  stex_surface_eval_params p;
  ASSERT_STEX_OK(stex_surface_eval_params_init(&p, sizeof p));
  EXPECT_EQ(p.mni, 60.0);
  EXPECT_EQ(p.cell_factor, 0.6);
  EXPECT_EQ(p.texel, 1.0);
  EXPECT_EQ(p.seed, 0u);
  std::vector<double> pos = {0, 0, 0, 1, 2, 3, 4, 5, 6}, nrm = {0, 0, 1, 0, 1, 0, 1, 1, 1};
  std::vector<float> out(3, 7.0f);
  auto call = [&](const stex_surface_eval_params* params, const double* n, const double* t = nullptr) {
    return stex_eval_surface_points(capi_context(), h.m, params, 3, pos.data(), n, t, out.data());
  };
  ASSERT_STEX_OK(call(&p, nrm.data()));
  auto message_has = [](const char* text) { return std::string(stex_last_error()).find(text) != std::string::npos; };

  std::vector<double> bad = nrm;
  bad[3] = bad[4] = bad[5] = 0.0;
  EXPECT_STEX_STATUS(call(&p, bad.data()), STEX_USAGE);
  EXPECT_TRUE(message_has("point 1: the normal is zero")) << stex_last_error();
  bad = nrm;
  bad[8] = std::nan("");
  EXPECT_STEX_STATUS(call(&p, bad.data()), STEX_USAGE);
  EXPECT_TRUE(message_has("point 2")) << stex_last_error();
  std::vector<double> tan = {1, 0, 0, 1, 0, 0, INFINITY, 0, 0};
  EXPECT_STEX_STATUS(call(&p, nrm.data(), tan.data()), STEX_USAGE);
  EXPECT_TRUE(message_has("point 2: the tangent is not finite")) << stex_last_error();
  pos[4] = 1e7;  // 2^22 texton units at texel 1
  EXPECT_STEX_STATUS(call(&p, nrm.data()), STEX_USAGE);
  EXPECT_TRUE(message_has("point 1: coordinate 1")) << stex_last_error();
  pos[4] = 2.0;

  stex_surface_eval_params q = p;
  q.mni = 0.0;
  EXPECT_STEX_STATUS(call(&q, nrm.data()), STEX_USAGE);
  q = p;
  q.texel = 0.0;
  EXPECT_STEX_STATUS(call(&q, nrm.data()), STEX_USAGE);
  q = p;
  q.reserved[1] = 1;
  EXPECT_STEX_STATUS(call(&q, nrm.data()), STEX_INVALID_ARGUMENT);
  q = p;
  q.struct_size = 8;
  EXPECT_STEX_STATUS(call(&q, nrm.data()), STEX_INVALID_ARGUMENT);
  EXPECT_STEX_STATUS(call(&p, nullptr), STEX_INVALID_ARGUMENT);
  EXPECT_STEX_STATUS(stex_eval_surface_points(nullptr, h.m, &p, 3, pos.data(), nrm.data(), nullptr, out.data()),
                     STEX_INVALID_ARGUMENT);
  EXPECT_STEX_STATUS(stex_surface_eval_params_init(&q, 16), STEX_INVALID_ARGUMENT);
  ASSERT_STEX_OK(stex_eval_surface_points(capi_context(), h.m, &p, 0, nullptr, nullptr, nullptr, nullptr));
  // No value was written by a failed call after the first success... and the first success wrote all three.
  for (float v : out) EXPECT_NE(v, 7.0f);

  // A B-spline texton (order 3) has no surface evaluation: STEX_INPUT, before any device work.
  ModelHandle cubic;
  stex::TextonModel cubic_model;
  load_both(synthetic_model(1, 6, 3, 2), "cubic.stex", &cubic, &cubic_model);
  EXPECT_STEX_STATUS(stex_eval_surface_points(capi_context(), cubic.m, &p, 3, pos.data(), nrm.data(), nullptr,
                                              out.data()),
                     STEX_INPUT);
  EXPECT_TRUE(message_has("order 0 or 1")) << stex_last_error();
}

// A 3-lobe Gabor model (kind "gabor", analysis/gabor_model.h), saved as an application would get it.
stex::GaborModel gabor_model() {
  stex::GaborModel m;
  m.bandwidth = 0.07;
  m.mean = 0.4;
  m.stddev = 0.2;
  m.components.clear();
  for (auto [f, o, s, w] : std::vector<std::array<double, 4>>{{0.1, 0.3, 0.0, 1.0}, {0.2, 1.5, 0.2, 0.5}, {0.05, 0.0, 6.2831853, 0.7}}) {
    stex::GaborComponent c;
    c.frequency = f;
    c.orientation = o;
    c.spread = s;
    c.weight = w;
    m.components.push_back(c);
  }
  return stex::gabor_roundtrip(m);
}

// stex_render_cl into a fresh cl_mem of the C API's context, `offset` bytes in, read back: `floats` values.
std::vector<float> render_through_cl_mem(const stex_model* m, const stex_render_params& p, std::int64_t x,
                                         std::int64_t y, int w, int h, std::size_t floats, std::size_t offset) {
  cl_context clc = nullptr;
  cl_command_queue queue = nullptr;
  std::vector<float> out(floats, -1.0f);
  EXPECT_EQ(stex_context_cl_objects(capi_context(), &clc, nullptr, &queue), STEX_OK) << stex_last_error();
  cl_int err = CL_SUCCESS;
  cl_mem buffer = clCreateBuffer(clc, CL_MEM_READ_WRITE, floats * sizeof(float) + offset, nullptr, &err);
  EXPECT_EQ(err, CL_SUCCESS);
  if (err != CL_SUCCESS) return out;
  EXPECT_EQ(stex_render_cl(capi_context(), m, &p, x, y, w, h, buffer, offset, 0, nullptr, nullptr), STEX_OK)
      << stex_last_error();
  EXPECT_EQ(clEnqueueReadBuffer(queue, buffer, CL_TRUE, offset, floats * sizeof(float), out.data(), 0, nullptr,
                                nullptr),
            CL_SUCCESS);
  clReleaseMemObject(buffer);
  return out;
}

TEST(KindsCApi, GaborModelLoadsAndRendersThroughTheSameHandle) {
  const std::string path = tmp_path("gabor.stex");
  const stex::ModelContainer container = stex::to_container(gabor_model());
  stex::save_container(container, path);
  ModelHandle gm;
  ASSERT_STEX_OK(stex_model_load(path.c_str(), &gm.m));
  const char* kind = nullptr;
  ASSERT_STEX_OK(stex_model_kind(gm.m, &kind));
  EXPECT_STREQ(kind, "gabor");
  stex_model_info info{};
  info.struct_size = sizeof info;
  ASSERT_STEX_OK(stex_model_get_info(gm.m, &info));
  EXPECT_EQ(info.channels, 1);
  EXPECT_EQ(info.mean[0], 0.4f);
  EXPECT_EQ(info.support, 0);
  EXPECT_EQ(info.linear, 0);

  // The registry's renderer on an internal context is the reference.
  std::unique_ptr<stex::Context> ctx = stex::Context::create(stex::test::test_device_spec());
  std::unique_ptr<stex::NoiseRenderer> reference = stex::make_noise_renderer(*ctx, container);
  stex::RenderParams rp;
  rp.seed = 99;
  rp.mni = 25.0;
  const std::int64_t x0 = -1000000000037, y0 = 4242;
  const int w = 70, h = 45;
  std::vector<float> ref(std::size_t(w) * h);
  reference->render(rp, x0, y0, w, h, ref.data());
  stex_render_params p;
  stex_render_params_init(&p, sizeof p);
  p.seed = rp.seed;
  p.mni = rp.mni;
  std::vector<float> got(ref.size(), -1.0f);
  ASSERT_STEX_OK(stex_render(capi_context(), gm.m, &p, x0, y0, w, h, got.data(), 0, nullptr, nullptr));
  EXPECT_EQ(count_bit_differences(got, ref), 0u);
  double lo = got[0], hi = got[0];
  for (float v : got) lo = std::min(lo, double(v)), hi = std::max(hi, double(v));
  EXPECT_GT(hi - lo, 0.1);  // a texture of std 0.2, not a constant

  // A strided render, and tiles, give the same pixels.
  const std::size_t stride = (std::size_t(w) + 5) * sizeof(float);
  std::vector<float> strided(std::size_t(h) * (w + 5), 0.0f);
  ASSERT_STEX_OK(stex_render(capi_context(), gm.m, &p, x0, y0, w, h, strided.data(), stride, nullptr, nullptr));
  std::vector<float> packed;
  for (int j = 0; j < h; ++j)
    packed.insert(packed.end(), strided.begin() + std::ptrdiff_t(j) * (w + 5),
                  strided.begin() + std::ptrdiff_t(j) * (w + 5) + w);
  EXPECT_EQ(count_bit_differences(packed, ref), 0u);

  // Into a cl_mem of the context (staged through the host for this kind).
  EXPECT_EQ(count_bit_differences(render_through_cl_mem(gm.m, p, x0, y0, w, h, ref.size(), 64), ref), 0u);

  // Saving through the C API writes the same container: it reloads and renders the same.
  const std::string again = tmp_path("gabor-again.stex");
  ASSERT_STEX_OK(stex_model_save(gm.m, again.c_str()));
  const stex::ModelContainer back = stex::load_container(again);
  EXPECT_EQ(back.kind, "gabor");
  EXPECT_EQ(back.payload, container.payload);
  ModelHandle gm2;
  ASSERT_STEX_OK(stex_model_load(again.c_str(), &gm2.m));
  std::vector<float> got2(ref.size());
  ASSERT_STEX_OK(stex_render(capi_context(), gm2.m, &p, x0, y0, w, h, got2.data(), 0, nullptr, nullptr));
  EXPECT_EQ(count_bit_differences(got2, ref), 0u);

  // Texton-only operations refuse it by kind; a texton strategy is a usage error.
  double xy[2] = {0.5, 0.5};
  float v[4];
  EXPECT_STEX_STATUS(stex_eval_points(capi_context(), gm.m, nullptr, 1, xy, v), STEX_INPUT);
  EXPECT_NE(std::string(stex_last_error()).find("kind 'gabor'"), std::string::npos) << stex_last_error();
  double pos[3] = {0, 0, 0}, nrm[3] = {0, 0, 1};
  EXPECT_STEX_STATUS(stex_eval_surface_points(capi_context(), gm.m, nullptr, 1, pos, nrm, nullptr, v), STEX_INPUT);
  stex_render_params splat = p;
  splat.strategy = STEX_STRATEGY_SPLAT;
  EXPECT_STEX_STATUS(stex_render(capi_context(), gm.m, &splat, 0, 0, 4, 4, got.data(), 0, nullptr, nullptr),
                     STEX_USAGE);
}

TEST(KindsCApi, UnknownKindsAndBadFieldsAreInputErrors) {
  // A container of a kind this stex does not know, and a gabor container with a bad field.
  stex::ModelContainer unknown;
  unknown.kind = "future";
  unknown.payload = {1.0f, 2.0f};
  const std::string p1 = tmp_path("future.stex");
  stex::save_container(unknown, p1);
  ModelHandle h;
  EXPECT_STEX_STATUS(stex_model_load(p1.c_str(), &h.m), STEX_INPUT);
  EXPECT_EQ(h.m, nullptr);
  EXPECT_NE(std::string(stex_last_error()).find("known kinds: texton"), std::string::npos) << stex_last_error();

  stex::ModelContainer bad = stex::to_container(gabor_model());
  bad.metadata["bandwidth"] = -1.0;
  const std::string p2 = tmp_path("bad-gabor.stex");
  stex::save_container(bad, p2);
  EXPECT_STEX_STATUS(stex_model_load(p2.c_str(), &h.m), STEX_INPUT);
  EXPECT_EQ(h.m, nullptr);

  // Texton models still load as texton (the analysis' own handle equals the loaded one).
  const std::string p3 = tmp_path("texton.stex");
  stex::save_model(synthetic_model(2, 6, 1, 4), p3);
  ASSERT_STEX_OK(stex_model_load(p3.c_str(), &h.m));
  const char* kind = nullptr;
  ASSERT_STEX_OK(stex_model_kind(h.m, &kind));
  EXPECT_STREQ(kind, "texton");
  EXPECT_STEX_STATUS(stex_model_kind(h.m, nullptr), STEX_INVALID_ARGUMENT);
}

// Filtered renders (docs/filtering.md) through the C API: with STEX_FILTER_AUTO a minified view of a texton
// model (orders 1 and 3), a gabor and an lrp model is the request path's filtered render (model/render_request.h,
// what `stex render` and `stex serve` write) bit for bit, into host memory and into a cl_mem; STEX_FILTER_OFF
// point-samples; STEX_FILTER_ON on a model that does not filter is STEX_USAGE.
TEST(KindsCApi, MinifiedViewsAreFilteredAsTheRequestPathFiltersThem) {
  std::unique_ptr<stex::Context> ctx = stex::Context::create(stex::test::test_device_spec());
  stex::LrpParams lp;
  lp.strata = 3;
  lp.cosines = 12;
  const stex::Image gravel = stex::load_exemplar(std::string(STEX_SOURCE_DIR) + "/data/gravel.png");
  const std::vector<std::pair<std::string, stex::ModelContainer>> models = {
      {"texton", stex::to_container(synthetic_model(3, 12, 1, 77))},
      {"texton-order3", stex::to_container(synthetic_model(1, 10, 3, 78))},
      {"gabor", stex::to_container(gabor_model())},
      {"lrp", stex::to_container(stex::analyse_lrp(gravel, lp))},
  };
  for (const auto& [name, container] : models) {
    SCOPED_TRACE(name);
    const std::string path = tmp_path("filtered-" + name + ".stex");
    stex::save_container(container, path);
    const stex::LoadedModel loaded = stex::load_model_file(path);
    ModelHandle h;
    ASSERT_STEX_OK(stex_model_load(path.c_str(), &h.m));
    const int w = 37, hh = 21;
    const std::int64_t x0 = -501, y0 = 77;
    for (int mode : {int(STEX_FILTER_AUTO), int(STEX_FILTER_OFF)}) {
      stex::RenderParams rp;
      rp.seed = 5;
      rp.scale = 0.25;
      stex::ModelRenderers renderers(*ctx);
      const stex::RenderedPixels ref = renderers.render(
          loaded, stex::RenderRequest::region(x0, y0, w, hh, rp, "auto",
                                              mode == STEX_FILTER_OFF ? stex::FilterMode::Off : stex::FilterMode::Auto));
      EXPECT_EQ(ref.filtered, mode == STEX_FILTER_AUTO);
      stex_render_params p;
      stex_render_params_init(&p, sizeof p);
      p.seed = rp.seed;
      p.scale = rp.scale;
      p.filter = mode;
      std::vector<float> got(ref.pixels.size(), -1.0f);
      ASSERT_STEX_OK(stex_render(capi_context(), h.m, &p, x0, y0, w, hh, got.data(), 0, nullptr, nullptr));
      EXPECT_EQ(count_bit_differences(got, ref.pixels), 0u) << "mode " << mode;
      EXPECT_EQ(count_bit_differences(render_through_cl_mem(h.m, p, x0, y0, w, hh, got.size(), 0), ref.pixels), 0u)
          << "mode " << mode << ", cl_mem";
    }
  }
  // A cs-rpn model of the phasor variant does not filter: STEX_FILTER_ON is a usage error; AUTO point-samples.
  stex::CsRpnModel phasor;
  phasor.variant = stex::CsRpnVariant::Phasor;
  stex::cs_rpn_load_spectra(phasor, nlohmann::json{{"grid", {1, 1}}, {"size", 64}, {"spectra", {"bilobe:0.1,0,0.01"}}});
  const std::string unfiltered = tmp_path("filtered-phasor.stex");
  stex::save_container(stex::to_container(phasor), unfiltered);
  ModelHandle h;
  ASSERT_STEX_OK(stex_model_load(unfiltered.c_str(), &h.m));
  stex_render_params p;
  stex_render_params_init(&p, sizeof p);
  p.scale = 0.5;
  p.filter = STEX_FILTER_ON;
  std::vector<float> out(64);
  EXPECT_STEX_STATUS(stex_render(capi_context(), h.m, &p, 0, 0, 8, 8, out.data(), 0, nullptr, nullptr), STEX_USAGE);
  EXPECT_NE(std::string(stex_last_error()).find("cs-rpn"), std::string::npos) << stex_last_error();
  p.filter = STEX_FILTER_AUTO;
  ASSERT_STEX_OK(stex_render(capi_context(), h.m, &p, 0, 0, 8, 8, out.data(), 0, nullptr, nullptr));
}

}  // namespace
