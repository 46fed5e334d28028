// Command-line options of farm rendering, shared by `stex render` and any other command (or test helper)
// that renders through farm::run: one call registers them on a CLI11 (sub)command.
#pragma once
#include <CLI/CLI.hpp>

#include "farm/batch.h"

namespace stex::farm {

// Registers --tile-size, --tiles, --tile-index, --task-index, --tiles-per-task, --skip-existing, --update,
// --force, --dry-run, --progress, --compression and --json (group "Farm"), bound to `options`.
void add_farm_options(CLI::App* app, FarmOptions& options);

// True when any farm option was given: the command should render through farm::run. Error(Usage) when a
// farm option was given without --tile-size.
bool farm_requested(const FarmOptions& options);

// The exit-code table (docs/farm.md), for --help footers.
const char* exit_code_help();

}  // namespace stex::farm
