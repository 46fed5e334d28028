// Meshes for surface noise: loading PLY/OBJ (Assimp), vertex colours, and baking through UVs without seams
// between UV charts (issue 9: "no seams across UV charts when baking").
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <vector>

#include "analysis/mesh.h"
#include "core/error.h"
#include "kernels/test_texton_common.h"
#include "runtime/surface.h"

namespace stex {
namespace {

using test::synthetic_model;
using test::texton_context;

std::string tmp_path(const std::string& name) {
  std::filesystem::create_directories(STEX_TEST_TMP_DIR);
  return std::string(STEX_TEST_TMP_DIR) + "/" + name;
}

// A sphere of radius 1 made of the 6 faces of a cube (N x N quads each) projected on it, normals = the
// position's direction; each face is its own UV chart in a 3 x 2 atlas with a margin, so every cube edge
// is a seam between two charts. Face-border vertices are duplicated (one per chart) with bit-identical
// positions and normals: they come from the same integer lattice point.
Mesh cube_sphere(int n) {
  Mesh m;
  for (int f = 0; f < 6; ++f) {
    const int fa = f / 2, sign = (f % 2) ? -1 : 1;  // faces: +X -X +Y -Y +Z -Z
    const int ua = (fa + 1) % 3, va = (fa + 2) % 3;
    const double col = f % 3, row = f / 3, margin = 0.03;
    const std::size_t base = m.vertex_count();
    for (int b = 0; b <= n; ++b)
      for (int a = 0; a <= n; ++a) {
        long c[3];
        c[fa] = sign * n;
        c[ua] = -n + 2 * a;
        c[va] = -n + 2 * b;
        const double len = std::sqrt(double(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]));
        for (int i = 0; i < 3; ++i) m.positions.push_back(double(c[i]) / len);
        for (int i = 0; i < 3; ++i) m.normals.push_back(double(c[i]) / len);
        m.uvs.push_back((col + margin + (1 - 2 * margin) * double(a) / n) / 3.0);
        m.uvs.push_back((row + margin + (1 - 2 * margin) * double(b) / n) / 2.0);
      }
    for (int b = 0; b < n; ++b)
      for (int a = 0; a < n; ++a) {
        const std::uint32_t v00 = std::uint32_t(base + b * (n + 1) + a), v10 = v00 + 1,
                            v01 = std::uint32_t(v00 + n + 1), v11 = v01 + 1;
        m.triangles.insert(m.triangles.end(), {v00, v10, v11, v00, v11, v01});
      }
  }
  return m;
}

struct SeamStats {
  double seam2 = 0.0, interior2 = 0.0, variance = 0.0;
  int seam_samples = 0, interior_samples = 0;
};

// Mean squared differences: across seams, between the two charts' bilinear lookups at the same surface
// point; inside charts, between the bilinear lookup and the exact surface noise at that point.
SeamStats seam_stats(int gutter) {
  const TextonModel model = synthetic_model(1, 8, 1, 31);
  SurfaceParams sp;
  sp.mni = 20.0;
  sp.seed = 77;
  sp.texel = 0.02;
  const Mesh mesh = cube_sphere(12);
  SurfaceRenderer renderer(texton_context(), model);
  BakeOptions bo;
  bo.width = bo.height = 512;
  bo.gutter = gutter;
  const BakeResult baked = bake_surface_noise(renderer, sp, model, mesh, bo);
  const SurfaceReference ref(model, sp);

  // Edges keyed by their two positions; an edge used by triangles of two charts is a seam.
  std::map<std::array<double, 6>, std::vector<std::pair<std::uint32_t, std::uint32_t>>> edges;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      std::uint32_t a = mesh.triangles[3 * t + k], b = mesh.triangles[3 * t + (k + 1) % 3];
      std::array<double, 3> pa{mesh.positions[3 * a], mesh.positions[3 * a + 1], mesh.positions[3 * a + 2]};
      std::array<double, 3> pb{mesh.positions[3 * b], mesh.positions[3 * b + 1], mesh.positions[3 * b + 2]};
      if (pb < pa) {
        std::swap(pa, pb);
        std::swap(a, b);
      }
      edges[{pa[0], pa[1], pa[2], pb[0], pb[1], pb[2]}].push_back({a, b});
    }
  SeamStats st;
  float va = 0, vb = 0;
  for (const auto& [key, uses] : edges) {
    if (uses.size() != 2 || uses[0].first == uses[1].first) continue;  // interior edge (shared vertices)
    for (double t : {0.13, 0.37, 0.5, 0.71, 0.9}) {
      auto uv = [&](std::pair<std::uint32_t, std::uint32_t> e, int i) {
        return (1 - t) * mesh.uvs[2 * e.first + i] + t * mesh.uvs[2 * e.second + i];
      };
      sample_bilinear(baked.image, uv(uses[0], 0), uv(uses[0], 1), &va);
      sample_bilinear(baked.image, uv(uses[1], 0), uv(uses[1], 1), &vb);
      st.seam2 += double(va - vb) * (va - vb);
      ++st.seam_samples;
    }
  }
  // Interior points: barycentric (0.3, 0.3, 0.4) of every 7th triangle.
  for (std::size_t t = 0; t < mesh.triangle_count(); t += 7) {
    const std::uint32_t* tv = &mesh.triangles[3 * t];
    const double w[3] = {0.3, 0.3, 0.4};
    double p[3] = {0, 0, 0}, n[3] = {0, 0, 0}, u = 0, v = 0;
    for (int k = 0; k < 3; ++k) {
      for (int i = 0; i < 3; ++i) {
        p[i] += w[k] * mesh.positions[3 * tv[k] + i];
        n[i] += w[k] * mesh.normals[3 * tv[k] + i];
      }
      u += w[k] * mesh.uvs[2 * tv[k]];
      v += w[k] * mesh.uvs[2 * tv[k] + 1];
    }
    const float pf[3] = {float(p[0]), float(p[1]), float(p[2])};
    const auto f = surface_frame(n, nullptr);
    float exact = 0;
    ref.eval(pf, f.data(), &exact);
    sample_bilinear(baked.image, u, v, &va);
    st.interior2 += double(va - exact) * (va - exact);
    st.variance += double(exact - model.mean[0]) * (exact - model.mean[0]);
    ++st.interior_samples;
  }
  st.seam2 /= st.seam_samples;
  st.interior2 /= st.interior_samples;
  st.variance /= st.interior_samples;
  return st;
}

