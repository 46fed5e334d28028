// Tiling and blending: validation, setup, reference, renderer. See tb.h and kernels/shared/tb.h.
#include "runtime/tb.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/math.h"
#include "runtime/chunked_gather.h"
#include "runtime/cs_spot.h"

namespace stex {

static_assert(sizeof(stex_tb_params) == 216, "stex_tb_params must match the OpenCL layout (216 bytes)");

namespace {
constexpr double k_fix_one = double(std::int64_t(1) << STEX_CS_FIX_BITS);
constexpr std::size_t k_tb_pad = 16;  // STEX_TB_PAD of kernels/tb.cl
constexpr int k_tb_run = 128;        // STEX_TB_RUN x STEX_TB_BLOCKS of kernels/tb.cl: pixels a work-item
}  // namespace

void validate_tb_model(const TbModel& m) {
  auto bad = [&](const std::string& what) {
    throw Error(ErrorKind::Input, std::string("invalid ") + (m.cs ? "cs-tb" : "tb") + " model: " + what);
  };
  if (m.channels < 1 || m.channels > STEX_TB_MAX_CHANNELS) bad("channels must be 1..4");
  if (m.width < 8 || m.height < 8 || m.width > 4096 || m.height > 4096) bad("the exemplar must be 8..4096 pixels on each side");
  if (!std::isfinite(m.tile) || m.tile < 2.0 || 2.0 * m.tile + 4.0 > std::min(m.width, m.height))
    bad("tile must be at least 2 pixels and 2 tile + 4 at most the exemplar's smaller side");
  if (m.gauss.size() != std::size_t(m.width) * m.height * m.channels) bad("gauss size does not match the exemplar");
  if (m.lut_size < 2 || m.lut_size > 65536) bad("lut_size must be 2..65536");
  if (!std::isfinite(m.lut_lo) || !std::isfinite(m.lut_hi) || !(m.lut_hi > m.lut_lo)) bad("lut range must be finite, lo < hi");
  if (m.lut.size() != std::size_t(m.lut_size) * m.channels) bad("lut size does not match channels x lut_size");
  if (m.pca.size() != std::size_t(m.channels) * (m.channels + 1)) bad("pca must have channels x (channels + 1) floats");
  for (const auto* v : {&m.gauss, &m.lut, &m.pca, &m.mean})
    for (float f : *v)
      if (!std::isfinite(f) || std::fabs(f) > 1e30f) bad("a non-finite value");
  if (m.n0 < 1 || m.n1 < 1 || m.n0 > 4096 || m.n1 > 4096 || m.mean.size() != std::size_t(m.n0) * m.n1 * m.channels)
    bad("the mean grid does not match n0 x n1 x channels");
  if (m.cs) {
    validate_model_periods("cs-tb", m.t0x, m.t0y, m.t1x, m.t1y);
    const double bw = m.width - 2.0 * (m.tile + 1.0), bh = m.height - 2.0 * (m.tile + 1.0);
    if (bw < std::fabs(m.t0x) + std::fabs(m.t1x) + 1.0 || bh < std::fabs(m.t0y) + std::fabs(m.t1y) + 1.0)
      bad("the exemplar minus a tile's radius on each side must hold a whole parallelogram of the periods: use a smaller tile");
  }
  validate_cs_hist(m.hist, m.channels, m.width, m.height, std::string("invalid ") + (m.cs ? "cs-tb" : "tb") + " model");
  if (m.hist.enabled() && (!m.cs || m.hist.mode != 2))
    bad("only cs-tb carries a histogram table, of mode cs (the stationary transfer is the LUT)");
}

TbSetup make_tb_setup(const TbModel& m, const RenderParams& rp) {
  validate_tb_model(m);
  validate_render_params(rp);
  TbSetup out;
  stex_tb_params& p = out.params;
  const double fs = k_fix_one * rp.scale;
  const std::int64_t g0x = std::llround(m.tile * fs), g0y = 0;
  const std::int64_t g1x = std::llround(0.5 * m.tile * fs), g1y = std::llround(0.5 * std::sqrt(3.0) * m.tile * fs);
  auto inv = [](std::int64_t ax, std::int64_t ay, std::int64_t bx, std::int64_t by, float* i) {
    const double det = double(ax) * double(by) - double(ay) * double(bx);
    i[0] = float(double(by) / det);
    i[1] = float(-double(bx) / det);
    i[2] = float(-double(ay) / det);
    i[3] = float(double(ax) / det);
  };
  p.seed_lo = stex_lo32(static_cast<stex_i64>(rp.seed));
  p.seed_hi = stex_hi32(static_cast<stex_i64>(rp.seed));
  p.g0x_lo = stex_lo32(g0x);
  p.g0x_hi = stex_hi32(g0x);
  p.g0y_lo = stex_lo32(g0y);
  p.g0y_hi = stex_hi32(g0y);
  p.g1x_lo = stex_lo32(g1x);
  p.g1x_hi = stex_hi32(g1x);
  p.g1y_lo = stex_lo32(g1y);
  p.g1y_hi = stex_hi32(g1y);
  float gi[4];
  inv(g0x, g0y, g1x, g1y, gi);
  p.gi00 = gi[0];
  p.gi01 = gi[1];
  p.gi10 = gi[2];
  p.gi11 = gi[3];
  // tb_run's triangle test relies on these (kernels/tb.cl): fa grows along a row, fb is the row's constant.
  if (!(p.gi00 > 0.0f) || p.gi10 != 0.0f)
    throw Error(ErrorKind::Internal, "tb: the triangle grid's inverse basis is not row-aligned");
  out.reduce_grid = cs_reduce_table(g0x, g0y, g1x, g1y);
  // stex_tb_canon's exact step needs |T| <= 2^28 fixed units (4096 output pixels).
  constexpr double k_max_fix = double(std::int64_t(1) << 28);
  if (m.tile * fs > k_max_fix) throw Error(ErrorKind::Usage, "tile x scale must be at most 4096 output pixels");
  const std::int64_t gdet = g0x * g1y - g0y * g1x;
  p.gdet_lo = stex_lo32(gdet);
  p.gdet_hi = stex_hi32(gdet);
  p.tdet_lo = p.tdet_hi = 0;
  p.inv_fix_scale = float(1.0 / fs);
  p.box_x0 = float(m.tile + 1.0);
  p.box_y0 = float(m.tile + 1.0);
  p.box_x1 = float(m.width - m.tile - 1.0);
  p.box_y1 = float(m.height - m.tile - 1.0);
  // tb's centres in model fixed units: the box [tile + 1, size - tile - 1] (at least 2 pixels wide).
  p.bfx0 = stex_i32(std::ceil((m.tile + 1.0) * k_fix_one));
  p.bfy0 = p.bfx0;
  p.bfx1 = stex_i32(std::floor((m.width - m.tile - 1.0) * k_fix_one));
  p.bfy1 = stex_i32(std::floor((m.height - m.tile - 1.0) * k_fix_one));
  p.unit_scale = rp.scale == 1.0 ? 1 : 0;
  p.inv_scale = float(1.0 / rp.scale);
  out.aligned = p.unit_scale && !m.cs;
  p.ex_w = m.width;
  p.ex_h = m.height;
  p.channels = m.channels;
  p.lut_size = m.lut_size;
  p.cs = m.cs ? 1 : 0;
  p.n0 = m.n0;
  p.n1 = m.n1;
  p.lut_lo = float(m.lut_lo);
  p.lut_hi = float(m.lut_hi);
  out.hist_params = cs_hist_params(m.hist);
  out.hist = cs_hist_device_table(m.hist);
  if (m.cs) {
    const std::int64_t t0x = std::llround(m.t0x * fs), t0y = std::llround(m.t0y * fs);
    const std::int64_t t1x = std::llround(m.t1x * fs), t1y = std::llround(m.t1y * fs);
    set_period_words(p, t0x, t0y, t1x, t1y);
    float ti[4];
    inv(t0x, t0y, t1x, t1y, ti);
    p.ti00 = ti[0];
    p.ti01 = ti[1];
    p.ti10 = ti[2];
    p.ti11 = ti[3];
    out.reduce_cs = cs_reduce_table(t0x, t0y, t1x, t1y);
    if (std::max({std::fabs(m.t0x), std::fabs(m.t0y), std::fabs(m.t1x), std::fabs(m.t1y)}) * fs > k_max_fix)
      throw Error(ErrorKind::Usage, "periods x scale must be at most 4096 output pixels");
    const std::int64_t tdet = t0x * t1y - t0y * t1x;
    p.tdet_lo = stex_lo32(tdet);
    p.tdet_hi = stex_hi32(tdet);
    // Integer periods at scale 1: the nodes' coordinates are multiples of 65536, so v - U = v (mod 65536).
    const std::int64_t one = std::int64_t(1) << STEX_CS_FIX_BITS;
    out.aligned = p.unit_scale && t0x % one == 0 && t0y % one == 0 && t1x % one == 0 && t1y % one == 0;
    // Node window: v's residual is in the base cell; v - U must land in the box (fixed units).
    const double det = double(t0x) * double(t1y) - double(t0y) * double(t1x);
    set_node_window(p, double(p.box_x0) * fs, double(p.box_y0) * fs, double(p.box_x1) * fs, double(p.box_y1) * fs,
                    [&](double x, double y, double* a, double* b) {
                      *a = (double(t1y) * x - double(t1x) * y) / det;
                      *b = (-double(t0y) * x + double(t0x) * y) / det;
                    });
  } else {
    out.reduce_cs = out.reduce_grid;  // unused
  }
  return out;
}

void tb_start_nodes(const TbSetup& s, std::int64_t px, std::int64_t py, std::int64_t* st) {
  const stex_tb_params& p = s.params;
  const std::int64_t x = stex_cs_pixel_fix(px), y = stex_cs_pixel_fix(py);
  std::int64_t rx, ry;
  stex_tb_base(s.reduce_grid.data(), stex_join64(p.g0x_lo, p.g0x_hi), stex_join64(p.g0y_lo, p.g0y_hi),
               stex_join64(p.g1x_lo, p.g1x_hi), stex_join64(p.g1y_lo, p.g1y_hi), p.gi00, p.gi01, p.gi10, p.gi11, x, y,
               &st[0], &st[1], &rx, &ry);
  st[2] = st[3] = 0;
  if (p.cs)
    stex_tb_base(s.reduce_cs.data(), stex_join64(p.t0x_lo, p.t0x_hi), stex_join64(p.t0y_lo, p.t0y_hi),
                 stex_join64(p.t1x_lo, p.t1x_hi), stex_join64(p.t1y_lo, p.t1y_hi), p.ti00, p.ti01, p.ti10, p.ti11, x, y,
                 &st[2], &st[3], &rx, &ry);
}

void tb_canonical(const TbSetup& s, std::int64_t px, std::int64_t py, std::int64_t* n, std::int64_t* r) {
  const stex_tb_params& p = s.params;
  std::int64_t st[4];
  tb_start_nodes(s, px, py, st);
  const std::int64_t x = stex_cs_pixel_fix(px), y = stex_cs_pixel_fix(py);
  stex_tb_canon(stex_join64(p.g0x_lo, p.g0x_hi), stex_join64(p.g0y_lo, p.g0y_hi), stex_join64(p.g1x_lo, p.g1x_hi),
                stex_join64(p.g1y_lo, p.g1y_hi), stex_join64(p.gdet_lo, p.gdet_hi), p.gi00, p.gi01, p.gi10, p.gi11, x, y,
                st[0], st[1], &n[0], &n[1], &r[0], &r[1]);
  n[2] = n[3] = r[2] = r[3] = 0;
  if (p.cs)
    stex_tb_canon(stex_join64(p.t0x_lo, p.t0x_hi), stex_join64(p.t0y_lo, p.t0y_hi), stex_join64(p.t1x_lo, p.t1x_hi),
                  stex_join64(p.t1y_lo, p.t1y_hi), stex_join64(p.tdet_lo, p.tdet_hi), p.ti00, p.ti01, p.ti10, p.ti11, x,
                  y, st[2], st[3], &n[2], &n[3], &r[2], &r[3]);
}

std::vector<float> TbReference::render(std::int64_t x, std::int64_t y, int width, int height) const {
  validate_region(x, y, width, height);
  const int ch = model_.channels;
  std::vector<float> out(std::size_t(width) * height * ch);
  float v[STEX_TB_MAX_CHANNELS];
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      // Start nodes of this very pixel (the kernel uses its chunk's: the canonical base makes them agree).
      std::int64_t st[4];
      tb_start_nodes(setup_, x + i, y + j, st);
      stex_tb_eval(setup_.params, model_.gauss.data(), model_.lut.data(), model_.pca.data(), model_.mean.data(),
                   setup_.hist_params, setup_.hist.data(), stex_cs_pixel_fix(x + i), stex_cs_pixel_fix(y + j), st[0], st[1], st[2], st[3], v);
      for (int c = 0; c < ch; ++c) out[(std::size_t(j) * width + i) * ch + c] = v[c];
    }
  return out;
}

