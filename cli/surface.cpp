// `stex surface MODEL --mesh MESH`: surface texton noise (S1 §6) on a triangle mesh, without a
// parameterisation: per-vertex colours (-o out.ply), a texture baked through the mesh's UVs (--bake), and/or
// a shaded preview image where every pixel evaluates the noise at its surface point (--preview). A thin
// client of runtime/surface.h and analysis/mesh.h; parameters are documented in runtime/surface.h.
#include <chrono>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>

#include "analysis/image_io.h"
#include "analysis/mesh.h"
#include "model/codecs.h"
#include "cli/commands.h"
#include "core/error.h"
#include "runtime/context.h"
#include "runtime/selftest.h"
#include "runtime/surface.h"

namespace stex::cli {
namespace {

struct SurfaceCliOptions {
  std::string model, mesh, output, bake, preview;
  std::string bake_size = "1024x1024", preview_size = "512x512", view = "1,0.8,1.6";
  int gutter = 4;
  double texel = 0.0;  // 0: automatic
  SurfaceParams params;
};

void parse_size(const std::string& s, const char* what, int* w, int* h) {
  char x = 0, extra = 0;
  std::istringstream in(s);
  if (!(in >> *w >> x >> *h) || x != 'x' || (in >> extra))
    throw Error(ErrorKind::Usage, std::string(what) + " must be WIDTHxHEIGHT, got '" + s + "'");
}

std::array<double, 3> parse_vec3(const std::string& s, const char* what) {
  std::array<double, 3> v{};
  char c1 = 0, c2 = 0, extra = 0;
  std::istringstream in(s);
  if (!(in >> v[0] >> c1 >> v[1] >> c2 >> v[2]) || c1 != ',' || c2 != ',' || (in >> extra))
    throw Error(ErrorKind::Usage, std::string(what) + " must be X,Y,Z, got '" + s + "'");
  return v;
}

void run_surface(SurfaceCliOptions& o, const GlobalOptions& global) {
  const auto t_start = std::chrono::steady_clock::now();
  if (o.output.empty() && o.bake.empty() && o.preview.empty())
    throw Error(ErrorKind::Usage, "nothing to do: give -o (vertex colours, .ply), --bake (texture) and/or --preview");
  if (!o.output.empty()) {
    const auto dot = o.output.find_last_of('.');
    if (dot == std::string::npos || o.output.substr(dot) != ".ply")
      throw Error(ErrorKind::Usage, "-o writes a PLY mesh with vertex colours: its name must end in .ply, got '" +
                                        o.output + "'");
  }
  BakeOptions bo;
  bo.gutter = o.gutter;
  parse_size(o.bake_size, "--bake-size", &bo.width, &bo.height);
  PreviewOptions po;
  parse_size(o.preview_size, "--preview-size", &po.width, &po.height);
  po.view = parse_vec3(o.view, "--view");
  const TextonModel model = load_model(o.model);
  const Mesh mesh = load_mesh(o.mesh);
  SurfaceParams sp = o.params;
  std::string texel_note;
  if (o.texel > 0.0) {
    sp.texel = o.texel;
  } else if (o.texel == 0.0) {
    // Automatic: the bounding box diagonal spans 8 texton supports.
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
      for (int i = 0; i < 3; ++i) {
        lo[i] = std::min(lo[i], mesh.positions[3 * v + i]);
        hi[i] = std::max(hi[i], mesh.positions[3 * v + i]);
      }
    const double diag = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                  (hi[2] - lo[2]) * (hi[2] - lo[2]));
    sp.texel = diag > 0.0 ? diag / (8.0 * double(model.support + model.order)) : 1.0;
    texel_note = " (automatic: the bounding box diagonal / (8 r))";
  } else {
    throw Error(ErrorKind::Usage, "--texel must be positive (world units per exemplar pixel), or 0 for automatic");
  }
  validate_surface_params(sp);

