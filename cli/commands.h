// Subcommands of the `stex` CLI. Each add_* registers its subcommand on the app; the callback runs the
// command and throws stex::Error on failure (main.cpp maps it to the exit code of its kind).
#pragma once
#include <CLI/CLI.hpp>

namespace stex::cli {

struct GlobalOptions {
  std::string device;  // --device / STEX_DEVICE: cpu, gpu, an index, or a name substring
  bool quiet = false;
};

void add_info(CLI::App& app, GlobalOptions& global);
void add_analyze(CLI::App& app, GlobalOptions& global);
void add_analyze_mix(CLI::App& app, GlobalOptions& global);
void add_render(CLI::App& app, GlobalOptions& global);
void add_demo_rng(CLI::App& app, GlobalOptions& global);
void add_assemble(CLI::App& app, GlobalOptions& global);
void add_bench(CLI::App& app, GlobalOptions& global);
void add_compare(CLI::App& app, GlobalOptions& global);
void add_s2_report(CLI::App& app, GlobalOptions& global);
void add_surface(CLI::App& app, GlobalOptions& global);
void add_gabor(CLI::App& app, GlobalOptions& global);
void add_cs_rpn(CLI::App& app, GlobalOptions& global);
void add_contrast(CLI::App& app, GlobalOptions& global);
void add_serve(CLI::App& app, GlobalOptions& global);
void add_selftest(CLI::App& app, GlobalOptions& global);
void add_periods(CLI::App& app, GlobalOptions& global);

}  // namespace stex::cli
