// Placeholder: replaced by the real subcommand.
#include "cli/commands.h"
#include "runtime/error.h"

namespace stex::cli {
void add_demo_rng(CLI::App& app, GlobalOptions&) {
  auto* sub = app.add_subcommand("demo-rng", "(not implemented yet)");
  sub->callback([] { throw Error(ErrorKind::Internal, "demo_rng: not implemented yet"); });
}
}  // namespace stex::cli
