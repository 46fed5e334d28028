// Placeholder: replaced by the real subcommand.
#include "cli/commands.h"
#include "runtime/error.h"

namespace stex::cli {
void add_analyze(CLI::App& app, GlobalOptions&) {
  auto* sub = app.add_subcommand("analyze", "(not implemented yet)");
  sub->callback([] { throw Error(ErrorKind::Internal, "analyze: not implemented yet"); });
}
}  // namespace stex::cli
