// `stex demo-rng -o out.png --size WxH --seed N [--cell P] [--origin X,Y]`: renders the counter-based RNG
// (kernels/shared/rng.h) as an RGB8 image through the runtime and kernels/rng_test.cl (kernel rng_image):
// each cell of P x P pixels shows the top bytes of its draw 0 in STEX_DOMAIN_TEST. A small real kernel on the
// selected device, used as the demo until texton rendering lands. The origin is a 64-bit pixel coordinate,
// so the picture at 10^12 is as good as at 0. Written atomically (temp file beside the target, renamed).
#include <OpenImageIO/imageio.h>

#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/program.h"

namespace stex::cli {

namespace {

// The demo writes one image in memory; keep it to a size any machine handles (16384 x 16384 RGB8 = 768 MiB).
constexpr std::int64_t k_max_pixels = std::int64_t(16384) * 16384;

struct DemoRngOptions {
  std::string output;
  std::string size = "512x512";
  std::uint64_t seed = 0;
  std::uint32_t cell = 1;
  std::vector<std::int64_t> origin{0, 0};
};

void parse_size(const std::string& text, std::int64_t* w, std::int64_t* h) {
  auto bad = [&](const std::string& why) {
    return Error(ErrorKind::Usage, "--size '" + text + "': " + why + " (expected WxH, e.g. 512x512)");
  };
  const std::size_t x = text.find_first_of("xX");
  if (x == std::string::npos) throw bad("missing 'x'");
  auto number = [&](const std::string& s) -> std::int64_t {
    if (s.empty() || s.size() > 9 || s.find_first_not_of("0123456789") != std::string::npos)
      throw bad("'" + s + "' is not a positive integer");
    return std::stoll(s);
  };
  *w = number(text.substr(0, x));
  *h = number(text.substr(x + 1));
  if (*w <= 0 || *h <= 0) throw bad("width and height must be positive");
  if (*w * *h > k_max_pixels)
    throw Error(ErrorKind::Limit, "--size '" + text + "': " + std::to_string(*w * *h) +
                                      " pixels exceed the demo's " + "limit of " +
                                      std::to_string(k_max_pixels));
}

std::string extension_of(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return path.substr(dot);
}

void write_rgb8(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb) {
  const std::string ext = extension_of(path);
  TempOutput temp(path);
  const std::string& tmp = temp.path();
  auto fail = [&](const std::string& why) {
    temp.discard();
    return Error(ErrorKind::Output, "cannot write '" + path + "': " + why);
  };
  auto out = OIIO::ImageOutput::create(tmp);
  if (!out) throw fail("no image writer for '" + ext + "': " + OIIO::geterror());
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("Software", std::string("stex ") + STEX_VERSION_STRING + " demo-rng");
  if (!out->open(tmp, spec)) throw fail(out->geterror());
  if (!out->write_image(OIIO::TypeDesc::UINT8, rgb.data())) {
    std::string err = out->geterror();
    out->close();
    throw fail(err);
  }
  if (!out->close()) throw fail(out->geterror());
  temp.commit();
}

void run_demo_rng(const GlobalOptions& global, const DemoRngOptions& opt) {
  std::int64_t width = 0, height = 0;
  parse_size(opt.size, &width, &height);
  if (opt.cell == 0) throw Error(ErrorKind::Usage, "--cell must be at least 1 pixel");
  if (opt.origin.size() != 2) throw Error(ErrorKind::Usage, "--origin takes two integers X,Y");
  const std::int64_t x0 = opt.origin[0], y0 = opt.origin[1];
  // The kernel computes x0 + x in int64: the last pixel must not overflow.
  if (x0 > std::numeric_limits<std::int64_t>::max() - (width - 1) ||
      y0 > std::numeric_limits<std::int64_t>::max() - (height - 1))
    throw Error(ErrorKind::Usage, "--origin " + std::to_string(x0) + "," + std::to_string(y0) +
                                      " with --size " + opt.size + " overflows 64-bit pixel coordinates");

  // Fail on an unknown output format before any device work.
  if (!OIIO::ImageOutput::create(opt.output))
    throw Error(ErrorKind::Output, "cannot write '" + opt.output + "': " + OIIO::geterror());

  std::unique_ptr<Context> ctx = Context::create(global.device);
  Program& program = ctx->program("rng_test.cl");
  Kernel kernel(program, "rng_image");
  const std::size_t pixels = std::size_t(width) * std::size_t(height);
  Buffer<unsigned char> rgb(*ctx, pixels * 3, CL_MEM_WRITE_ONLY, "demo-rng image");
  kernel.set_arg(0, cl_long(x0));
  kernel.set_arg(1, cl_long(y0));
  kernel.set_arg(2, cl_uint(opt.cell));
  kernel.set_arg(3, cl_uint(opt.seed & 0xffffffffu));
  kernel.set_arg(4, cl_uint(opt.seed >> 32));
  kernel.set_arg(5, rgb);
  const double ms = kernel.launch(*ctx, NDRange(std::size_t(width), std::size_t(height)));
  const std::vector<unsigned char> host = rgb.read();
  write_rgb8(opt.output, int(width), int(height), host);
  if (!global.quiet)
    std::printf("wrote %s: %lldx%lld, seed %llu, device '%s', build %.3f s, kernel %.3f ms\n",
                opt.output.c_str(), static_cast<long long>(width), static_cast<long long>(height),
                static_cast<unsigned long long>(opt.seed), ctx->info().name.c_str(), program.build_seconds(),
                ms);
}

}  // namespace

void add_demo_rng(CLI::App& app, GlobalOptions& global) {
  auto* sub = app.add_subcommand("demo-rng", "Render the counter-based RNG as an image on the OpenCL device");
  auto opt = std::make_shared<DemoRngOptions>();
  sub->add_option("-o,--output", opt->output, "Output image (format by extension: .png, .exr, .tif, ...)")
      ->required();
  sub->add_option("--size", opt->size, "Image size WxH")->capture_default_str();
  sub->add_option("--seed", opt->seed, "64-bit seed")->capture_default_str();
  sub->add_option("--cell", opt->cell, "Cell size in pixels (each cell shows one draw)")
      ->capture_default_str();
  sub->add_option("--origin", opt->origin, "Top-left pixel X,Y (64-bit)")->delimiter(',')->expected(2);
  sub->callback([&global, opt] { run_demo_rng(global, *opt); });
}

}  // namespace stex::cli