// Without a seam, the two lookups at a seam point are two independent bilinear interpolation errors of
// the same field: E (a - b)^2 = 2 e^2 with e^2 the interior interpolation error. Bound: 3 e^2 (the seam
// estimate averages 12 cube edges x 12 segments x 5 points = 720 samples, so its relative standard error is
// about sqrt(2/720) = 5%; 3 instead of 2 leaves room for the slightly larger error at chart borders, where the
// gutter's extrapolated points lie off the sphere). The same check without a gutter must fail, by far.
TEST(SurfaceBake, NoSeamsAcrossUvCharts) {
  const SeamStats with = seam_stats(4);
  ASSERT_EQ(with.seam_samples, 12 * 12 * 5);
  EXPECT_LT(with.interior2, 0.05 * with.variance) << "bilinear lookups should be close to the noise";
  EXPECT_LT(with.seam2, 3.0 * with.interior2) << "seam " << with.seam2 << " interior " << with.interior2;
  const SeamStats without = seam_stats(0);
  EXPECT_GT(without.seam2, 10.0 * without.interior2) << "without a gutter the charts must show seams";
  std::printf("seam mean squared difference %.3g (gutter 4) vs %.3g (no gutter); interior interpolation "
              "%.3g; variance %.3g\n",
              with.seam2, without.seam2, with.interior2, with.variance);
}

TEST(SurfaceBake, VertexValuesEqualTheReference) {
  const TextonModel model = synthetic_model(3, 6, 1, 32);
  SurfaceParams sp;
  sp.texel = 0.03;
  const Mesh mesh = cube_sphere(4);
  SurfaceRenderer renderer(texton_context(), model);
  const std::vector<float> got = surface_vertex_values(renderer, sp, mesh);
  const SurfaceReference ref(model, sp);
  std::vector<float> expected(got.size());
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const float p[3] = {float(mesh.positions[3 * v]), float(mesh.positions[3 * v + 1]),
                        float(mesh.positions[3 * v + 2])};
    const auto f = surface_frame(&mesh.normals[3 * v], nullptr);
    ref.eval(p, f.data(), &expected[3 * v]);
  }
  EXPECT_EQ(test::count_bit_differences(expected, got), 0u);
}

TEST(MeshIo, ObjWithUvsAndPlyRoundTrip) {
  const std::string obj = tmp_path("quad.obj");
  {
    std::ofstream out(obj);
    out << "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
           "f 1/1 2/2 3/3 4/4\n";
  }
  const Mesh m = load_mesh(obj);
  EXPECT_EQ(m.triangle_count(), 2u);
  EXPECT_EQ(m.vertex_count(), 4u);
  ASSERT_EQ(m.uvs.size(), 8u);
  for (std::size_t v = 0; v < 4; ++v) EXPECT_NEAR(m.normals[3 * v + 2], 1.0, 1e-12);  // generated, +Z
  std::vector<float> values(4 * 3, 0.5f);
  values[0] = 2.0f;  // clamped to 255
  const std::string ply = tmp_path("quad.ply");
  write_ply_with_colours(ply, m, values, 3, false);
  const Mesh back = load_mesh(ply);
  EXPECT_EQ(back.triangle_count(), 2u);
  EXPECT_EQ(back.vertex_count(), 4u);
  EXPECT_TRUE(back.uvs.empty());
}

TEST(MeshIo, BadFilesAreInputErrors) {
  const std::string junk = tmp_path("junk.obj");
  {
    std::ofstream out(junk, std::ios::binary);
    out.write("\0\1\2\3garbage", 11);
  }
  const std::string text = tmp_path("notes.txt");
  {
    std::ofstream out(text);
    out << "hello\n";
  }
  const std::string empty_obj = tmp_path("empty.obj");
  {
    std::ofstream out(empty_obj);
    out << "# nothing\nv 0 0 0\n";
  }
  for (const std::string& p : {junk, text, empty_obj, tmp_path("missing.ply")}) {
    try {
      load_mesh(p);
      ADD_FAILURE() << p;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input) << p << ": " << e.what();
    }
  }
  Mesh no_uv = cube_sphere(2);
  no_uv.uvs.clear();
  const TextonModel model = synthetic_model(1, 4, 1, 1);
  SurfaceRenderer renderer(texton_context(), model);
  EXPECT_THROW(bake_surface_noise(renderer, SurfaceParams{}, model, no_uv, BakeOptions{}), Error);
}

}  // namespace
}  // namespace stex
