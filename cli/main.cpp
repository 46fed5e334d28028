// Entry point of the `stex` CLI: registers the subcommands; cli/app_main.h maps errors to documented exit
// codes (core/error.h, README "Exit codes"). No exception escapes main.
#include <string>

#include "cli/app_main.h"
#include "runtime/device.h"

int main(int argc, char** argv) {
  // Before any OpenCL call: PoCL's kernel cache in a per-user stex directory unless POCL_CACHE_DIR is set.
  stex::configure_kernel_cache();
  CLI::App app{"stex: texture noise by example on OpenCL devices"};
  app.set_version_flag("--version", std::string("stex ") + STEX_VERSION_STRING);
  app.require_subcommand(1);
  app.fallthrough();  // global options (--device, -q) are accepted after the subcommand too
  stex::cli::GlobalOptions global;
  stex::cli::add_global_options(app, global);
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
  stex::cli::add_periods(app, global);
  return stex::cli::run_app(app, argc, argv, "stex");
}