  std::unique_ptr<Context> ctx = Context::create(global.device);
  SurfaceRenderer renderer(*ctx, model);
  ensure_selftest(*ctx, {SelftestRow{"surface", "points"}});  // known-answer check (runtime/selftest.h)
  // A model analysed in linear light gives linear values: 8-bit outputs are encoded to sRGB.
  if (!o.output.empty()) {
    const std::vector<float> values = surface_vertex_values(renderer, sp, mesh);
    write_ply_with_colours(o.output, mesh, values, model.channels, model.linear);
  }
  const std::vector<std::pair<std::string, std::string>> meta = {
      {"Software", std::string("stex ") + STEX_VERSION_STRING},
      {"stex:mode", "surface"},
      {"stex:seed", std::to_string(sp.seed)},
      {"stex:mni", std::to_string(sp.mni)},
      {"stex:texel", std::to_string(sp.texel)},
      {"stex:cell", std::to_string(sp.cell_factor)}};
  auto float_ext = [](const std::string& p) {
    const auto dot = p.find_last_of('.');
    const std::string e = dot == std::string::npos ? "" : p.substr(dot);
    return e == ".exr" || e == ".hdr";
  };
  if (!o.bake.empty()) {
    const BakeResult baked = bake_surface_noise(renderer, sp, model, mesh, bo);
    WriteOptions wo;
    wo.encode_srgb = model.linear && !float_ext(o.bake);
    wo.metadata = meta;
    write_image_atomic(o.bake, baked.image, wo);
  }
  if (!o.preview.empty()) {
    const Image img = render_mesh_preview(renderer, sp, mesh, po);
    WriteOptions wo;
    wo.encode_srgb = model.linear && !float_ext(o.preview);
    wo.metadata = meta;
    write_image_atomic(o.preview, img, wo);
  }
  if (global.quiet) return;
  const double wall_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_start).count();
  std::printf("surface noise on %s: %zu vertices, %zu triangles, texel %.6g world units%s, MNI %.6g, seed %llu; "
              "device %s, wall %.1f ms\n",
              o.mesh.c_str(), mesh.vertex_count(), mesh.triangle_count(), sp.texel, texel_note.c_str(), sp.mni,
              static_cast<unsigned long long>(sp.seed), ctx->info().name.c_str(), wall_ms);
  if (!o.output.empty()) std::printf("  vertex colours -> %s\n", o.output.c_str());
  if (!o.bake.empty()) std::printf("  baked %dx%d texture -> %s\n", bo.width, bo.height, o.bake.c_str());
  if (!o.preview.empty()) std::printf("  preview -> %s\n", o.preview.c_str());
}

}  // namespace

void add_surface(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<SurfaceCliOptions>();
  auto* sub = app.add_subcommand(
      "surface",
      "Surface texton noise (S1 §6) on a PLY/OBJ mesh without a parameterisation: vertex colours, a texture "
      "baked through the mesh's UVs (seamless across UV charts), a shaded preview");
  sub->add_option("model", o->model, "Model file (.stex) from `stex analyze`")->required();
  sub->add_option("--mesh", o->mesh, "Triangle mesh: PLY or OBJ (normals generated when missing)")->required();
  sub->add_option("-o,--output", o->output, "PLY mesh with per-vertex colours");
  sub->add_option("--bake", o->bake, "Texture baked through the mesh's first UV set (.png, .exr, .tif)");
  sub->add_option("--bake-size", o->bake_size, "Baked texture size WIDTHxHEIGHT (default 1024x1024)");
  sub->add_option("--gutter", o->gutter,
                  "Texels around UV charts filled with the surface's continuation, [0, 64] (default 4)");
  sub->add_option("--preview", o->preview, "Shaded orthographic view, noise evaluated per pixel (.png, .exr)");
  sub->add_option("--preview-size", o->preview_size, "Preview size WIDTHxHEIGHT (default 512x512)");
  sub->add_option("--view", o->view, "Direction towards the preview camera X,Y,Z (default 1,0.8,1.6)");
  sub->add_option("--texel", o->texel,
                  "World units per exemplar pixel (the texture's scale); 0 (default): bounding box diagonal / "
                  "(8 texton sizes)");
  sub->add_option("--mni", o->params.mni, "Mean number of impacts lambda r^3, (0, 10000] (default 60, S1 §9)");
  sub->add_option("--seed", o->params.seed, "64-bit seed of the 3-D impulse process (default 0)");
  sub->add_option("--cell", o->params.cell_factor, "Cell side of the 3-D grid as a fraction of r, [0.1, 2] (0.6)");
  sub->callback([o, &global] { run_surface(*o, global); });
}

}  // namespace stex::cli
