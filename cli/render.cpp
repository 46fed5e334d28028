// Placeholder: replaced by the real subcommand.
#include "cli/commands.h"
#include "runtime/error.h"

namespace stex::cli {
void add_render(CLI::App& app, GlobalOptions&) {
  auto* sub = app.add_subcommand("render", "(not implemented yet)");
  sub->callback([] { throw Error(ErrorKind::Internal, "render: not implemented yet"); });
}
}  // namespace stex::cli
