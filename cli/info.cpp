// Placeholder: replaced by the real subcommand.
#include "cli/commands.h"
#include "runtime/error.h"

namespace stex::cli {
void add_info(CLI::App& app, GlobalOptions&) {
  auto* sub = app.add_subcommand("info", "(not implemented yet)");
  sub->callback([] { throw Error(ErrorKind::Internal, "info: not implemented yet"); });
}
}  // namespace stex::cli
