// `stex render MODEL -o OUT --size WxH [--origin X,Y] [--scale S] [--mni N] [--seed N] [--cell C]
//  [--strategy auto|splat|gather|gather-local|gather-padded] [--mode texton|adsn|dsn|cadsn|cdsn|rpn] [--kernel exemplar|texton]
//  [--exemplar PATH] [--bits 8|16|32]`:
// renders a region of a texton noise model (S1 eq. 1-3, §8) on the selected OpenCL device
// (runtime/texton_renderer.h), or one of the comparison modes on the host (analysis/gaussian_synthesis.h,
// S2 §2.1-2.2: ADSN on Z^2 and circular and RPN of the exemplar's t_u or the texton kernel; DSN of the texton
// on Z^2 and circular). A thin client: parse, validate, call, write through analysis/image_io's atomic
// writer, report.
//
// Every parameter is validated before anything is allocated or the device is touched; errors are
// stex::Error, mapped to exit codes by main.cpp (README "Exit codes"): bad values 2 (Usage), missing or
// corrupt model/exemplar 3 (Input), no device 4, sizes beyond the pixel budget or the device 5 (Limit),
// unwritable output 6. Nothing is written on error.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "analysis/gaussian_synthesis.h"
#include "analysis/image_io.h"
#include "analysis/mix.h"
#include "model/codecs.h"
#include "model/kinds.h"
#include "model/loaded_model.h"
#include "model/render_request.h"
#include "analysis/render_metadata.h"
#include "cli/commands.h"
#include "core/error.h"
#include "farm/batch.h"
#include "farm/farm_cli.h"
#include "runtime/context.h"
#include "runtime/selftest.h"
#include "runtime/texton_filter.h"
#include "runtime/texton_params.h"
#include "runtime/texton_renderer.h"