TbNoise::TbNoise(Context& ctx, const TbModel& model, const NoiseRendererOptions& options)
    : ctx_(ctx), model_(model), setup_(make_tb_setup(model, RenderParams{})) {
  if (options.strategy != "auto" && options.strategy != "gather")
    throw Error(ErrorKind::Usage, "unknown strategy '" + options.strategy + "' for " + kind() + " (expected auto or gather)");
  gauss_ = Buffer<float>(ctx_, model_.gauss, CL_MEM_READ_ONLY, "tb exemplar");
  lut_ = Buffer<float>(ctx_, model_.lut, CL_MEM_READ_ONLY, "tb lut");
  pca_ = Buffer<float>(ctx_, model_.pca, CL_MEM_READ_ONLY, "tb pca");
  mean_ = Buffer<float>(ctx_, model_.mean, CL_MEM_READ_ONLY, "tb mean");
  hist_ = Buffer<float>(ctx_, setup_.hist, CL_MEM_READ_ONLY, "tb histogram table");
}

NoiseRenderStats TbNoise::render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                                 float* out) {
  validate_region(x, y, width, height);
  if (params != setup_params_) {
    setup_ = make_tb_setup(model_, params);
    setup_params_ = params;
  }
  const int al = setup_.aligned ? 1 : 0, unit = setup_.params.unit_scale ? 1 : 0;
  const int variant = al ? 2 : unit;  // aligned implies scale 1
  if (!kernel_[variant]) {
    // Channels, kind, alignment and scale 1 are compile-time constants of the kernels (their loops unroll).
    const std::string options = "-DSTEX_TB_CH=" + std::to_string(model_.channels) + " -DSTEX_TB_CS=" +
                                (model_.cs ? "1" : "0") + " -DSTEX_TB_ALIGNED=" + std::to_string(al) +
                                " -DSTEX_TB_UNIT=" + std::to_string(unit);
    Program& program = ctx_.program("tb.cl", options);
    kernel_[variant] = std::make_unique<Kernel>(program, "tb");
    vertex_kernel_[variant] = std::make_unique<Kernel>(program, "tb_vertices");
  }
  // The run kernel: tb or cs-tb at any scale (aligned: one vloadN per vertex and channel; else bilinear
  // gathers), with g0x >= 8 output pixels (a run meets 2 columns).
  const std::int64_t g0x = stex_join64(setup_.params.g0x_lo, setup_.params.g0x_hi);
  const bool run_ok = g0x >= 8 * std::int64_t(k_fix_one);
  const bool run = run_ok && (run_mode == 1 || (run_mode < 0 && (ctx_.info().type & CL_DEVICE_TYPE_CPU) != 0));
  // 16 lanes need a tile of >= 16 pixels (a run then still meets at most 2 grid columns). Auto picks them
  // whatever the native vector width: a run's scalar work (its canonical step, vertex reads, triangle test)
  // is shared by twice the pixels (BM_Tb16 against BM_Tb8: 0.70-0.77 x on AVX2, 0.83-0.93 x on AVX-512).
  const bool wide = g0x >= 16 * std::int64_t(k_fix_one) && run_lanes != 8;
  if (run && !run_kernel_[variant][wide]) {
    // 8 lanes (the kernel's default): the program above, already built.
    const std::string options = "-DSTEX_TB_CH=" + std::to_string(model_.channels) + " -DSTEX_TB_CS=" +
                                (model_.cs ? "1" : "0") + " -DSTEX_TB_ALIGNED=" + std::to_string(al) +
                                " -DSTEX_TB_UNIT=" + std::to_string(unit) + (wide ? " -DSTEX_TB_LANES=16" : "");
    run_kernel_[variant][wide] = std::make_unique<Kernel>(ctx_.program("tb.cl", options), "tb_run");
  }
  if (run && al && planar_.size() == 0) {  // the aligned path's exemplar (the bilinear path reads gauss_)
    const std::size_t plane = std::size_t(model_.width) * std::size_t(model_.height);
    std::vector<float> planar(std::size_t(model_.channels) * plane + 2 * k_tb_pad, 0.0f);
    for (std::size_t t = 0; t < plane; ++t)
      for (int c = 0; c < model_.channels; ++c)
        planar[k_tb_pad + std::size_t(c) * plane + t] = model_.gauss[t * std::size_t(model_.channels) + std::size_t(c)];
    planar_ = Buffer<float>(ctx_, planar, CL_MEM_READ_ONLY, "tb planar exemplar");
  }
  if (run && lut_pairs_.size() == 0) {
    // The LUT as pairs (T^-1[i], T^-1[i + 1] - T^-1[i]) (float, as stex_tb_lut computes b - a).
    const std::size_t n = std::size_t(model_.lut_size);
    std::vector<float> pairs(2 * n * std::size_t(model_.channels), 0.0f);
    for (std::size_t c = 0; c < std::size_t(model_.channels); ++c)
      for (std::size_t i = 0; i < n; ++i) {
        pairs[2 * (c * n + i)] = model_.lut[c * n + i];
        if (i + 1 < n) pairs[2 * (c * n + i) + 1] = model_.lut[c * n + i + 1] - model_.lut[c * n + i];
      }
    lut_pairs_ = Buffer<float>(ctx_, pairs, CL_MEM_READ_ONLY, "tb lut pairs");
  }
  last_kernel = run ? (wide ? "tb_run16" : "tb_run") : "tb";
  GatherChunking chunking;
  chunking.max_chunk_pixels = max_chunk_pixels ? max_chunk_pixels : default_chunk_pixels(channels());
  // Chunks at most 4096 pixels wide and high: the pixel kernel's residuals from the chunk's first pixel's
  // canonical node stay below 2^30 fixed units (stex_cs_canon_near's 32-bit arithmetic).
  chunking.max_side = 4096;
  if (local_size[0] && local_size[1]) chunking.local = local_size;
  if (run) {
    chunking.pixels_per_item_x = k_tb_run;
    // 8 x 8 work-items: 8 of 128 pixels span a 1024-pixel row (16 x 4 would leave half of each group idle).
    if (!(local_size[0] && local_size[1])) chunking.local = {8, 8};
  }
  chunking.out_buffer = &out_;
  // Per chunk: the canonical nodes of its first pixel and the window of grid vertices its pixels use.
  std::int64_t node[4], res[4];
  int dk_min = 0, dl_min = 0, nk = 0, nl = 0;
  chunking.before_chunk = [&](std::int64_t x0, std::int64_t y0, int w, int h) -> double {
    tb_canonical(setup_, x0, y0, node, res);
    const stex_tb_params& p = setup_.params;
    const double g0x = double(stex_join64(p.g0x_lo, p.g0x_hi)), g1x = double(stex_join64(p.g1x_lo, p.g1x_hi));
    const double g1y = double(stex_join64(p.g1y_lo, p.g1y_hi));  // g0y = 0
    double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
    for (int cj : {0, h - 1})
      for (int ci : {0, w - 1}) {
        const double ax = double(res[0]) + double(ci) * k_fix_one, ay = double(res[1]) + double(cj) * k_fix_one;
        const double b = ay / g1y, a = (ax - b * g1x) / g0x;
        amin = std::min(amin, a);
        amax = std::max(amax, a);
        bmin = std::min(bmin, b);
        bmax = std::max(bmax, b);
      }
    // Margins: 2 cells below (rounding), the vertices' +1 and 2 cells above (the run kernel's last run
    // reaches < 16 pixels, under a cell, past the chunk).
    dk_min = int(std::floor(amin)) - 2;
    dl_min = int(std::floor(bmin)) - 2;
    nk = int(std::floor(amax)) + 3 - dk_min + 1;
    nl = int(std::floor(bmax)) + 3 - dl_min + 1;
    const std::size_t need = std::size_t(al ? 1 : 2) * std::size_t(nk) * std::size_t(nl);
    centres_.reserve(ctx_, need, CL_MEM_READ_WRITE, "tb vertex centres");
    Kernel& vk = *vertex_kernel_[variant];
    cl_uint a = 0;
    vk.set_arg(a++, setup_.params);
    vk.set_arg(a++, cl_long(node[0] + dk_min));
    vk.set_arg(a++, cl_long(node[1] + dl_min));
    vk.set_arg(a++, cl_long(node[2]));
    vk.set_arg(a++, cl_long(node[3]));
    vk.set_arg(a++, cl_int(nk));
    vk.set_arg(a++, cl_int(nl));
    vk.set_arg(a++, cl_long(x0));
    vk.set_arg(a++, cl_long(y0));
    vk.set_arg(a++, centres_);
    if (!vertex_watchdog_) vertex_watchdog_ = std::make_unique<LoopWatchdog>(ctx_);
    return launch_watched(ctx_, vk, *vertex_watchdog_, a, std::size_t(nk), std::size_t(nl), {0, 0});
  };
  // The run kernel (k_tb_run pixels per work-item) reads the planar field when aligned and the LUT in pairs.
  Kernel& kernel = run ? *run_kernel_[variant][wide] : *kernel_[variant];
  return render_gather_chunks(ctx_, kernel, channels(), x, y, width, height, out, chunking,
                              [&](Kernel& k, cl_uint a, std::int64_t, std::int64_t) {
                                k.set_arg(a++, setup_.params);
                                if (run && al)
                                  k.set_arg(a++, planar_);
                                else
                                  k.set_arg(a++, gauss_);
                                if (run)
                                  k.set_arg(a++, lut_pairs_);
                                else
                                  k.set_arg(a++, lut_);
                                k.set_arg(a++, pca_);
                                k.set_arg(a++, mean_);
                                k.set_arg(a++, setup_.hist_params);
                                k.set_arg(a++, hist_);
                                k.set_arg(a++, centres_);
                                k.set_arg(a++, cl_int(nk));
                                k.set_arg(a++, cl_int(nl));
                                k.set_arg(a++, cl_int(dk_min));
                                k.set_arg(a++, cl_int(dl_min));
                                for (int q = 0; q < 4; ++q) k.set_arg(a++, cl_int(res[q]));
                                return a;
                              });
}

}  // namespace stex
