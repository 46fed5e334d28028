// `stex assemble`: stitches the per-tile files of a farm render into one image (farm/assemble.h), after
// checking that they all belong to the same render and that every tile is present exactly once.
//   stex assemble out/t_*.exr -o big.exr
//   stex assemble --template 'out/t_{tx}_{ty}.exr' -o big.exr
#include "farm/assemble.h"

#include <cstdio>

#include "cli/commands.h"
#include "core/error.h"
#include "farm/farm_cli.h"

namespace stex::cli {

void add_assemble(CLI::App& app, GlobalOptions& global) {
  struct Options {
    std::vector<std::string> inputs;
    std::string name_template;
    std::string output;
    int bits = 0;
    std::string compression;
  };
  auto opts = std::make_shared<Options>();
  auto* sub = app.add_subcommand("assemble", "Stitch the per-tile files of a farm render into one image");
  sub->add_option("tiles", opts->inputs, "Tile files written by `stex render --tile-size ... -o TEMPLATE`");
  sub->add_option(
      "--template", opts->name_template,
      "Instead of listing files: the render's name template (e.g. 'out/t_{tx}_{ty}.exr'); the grid is "
      "read from tile 0");
  sub->add_option(
         "-o,--output", opts->output,
         "Output image; .exr/.tif are written as tiled files, other formats as scanlines (bounded memory)")
      ->required();
  sub->add_option("--bits", opts->bits, "Output pixel type: 0 by extension (exr/tif float), 8, 16, 32")
      ->check(CLI::IsMember({0, 8, 16, 32}));
  sub->add_option("--compression", opts->compression, "OIIO compression, e.g. zip, piz, none (EXR)");
  sub->footer(farm::exit_code_help());
  sub->callback([opts, &global] {
    if (opts->inputs.empty() == opts->name_template.empty())
      throw Error(ErrorKind::Usage, "assemble: give either tile files or --template (one of them)");
    std::vector<std::string> inputs =
        opts->name_template.empty() ? opts->inputs : farm::template_inputs(opts->name_template);
    farm::OutputSettings settings;
    settings.bits = opts->bits;
    settings.compression = opts->compression;
    farm::AssembleResult r = farm::assemble(inputs, opts->output, settings);
    if (!global.quiet) {
      std::fprintf(stderr,
                   "stex: assembled %lld tile%s into %s (%dx%d, %d channel%s, param hash %s) in %.2f s\n",
                   static_cast<long long>(r.tiles), r.tiles == 1 ? "" : "s", opts->output.c_str(), r.width, r.height,
                   r.channels, r.channels == 1 ? "" : "s",
                   r.identity.param_hash.c_str(), r.seconds);
    }
  });
}

}  // namespace stex::cli
