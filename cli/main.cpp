// Entry point of the `stex` CLI: registers the subcommands and maps errors to documented exit codes
// (core/error.h, README "Exit codes"). No exception escapes main.
#include <cstdio>
#include <exception>
#include <new>

#include "cli/commands.h"
#include "core/error.h"
#include "runtime/device.h"

int main(int argc, char** argv) {
  // Before any OpenCL call: PoCL's kernel cache in a per-user stex directory unless POCL_CACHE_DIR is set.
  stex::configure_kernel_cache();
  CLI::App app{"stex: texture noise by example on OpenCL devices"};
  app.set_version_flag("--version", std::string("stex ") + STEX_VERSION_STRING);
  app.require_subcommand(1);
  app.fallthrough();  // global options (--device, -q) are accepted after the subcommand too
  stex::cli::GlobalOptions global;
  app.add_option("--device", global.device,
                 "OpenCL device: cpu, gpu, an index, or a name substring (default: $STEX_DEVICE, else the "
                 "first GPU, else the first CPU device)")
      ->envname("STEX_DEVICE");
  app.add_flag("-q,--quiet", global.quiet, "Print only errors");
  stex::cli::add_info(app, global);
  stex::cli::add_analyze(app, global);
  stex::cli::add_analyze_mix(app, global);
  stex::cli::add_render(app, global);
  stex::cli::add_demo_rng(app, global);
  stex::cli::add_assemble(app, global);
  stex::cli::add_bench(app, global);
  stex::cli::add_compare(app, global);
  stex::cli::add_s2_report(app, global);
  stex::cli::add_surface(app, global);
  stex::cli::add_gabor(app, global);
  stex::cli::add_cs_rpn(app, global);
  stex::cli::add_contrast(app, global);
  stex::cli::add_serve(app, global);
  stex::cli::add_selftest(app, global);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int rc = app.exit(e);
    return rc == 0 ? 0 : static_cast<int>(stex::ErrorKind::Usage);
  } catch (const stex::Error& e) {
    std::fprintf(stderr, "stex: error: %s\n", e.what());
    return e.exit_code();
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "stex: error: out of memory\n");
    return static_cast<int>(stex::ErrorKind::Limit);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stex: internal error: %s\n", e.what());
    return static_cast<int>(stex::ErrorKind::Internal);
  }
  return 0;
}
