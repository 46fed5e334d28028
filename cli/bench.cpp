// `stex bench ...`: runs the program `stex-bench` (benchmarks/suite/main.cpp) with the same arguments and
// the global options, so that the benchmark suite and its baselines (OpenMP, FFTW, the S1 kernel's host
// side) are not linked into `stex`. `stex-bench` is looked up next to this executable (the build tree and an
// installed bin/ put them side by side), else $STEX_BENCH names it. `stex bench --help` prints its options.
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "core/error.h"

namespace stex::cli {
namespace {

namespace fs = std::filesystem;

fs::path bench_program() {
  if (const char* env = std::getenv("STEX_BENCH"); env && *env) return env;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw Error(ErrorKind::Internal, "cannot find the stex executable (/proc/self/exe): " + ec.message());
  return self.parent_path() / "stex-bench";
}

[[noreturn]] void exec_bench(const GlobalOptions& global, const std::vector<std::string>& rest) {
  const fs::path program = bench_program();
  std::vector<std::string> args{program.string()};
  if (!global.device.empty()) args.insert(args.end(), {"--device", global.device});
  if (global.quiet) args.push_back("--quiet");
  args.insert(args.end(), rest.begin(), rest.end());
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::fflush(nullptr);
  ::execv(argv[0], argv.data());
  const int err = errno;
  throw Error(ErrorKind::Usage, "stex bench is not available: cannot run '" + program.string() + "' (" +
                                    std::strerror(err) +
                                    "); it is built and installed beside stex unless STEX_BUILD_BENCHMARKS=OFF, "
                                    "and $STEX_BENCH may name it");
}

}  // namespace

void add_bench(CLI::App& app, GlobalOptions& global) {
  auto* sub = app.add_subcommand(
      "bench",
      "Measure texton noise and the other kinds on the selected device: ms per frame, fps, quality, the compute "
      "floor, beside the baselines (runs the program stex-bench; `stex bench --help` lists its options; "
      "docs/benchmarks.md)");
  // Every argument after `bench`, --help and the global options included, is stex-bench's.
  sub->set_help_flag();
  sub->fallthrough(false);
  sub->prefix_command();
  sub->allow_extras();
  sub->callback([sub, &global] { exec_bench(global, sub->remaining()); });
}

}  // namespace stex::cli
