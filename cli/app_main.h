// The entry of a stex executable (`stex`, and `stex-bench` which `stex bench` runs): the global options, the
// kernel cache, and the mapping of errors to the documented exit codes (core/error.h, README "Exit codes").
// No exception escapes run_app.
#pragma once
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <new>
#include <string>

#include "cli/commands.h"
#include "core/error.h"

namespace stex::cli {

// --device (or $STEX_DEVICE) and -q, accepted before or after a subcommand.
inline void add_global_options(CLI::App& app, GlobalOptions& global) {
  app.add_option("--device", global.device,
                 "OpenCL device: cpu, gpu, an index, or a name substring (default: $STEX_DEVICE, else the "
                 "first GPU, else the first CPU device)")
      ->envname("STEX_DEVICE");
  app.add_flag("-q,--quiet", global.quiet, "Print only errors");
}

// Parses and runs; returns the process's exit code. `program` prefixes error messages ("stex").
inline int run_app(CLI::App& app, int argc, char** argv, const char* program) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : static_cast<int>(ErrorKind::Usage);
  } catch (const Error& e) {
    std::fprintf(stderr, "%s: error: %s\n", program, e.what());
    return e.exit_code();
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "%s: error: out of memory\n", program);
    return static_cast<int>(ErrorKind::Limit);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: internal error: %s\n", program, e.what());
    return static_cast<int>(ErrorKind::Internal);
  }
  return 0;
}

}  // namespace stex::cli