namespace stex::cli {
namespace {

constexpr std::uint64_t k_default_pixel_budget = std::uint64_t(1) << 28;  // 16384^2 pixels per call

struct RenderCliOptions {
  std::string model, output, size, origin = "0,0", strategy = "auto", mode, exemplar;  // mode "": the kind's
  std::string kernel = "exemplar";  // adsn, cadsn, rpn: the exemplar's t_u or the model's texton kernel
  RenderParams params;
  bool mni_given = false, cell_given = false;  // --mni / --cell on the command line
  int bits = 0;
  bool filter = false, no_filter = false;  // S1 §5 on-the-fly filtering (runtime/texton_filter.h)
  std::string camera;                      // HEIGHT,TILT,FOV: a perspective view of the plane (filtered)
  std::string uv_map;                      // a UV map image: per-pixel plane points (filtered)
  std::uint64_t pixel_budget = k_default_pixel_budget;
  farm::FarmOptions farm;  // --tile-size and friends (docs/farm.md): render as tiles through farm::run
  // Noise mixing (kind mix, runtime/mix_model.h): a mixing map replacing the model's
  std::string mix_map, mix_origin = "0,0", mix_wrap = "repeat";
  double mix_scale = 1.0;
  bool mix_image_options = false;
};

[[noreturn]] void usage(const std::string& m) { throw Error(ErrorKind::Usage, m); }

void warn(const std::string& w) { std::fprintf(stderr, "stex: warning: %s\n", w.c_str()); }

// Strict signed 64-bit decimal (no trailing garbage, no overflow).
bool parse_i64(const std::string& s, std::int64_t* v) {
  if (s.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const long long r = std::strtoll(s.c_str(), &end, 10);
  if (errno != 0 || end != s.c_str() + s.size()) return false;
  *v = r;
  return true;
}

void parse_size(const std::string& s, std::int64_t* w, std::int64_t* h) {
  const auto x = s.find_first_of("xX");
  if (x == std::string::npos || !parse_i64(s.substr(0, x), w) || !parse_i64(s.substr(x + 1), h))
    usage("--size must be WIDTHxHEIGHT (e.g. 1024x1024), got '" + s + "'");
  if (*w < 1 || *h < 1) usage("--size must be at least 1x1, got '" + s + "'");
}

void parse_origin(const std::string& s, std::int64_t* x, std::int64_t* y) {
  const auto comma = s.find(',');
  if (comma == std::string::npos || !parse_i64(s.substr(0, comma), x) || !parse_i64(s.substr(comma + 1), y))
    usage("--origin must be X,Y (64-bit integers, output pixels), got '" + s + "'");
}

std::string lower_extension(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string e = path.substr(dot + 1);
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

bool file_exists(const std::string& p) {
  std::FILE* f = std::fopen(p.c_str(), "rb");
  if (!f) return false;
  std::fclose(f);
  return true;
}

// --exemplar, else the model's exemplar name beside the model file, else in the working directory.
std::string find_exemplar(const RenderCliOptions& o, const TextonModel& m) {
  if (!o.exemplar.empty()) return o.exemplar;
  if (m.exemplar_name.empty())
    throw Error(ErrorKind::Input,
                "--mode " + o.mode +
                    " needs the exemplar: the model names none; pass --exemplar PATH (or --kernel texton)");
  const auto slash = o.model.find_last_of('/');
  const std::string beside =
      slash == std::string::npos ? m.exemplar_name : o.model.substr(0, slash + 1) + m.exemplar_name;
  if (file_exists(beside)) return beside;
  if (file_exists(m.exemplar_name)) return m.exemplar_name;
  throw Error(ErrorKind::Input,
              "--mode " + o.mode + " needs the exemplar '" + m.exemplar_name +
                  "' (not found beside the model or in the working directory); pass --exemplar PATH");
}

// The region and the output file of a render, checked before the model is read or the device touched.
struct RenderTarget {
  std::int64_t w = 0, h = 0, ox = 0, oy = 0;
  bool uv_mapped = false;  // --uv-map: the map gives the size and every pixel's plane point
  UvMap uv_map;
  bool farm_mode = false;  // --tile-size and friends: tiles through farm::run
  std::string ext;         // the output's extension, lower case
  bool float_out = false;  // float values out (.exr, or --bits 32)
};

// --uv-map: reads the map (the output's size; only the header decides before the pixels).
void read_uv_map(const RenderCliOptions& o, RenderTarget* t) {
  if (!o.camera.empty()) usage("--uv-map and --camera exclude each other (each defines the mapping)");
  if (o.params.scale != 1.0) usage("--uv-map defines the mapping: --scale does not apply");
  if (o.origin != "0,0") usage("--uv-map defines every pixel's plane point: --origin does not apply");
  const Image map = load_float_image(o.uv_map, "UV map", o.pixel_budget);
  if (map.channels < 2)
    throw Error(ErrorKind::Input, "UV map '" + o.uv_map + "' has " + std::to_string(map.channels) +
                                      " channel; it needs (u, v) in its first two channels");
  UvMap& uv = t->uv_map;
  uv.width = map.width;
  uv.height = map.height;
  uv.uv.resize(2 * std::size_t(map.width) * std::size_t(map.height));
  for (std::size_t k = 0; k < uv.uv.size() / 2; ++k) {
    uv.uv[2 * k] = map.pixels[k * std::size_t(map.channels)];
    uv.uv[2 * k + 1] = map.pixels[k * std::size_t(map.channels) + 1];
  }
  validate_uv_map(uv, "UV map '" + o.uv_map + "'");
  const std::string map_size = std::to_string(map.width) + "x" + std::to_string(map.height);
  if (!o.size.empty()) {
    parse_size(o.size, &t->w, &t->h);
    if (t->w != map.width || t->h != map.height)
      usage("--size " + o.size + " differs from the UV map's size " + map_size + " (omit --size)");
  }
  t->w = map.width;
  t->h = map.height;
  t->uv_mapped = true;
}

// 1. The region, the pixel budget, the parameters and the output, before any allocation or device work.
RenderTarget plan_target(const RenderCliOptions& o) {
  RenderTarget t;
  if (!o.uv_map.empty()) {
    read_uv_map(o, &t);
  } else {
    if (o.size.empty()) usage("--size is required (WIDTHxHEIGHT), unless --uv-map gives it");
    parse_size(o.size, &t.w, &t.h);
  }
  parse_origin(o.origin, &t.ox, &t.oy);
  // Farm mode (--tile-size) renders one tile per call: the pixel budget applies to a tile.
  t.farm_mode = farm::farm_requested(o.farm);
  const std::uint64_t call_pixels =
      t.farm_mode ? std::uint64_t(std::min<std::int64_t>(t.w, o.farm.tile_size)) *
                        std::uint64_t(std::min<std::int64_t>(t.h, o.farm.tile_size))
                  : std::uint64_t(t.w) * std::uint64_t(t.h);
  if (t.w > INT32_MAX || t.h > INT32_MAX || call_pixels > o.pixel_budget)
    throw Error(ErrorKind::Limit, "--size " + o.size + " is " +
                                      std::to_string(std::uint64_t(t.w) * std::uint64_t(t.h)) +
                                      " pixels, above the pixel budget of " + std::to_string(o.pixel_budget) +
                                      " per call (--pixel-budget; render larger images as tiles)");
  validate_region(t.ox, t.oy, t.w, t.h);
  validate_render_params(o.params);
  t.ext = lower_extension(o.output);
  if (t.ext != "exr" && t.ext != "png" && t.ext != "tif" && t.ext != "tiff")
    usage("output '" + o.output + "': the extension must be .exr, .png, .tif or .tiff");
  if (o.bits != 0 && o.bits != 8 && o.bits != 16 && o.bits != 32) usage("--bits must be 8, 16 or 32");
  t.float_out = t.ext == "exr" || o.bits == 32;
  if (t.ext == "exr" && o.bits == 8) usage("--bits 8 is not available for .exr (16: half, 32: float)");
  if (t.ext == "png" && o.bits == 32) usage("--bits 32 is not available for .png (8 or 16)");
  if (o.kernel != "exemplar" && o.kernel != "texton")
    usage("unknown --kernel '" + o.kernel + "' (expected exemplar or texton)");
  // Fail before rendering when the output directory does not exist (the writer would fail at the end).
  const std::filesystem::path parent = std::filesystem::path(o.output).parent_path();
  std::error_code ec;
  if (!t.farm_mode && !parent.empty() && !std::filesystem::is_directory(parent, ec))
    throw Error(ErrorKind::Output, "cannot write '" + o.output + "': directory '" + parent.string() +
                                       "' does not exist");
  return t;
}

// What is rendered: the model's own noise on the device, or (texton models) a comparison mode on the host;
// filtered, through a camera or a UV map.
struct RenderMode {
  std::string mode;          // the model's kind (its own noise) or adsn, dsn, cadsn, cdsn, rpn
  bool own_mode = false;     // the model's own noise, on the device
  bool kernel_mode = false;  // adsn, cadsn, rpn: a kernel filtered on the host
  bool camera = false, mapped = false, filtered = false;
  PerspectiveCamera cam;
  std::string mix_map_spec;  // mix models: the map rendered (provenance)
};

// --mix-map and friends: mix models only. The model's map is replaced (re-encoded, so the renderer sees
// exactly the model a file with that map would hold; the file's SHA-256 stays the provenance).
void apply_mix_map(const RenderCliOptions& o, LoadedModel* model, RenderMode* m) {
  const MixModel* mix = model->as<MixModel>();
  if (!mix) {
    if (!o.mix_map.empty() || o.mix_image_options)
      usage("--mix-map, --mix-scale, --mix-origin and --mix-wrap apply to mix models (stex analyze-mix); '" +
            o.model + "' is a " + model->container.kind + " model");
    return;
  }
  if (o.mix_image_options && o.mix_map.empty())
    usage("--mix-scale, --mix-origin and --mix-wrap place an image mixing map given with --mix-map; without it "
          "they would change nothing (the model's stored map is rendered as stored)");
  if (!o.mix_map.empty()) {
    MixModel changed = *mix;
    changed.map = parse_mix_map(o.mix_map, o.mix_scale, o.mix_origin, o.mix_wrap, o.mix_image_options);
    *model = make_loaded_model(to_container(changed), o.model, model->sha256);
  }
  m->mix_map_spec = mix_map_spec(model->as<MixModel>()->map);
}

// 2. The model's kind decides what --mode and --strategy mean; the usage checks of every combination.
RenderMode choose_mode(const RenderCliOptions& o, const RenderTarget& t, LoadedModel* model) {
  RenderMode m;
  apply_mix_map(o, model, &m);
  const bool texton_kind = model->as<TextonModel>() != nullptr;
  m.mode = o.mode.empty() ? model->container.kind : o.mode;
  m.own_mode = m.mode == model->container.kind;
  const std::string& mode = m.mode;
  if (!texton_kind && !m.own_mode)
    usage("--mode " + mode + " applies to texton models; '" + o.model + "' is a " + model->container.kind +
          " model (render it without --mode)");
  if (texton_kind && !m.own_mode && mode != "adsn" && mode != "dsn" && mode != "cadsn" && mode != "cdsn" &&
      mode != "rpn")
    usage("unknown --mode '" + mode + "' (expected texton, adsn, dsn, cadsn, cdsn or rpn)");
  if (texton_kind) parse_texton_strategy(o.strategy);
  if ((o.mni_given || o.cell_given) && m.own_mode && !model->summary.poisson)
    usage(std::string(o.mni_given ? "--mni" : "--cell") + " does not apply to '" + o.model + "', a " +
          model->container.kind +
          " model: only the kinds driven by a Poisson impulse process read it (texton, gabor, mix, cs-rpn's gabor "
          "and phasor variants)");
  // adsn, cadsn, rpn filter a kernel: the exemplar's t_u or the model's texton kernel (gaussian_synthesis.h).
  m.kernel_mode = mode == "adsn" || mode == "cadsn" || mode == "rpn";
  if (o.kernel == "texton" && !m.kernel_mode) usage("--kernel applies to --mode adsn, cadsn and rpn only");
  if (!o.exemplar.empty() && !(m.kernel_mode && o.kernel == "exemplar"))
    usage("--exemplar applies to --mode adsn, cadsn and rpn with --kernel exemplar (the exemplar whose t_u they "
          "filter)");
  if (t.farm_mode && (mode == "cadsn" || mode == "cdsn" || mode == "rpn"))
    usage("--mode " + mode +
          " is circular on the region's domain, not tile-invariant: --tile-size needs texton or dsn");
  if (texton_kind && !m.own_mode && o.params.scale != 1.0) usage("--scale is only supported with --mode texton");
  if (t.farm_mode && mode == "adsn")
    usage(
        "--mode adsn is tile-invariant only to float rounding (one FFT per tile), not bit for bit: "
        "--tile-size "
        "needs texton or dsn");
  // Filtering: --filter for the flat plane (texton models of any order: the box prefilter), --camera for a
  // perspective view (S1 §5, order 1; filtered unless --no-filter). Texton mode; tiles too, except a UV map (the
  // map is the image).
  // --uv-map is a mapped view like --camera, with the Jacobian from the map's finite differences.
  // A minified flat render of a filterable model is filtered by default too.
  m.camera = !o.camera.empty();
  m.mapped = m.camera || t.uv_mapped;
  // Gabor, lrp and cs-rpn models filter a minified view in closed form (docs/filtering.md), on the same path.
  const bool minified = o.params.scale < 1.0 && m.own_mode && model->filterable();
  m.filtered = o.filter || ((m.mapped || minified) && !o.no_filter);
  if (o.filter && o.no_filter) usage("--filter and --no-filter exclude each other");
  if (o.no_filter && !m.mapped && !minified)
    usage("--no-filter applies where stex filters by default: --camera and --uv-map views, and --scale < 1 on a "
          "model that filters (" + std::string(LoadedModel::filtering_kinds) + "; --mode texton for texton models)");
  if (m.mapped && (!texton_kind || !m.own_mode))
    usage("--camera and --uv-map apply to texton models in --mode texton");
  if (m.filtered && (!m.own_mode || !(texton_kind || model->filterable())))
    usage("--filter applies to " + std::string(LoadedModel::filtering_kinds) + " (texton: --mode texton)");
  if (m.filtered && !m.mapped && !model->mappable() && o.params.scale >= 1.0)
    usage("--filter on a " + model->container.kind + (texton_kind ? " model of order " + std::to_string(model->as<TextonModel>()->order) : std::string(" model")) +
          " filters minified views only (--scale < 1): at --scale " + std::to_string(o.params.scale) +
          " it would change nothing");
  if (t.uv_mapped && t.farm_mode)
    usage("--uv-map renders single images: the map is the image (no --tile-size; a camera view or --filter tiles)");
  if (m.camera && o.params.scale != 1.0) usage("--camera defines the mapping: --scale does not apply");
  if (m.camera) m.cam = parse_camera(o.camera, t.w, t.h);
  if (minified && !m.filtered)
    warn("--scale " + std::to_string(o.params.scale) + " < 1 with --no-filter point-samples the " +
         (texton_kind ? "texton: the render aliases (S1 §5)" : "kernels: the render aliases"));
  else if (o.params.scale < 1.0 && m.own_mode && !m.filtered)
    warn("--scale " + std::to_string(o.params.scale) + " < 1 point-samples this " + model->container.kind +
         " model: the render aliases (filtering applies to " + std::string(LoadedModel::filtering_kinds) + "; the "
         "OpenImageIO plugin's MIP=1 levels are box means, docs/oiio-plugin.md)");
  return m;
}

// Tiles through the farm layer (docs/farm.md): the same pixels, written per tile or out of core.
void render_tiles(const RenderCliOptions& o, const GlobalOptions& global, const RenderTarget& t,
                  const RenderMode& m, const LoadedModel& model) {
  std::unique_ptr<Context> ctx;
  std::unique_ptr<NoiseRenderer> renderer;
  // Filtered renders and camera views (S1 §5) go tile by tile through the request path of single images and
  // `stex serve` (model/render_request.h): a pixel depends on its absolute coordinates only (the camera holds
  // the whole image's size), so tiles join bit for bit. It passes the self-test gate itself.
  std::unique_ptr<ModelRenderers> requests;
  NoiseRendererOptions nro;
  nro.strategy = o.strategy;
  if (m.filtered || m.camera) {
    ctx = Context::create(global.device);
    requests = std::make_unique<ModelRenderers>(*ctx);
  } else if (m.own_mode) {
    ctx = Context::create(global.device);
    renderer = model.make_renderer(*ctx, nro);
    // The known-answer self-test of the path about to be used (runtime/selftest.h): exit 4 if it differs.
    ensure_selftest(*ctx, model.selftest_rows(o.params, nro, ctx->info()));
  }
  const TextonModel* texton = model.as<TextonModel>();  // --mode dsn
  const bool encode_srgb = model.linear && !t.float_out;
  farm::RegionRenderer region = [&](std::int64_t x0, std::int64_t y0, int tw, int th, std::vector<float>& out) {
    if (requests) {
      RenderRequest req = RenderRequest::region(x0, y0, tw, th, o.params, o.strategy,
                                                m.filtered ? FilterMode::On : FilterMode::Off);
      if (m.camera) req.camera = m.cam;
      RenderedPixels px = requests->render(model, req);
      out = std::move(px.pixels);
    } else if (renderer) {
      renderer->render(o.params, x0, y0, tw, th, out.data());
    } else {
      out = synthesize_dsn(*texton, x0, y0, tw, th, o.params.mni, o.params.seed).pixels;
    }
    if (encode_srgb)
      for (float& v : out) v = linear_to_srgb(v);
  };
  char num[64];
  farm::RenderJob job;
  job.width = t.w;
  job.height = t.h;
  job.channels = requests ? model.summary.channels : renderer ? renderer->channels() : texton->channels;
  job.origin_x = t.ox;
  job.origin_y = t.oy;
  job.output = o.output;
  job.model_hash = model.sha256;
  job.seed = o.params.seed;
  job.mni = o.params.mni;
  job.params.emplace_back("mode", m.mode);
  std::snprintf(num, sizeof num, "%.17g", o.params.scale);
  job.params.emplace_back("scale", num);
  std::snprintf(num, sizeof num, "%.17g", o.params.cell_factor);
  job.params.emplace_back("cell", num);
  job.params.emplace_back("encoding", encode_srgb ? "srgb" : "as-rendered");
  if (!m.mix_map_spec.empty()) job.params.emplace_back("mix_map", m.mix_map_spec);
  // Only when used, so the tiles of unfiltered renders keep the parameters they were written with.
  if (m.filtered) job.params.emplace_back("filter", "on");
  if (m.camera) job.params.emplace_back("camera", o.camera);
  job.settings.bits = o.bits;
  job.settings.metadata = {
      {"stex:mode", m.mode}, {"stex:kind", model.container.kind}, {"stex:model_sha256", model.sha256},
      {"stex:filter", m.filtered ? model.filter_name(m.mapped) : "none"}, {"stex:camera", o.camera}};
  farm::FarmOptions fo = o.farm;
  fo.quiet = fo.quiet || global.quiet;
  farm::run(fo, job, region);
}

// A single image and how it was made.
struct RenderedRegion {
  Image img;
  std::vector<SelftestResult> selftest_ran;  // the self-test rows checked now (not cached)
  std::string device_name = "host", strategy;
  double device_ms = 0.0;
};

// The model's own noise on the device, through the render path `stex serve` shares (model/render_request.h).
RenderedRegion render_on_device(const RenderCliOptions& o, const GlobalOptions& global, const RenderTarget& t,
                                const RenderMode& m, const LoadedModel& model) {
  // The CLI filters when asked (or mapped).
  RenderRequest req = RenderRequest::region(t.ox, t.oy, int(t.w), int(t.h), o.params, o.strategy,
                                            m.filtered ? FilterMode::On : FilterMode::Off);
  if (m.camera) req.camera = m.cam;
  if (t.uv_mapped) req.uv_map = &t.uv_map;
  std::unique_ptr<Context> ctx = Context::create(global.device);
  RenderedPixels px = ModelRenderers(*ctx).render(model, req);
  RenderedRegion r;
  r.img = Image{px.width, px.height, px.channels, std::move(px.pixels)};
  r.selftest_ran = std::move(px.selftest_ran);
  r.strategy = std::move(px.strategy);
  r.device_ms = px.device_ms;
  r.device_name = ctx->info().name;
  return r;
}

// The kernel of adsn, cadsn and rpn: the model's texton, or t_u of the exemplar's periodic component.
NormalisedKernel host_kernel(const RenderCliOptions& o, const TextonModel& model) {
  if (o.kernel == "texton") return texton_kernel(model);
  const std::string path = find_exemplar(o, model);
  LoadOptions lo;
  lo.linear = model.linear;
  std::vector<std::string> warnings;
  const Image exemplar = load_exemplar(path, lo, &warnings);
  for (const auto& wmsg : warnings) warn(wmsg);
  if (!model.exemplar_hash.empty() && sha256_file_hex(path) != model.exemplar_hash)
    warn("exemplar '" + path + "' differs from the one the model was analysed from (SHA-256 mismatch)");
  return normalised_kernel(exemplar, true);
}

// The comparison modes of texton models, on the host (analysis/gaussian_synthesis.h).
RenderedRegion render_on_host(const RenderCliOptions& o, const RenderTarget& t, const RenderMode& m,
                              const TextonModel& model) {
  RenderedRegion r;
  r.strategy = m.mode;
  const int w = int(t.w), h = int(t.h);
  if (m.mode == "dsn") {
    r.img = synthesize_dsn(model, t.ox, t.oy, w, h, o.params.mni, o.params.seed);
  } else if (m.mode == "cdsn") {
    r.img = synthesize_cdsn(model, t.ox, t.oy, w, h, o.params.mni, o.params.seed, o.pixel_budget);
  } else {
    const NormalisedKernel kernel = host_kernel(o, model);
    if (m.mode == "adsn")
      r.img = synthesize_adsn_z2(kernel, t.ox, t.oy, w, h, o.params.seed, o.pixel_budget);
    else if (m.mode == "cadsn")
      r.img = synthesize_cadsn(kernel, t.ox, t.oy, w, h, o.params.seed, o.pixel_budget);
    else
      r.img = synthesize_rpn(kernel, t.ox, t.oy, w, h, o.params.seed, o.pixel_budget);
  }
  return r;
}

// 3. Writes atomically, with provenance; returns the number of values clamped.
std::size_t write_render(const RenderCliOptions& o, const RenderTarget& t, const RenderMode& m,
                         const LoadedModel& model, const RenderedRegion& r) {
  WriteOptions wo;
  wo.bits = o.bits;
  // A model analysed in linear light renders linear values: float outputs keep them (EXR is linear by
  // convention), integer outputs are encoded to sRGB.
  wo.encode_srgb = model.linear && !t.float_out;
  RenderProvenance prov;
  prov.model_sha256 = model.sha256;
  prov.mode = m.mode;
  prov.kind = model.container.kind;
  prov.strategy = r.strategy;
  prov.exemplar_name = model_exemplar_name(model.container);
  prov.params = o.params;
  prov.x = t.ox;
  prov.y = t.oy;
  prov.filter = m.filtered ? model.filter_name(m.mapped) : "none";
  prov.camera = o.camera;
  prov.uv_map = o.uv_map;
  prov.mix_map = m.mix_map_spec;
  wo.metadata = render_metadata(prov);
  return write_image_atomic(o.output, r.img, wo);
}

// The one-line summary (and the clamping note) on stdout.
void report_render(const RenderCliOptions& o, const RenderTarget& t, const RenderedRegion& r, std::size_t clamped,
                   std::chrono::steady_clock::time_point t_start) {
  const double wall_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_start).count();
  if (clamped > 0)
    std::printf("note: %zu of %zu values were outside [0, 1] and clamped for the %s-bit %s output (use .exr to "
                "keep them)\n",
                clamped, r.img.pixels.size(), o.bits == 16 ? "16" : "8", t.ext.c_str());
  std::string checked;
  for (const SelftestResult& s : r.selftest_ran) {
    char ms[32];
    std::snprintf(ms, sizeof ms, "%.0f", s.ms);
    checked += (checked.empty() ? ", self-test " : "; ") + s.row.name() + " passed in " + ms + " ms";
  }
  std::printf("rendered %" PRId64 "x%" PRId64 " at (%" PRId64 ", %" PRId64 ") -> %s: device %s, strategy %s, device "
              "%.1f ms, wall %.1f ms%s\n",
              t.w, t.h, t.ox, t.oy, o.output.c_str(), r.device_name.c_str(), r.strategy.c_str(), r.device_ms,
              wall_ms, checked.c_str());
}

// `stex render`: options -> target and mode (every usage check before the device), then one of three paths.
void run_render(const RenderCliOptions& o, const GlobalOptions& global) {
  const auto t_start = std::chrono::steady_clock::now();
  const RenderTarget t = plan_target(o);
  LoadedModel model = load_model_file(o.model, /*defer_unknown_kind=*/true);  // usage errors come first
  const RenderMode m = choose_mode(o, t, &model);
  if (t.farm_mode) return render_tiles(o, global, t, m, model);
  const RenderedRegion r = m.own_mode ? render_on_device(o, global, t, m, model)
                                      : render_on_host(o, t, m, *model.as<TextonModel>());
  const std::size_t clamped = write_render(o, t, m, model, r);
  if (!global.quiet) report_render(o, t, r, clamped, t_start);
}

}  // namespace

void add_render(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<RenderCliOptions>();
  auto* sub = app.add_subcommand(
      "render",
      "Render a region of a model of any kind (texton, lrp, gabor, mix, cs-spot, tb, cs-tb, cs-rpn; unbounded, "
      "seamless, deterministic: a pixel depends only on the "
      "model, the parameters, the seed and its coordinates). Output format by extension: .exr keeps float values; "
      ".png/.tif are 8-bit (or --bits 16) and clamp to [0, 1] (the count is reported). Models analysed with "
      "--linear render linear light: .exr keeps it, .png/.tif are encoded to sRGB.");
  sub->add_option("model", o->model, "Model file (.stex) from `stex analyze`")->required();
  sub->add_option("-o,--output", o->output, "Output image (.exr, .png, .tif)")->required();
  sub->add_option("--size", o->size, "Output size WIDTHxHEIGHT in pixels (required, except with --uv-map)");
  sub->add_option("--origin", o->origin, "Top-left output pixel X,Y (64-bit integers; default 0,0)");
  sub->add_option("--scale", o->params.scale,
                  "Output pixels per exemplar pixel, in [1/1024, 1024] (default 1; below 1, texton, gabor, lrp and "
                  "cs-rpn models are filtered unless --no-filter, and the other kinds alias with a warning: "
                  "docs/filtering.md)");
  sub->add_flag("--filter", o->filter,
                "Filter minified views: texton (any order) by the texton convolved with the pixel's box (exact), "
                "texton camera and UV-map views (order 1) by S1 §5 (MIP pyramid of the texton, trilinear plus "
                "anisotropic probes along the pixel footprint's major axis), gabor by convolving "
                "each kernel with the pixel's Gaussian footprint, lrp and cs-rpn (not phasor) by fading each cosine "
                "by its transfer (S3 §6.4; --scale < 1; docs/filtering.md). The default at --scale < 1 and for "
                "--camera and --uv-map views");
  sub->add_option("--camera", o->camera,
                  "HEIGHT,TILT,FOV: render a perspective view of the textured plane (camera HEIGHT exemplar pixels "
                  "above plane point (0,0), looking towards +y, TILT degrees from straight down in [0, 89], "
                  "vertical field of view FOV degrees over --size's height; sky above the horizon is the mean), "
                  "filtered per pixel from the view's UV Jacobian");
  sub->add_option("--uv-map", o->uv_map,
                  "UV map image (EXR or another float format, at least 2x2): channels 0 and 1 of pixel (i, j) are the "
                  "plane point (u, v), in exemplar pixels, that output pixel (i, j) shows; the output has the map's "
                  "size. Filtered per pixel (S1 §5) with the UV Jacobian from finite differences of neighbouring "
                  "pixels (central inside, one-sided on the border); NaN/Inf values are an input error");
  sub->add_flag("--no-filter", o->no_filter,
                "With --scale < 1 (texton order 1, gabor, lrp, cs-rpn), --camera or --uv-map: point-sample every pixel "
                "instead of "
                "filtering (shows the aliasing)");
  sub->add_option("--mni", o->params.mni,
                  "Mean number of impacts per pixel, in (0, 10000] (default 30, S1 §9): lambda = MNI / r^2");
  sub->add_option("--seed", o->params.seed, "64-bit seed of the impulse process (default 0)");
  sub->add_option("--cell", o->params.cell_factor,
                  "Grid cell side as a fraction of the texton size r, in [0.1, 2] (default 0.6, S1 §8)");
  sub->add_option("--strategy", o->strategy,
                  "auto, splat, gather or gather-local; outputs are identical. splat: blocks of pixels per "
                  "work-item (auto on CPU devices); gather: one work-item per pixel (auto on other devices); "
                  "gather-local: gather with a work-group sharing its tile's impulses in local memory (auto on "
                  "GPUs; the plain gather if they do not fit). lrp models: gather (auto on GPUs) or gather-padded "
                  "(auto on CPU devices: cosine chunks computed whole, which CPU compilers vectorise)");
  sub->add_option(
      "--mode", o->mode,
      "texton (default); on the host, scale 1 (S2 §2.1-2.2, docs/s2.md): adsn: Gaussian texture on Z^2, "
      "kernel * white noise (tile-invariant to float rounding); cadsn: the same, circular on the region "
      "(at least the kernel's size); rpn: random phase noise of the kernel, circular; dsn: discrete spot "
      "noise of the texton on Z^2 (tile-invariant); cdsn: the same, circular");
  sub->add_option(
      "--kernel", o->kernel,
      "Kernel of adsn, cadsn, rpn: exemplar (default: t_u of the exemplar's periodic component, needs "
      "the exemplar) or texton (the model's texton, whose ADSN has the texton noise covariance)");
  sub->add_option("--exemplar", o->exemplar,
                  "Exemplar for --mode adsn|cadsn|rpn (default: the model's, beside the model)");
  sub->add_option("--bits", o->bits, "8 or 16 for .png/.tif, 16 (half) or 32 for .exr (default 8 / 32)");
  sub->add_option("--pixel-budget", o->pixel_budget,
                  "Largest output in pixels for one call (default 2^28); larger renders are tiles");
  sub->add_option("--mix-map", o->mix_map,
                  "Mix models (stex analyze-mix, S1 §7): the mixing map rho(x), replacing the model's, in output "
                  "pixels: const:RHO, ramp:X0:X1 (rho 0 at x = X0 to 1 at x = X1; quantised to the model's levels "
                  "these are S1 Fig. 5's strips), strips:PERIOD[:WIDTH] (rho 0 then 1 each half period, edges "
                  "ramped over WIDTH), or a grey image file (0 = exemplar A, 1 = B; bilinear). Each impulse uses "
                  "the texton of the level nearest to rho at the impulse; the mean is (1 - rho) m0 + rho m1");
  sub->add_option("--mix-scale", o->mix_scale, "Image mixing maps: output pixels per map pixel (default 1)");
  sub->add_option("--mix-origin", o->mix_origin,
                  "Image mixing maps: output pixel X,Y of the map's top-left corner (default 0,0)");
  sub->add_option("--mix-wrap", o->mix_wrap, "Image mixing maps: repeat (default) or clamp outside the map");
  farm::add_farm_options(sub, o->farm);
  sub->footer(farm::exit_code_help());
  sub->callback([o, sub, &global] {
    o->mix_image_options = sub->count("--mix-scale") || sub->count("--mix-origin") || sub->count("--mix-wrap");
    o->mni_given = sub->count("--mni") > 0;
    o->cell_given = sub->count("--cell") > 0;
    run_render(*o, global);
  });
}

}  // namespace stex::cli
