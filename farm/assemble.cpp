// Assemble per-tile files into one image (farm/assemble.h).
#include "farm/assemble.h"

#include <chrono>
#include <map>

#include "core/error.h"
#include "farm/name_template.h"
#include "farm/tiled_image_writer.h"

namespace stex::farm {

std::vector<std::string> template_inputs(const std::string& name_template) {
  NameTemplate name(name_template);
  if (!name.has_placeholders())
    throw Error(ErrorKind::Usage,
                "--template '" + name_template + "' has no placeholder ({tx}, {ty}, {index}, <UDIM>)");
  TileRect first;  // tile 0 of any grid: tx = ty = index = 0
  std::string first_path = name.format(first);
  OutputInspection ins = inspect_output(first_path, false);
  if (ins.state != OutputState::Valid) {
    throw Error(ErrorKind::Input, "cannot read the grid from the first tile '" + first_path +
                                      "': " + (ins.state == OutputState::Missing ? "missing" : ins.problem));
  }
  TileGrid grid(ins.info.id.full_width, ins.info.id.full_height, ins.info.id.tile_size);
  name.check_grid(grid);
  std::vector<std::string> out;
  for (std::int64_t i = 0; i < grid.count(); ++i) out.push_back(name.format(grid.tile(i)));
  return out;
}

AssembleResult assemble(const std::vector<std::string>& inputs, const std::string& output,
                        const OutputSettings& settings) {
  auto t0 = std::chrono::steady_clock::now();
  if (inputs.empty()) throw Error(ErrorKind::Usage, "assemble: no input tiles");
  std::vector<OutputInfo> infos;
  infos.reserve(inputs.size());
  for (const std::string& path : inputs) {
    OutputInspection ins = inspect_output(path, false);  // pixels are checked when read below
    if (ins.state == OutputState::Missing)
      throw Error(ErrorKind::Input, "assemble: '" + path + "' does not exist");
    if (ins.state == OutputState::Invalid)
      throw Error(ErrorKind::Input, "assemble: '" + path + "': " + ins.problem);
    if (ins.info.tile_index < 0)
      throw Error(ErrorKind::Input, "assemble: '" + path + "' is a whole image, not a tile of a farm render");
    infos.push_back(ins.info);
  }
  const OutputInfo& ref = infos[0];
  auto differs = [&](std::size_t i, const std::string& what, const std::string& a, const std::string& b) {
    throw Error(ErrorKind::Input, "assemble: '" + inputs[i] + "' belongs to a different render than '" +
                                      inputs[0] + "': " + what + " " + b + " vs " + a);
  };
  for (std::size_t i = 1; i < infos.size(); ++i) {
    const OutputInfo& o = infos[i];
    if (o.id.model_hash != ref.id.model_hash) differs(i, "model hash", ref.id.model_hash, o.id.model_hash);
    if (o.id.param_hash != ref.id.param_hash) differs(i, "param hash", ref.id.param_hash, o.id.param_hash);
    if (o.id.full_width != ref.id.full_width || o.id.full_height != ref.id.full_height)
      differs(i, "full size", std::to_string(ref.id.full_width) + "x" + std::to_string(ref.id.full_height),
              std::to_string(o.id.full_width) + "x" + std::to_string(o.id.full_height));
    if (o.id.tile_size != ref.id.tile_size)
      differs(i, "tile size", std::to_string(ref.id.tile_size), std::to_string(o.id.tile_size));
    if (o.id.channels != ref.id.channels)
      differs(i, "channels", std::to_string(ref.id.channels), std::to_string(o.id.channels));
    if (o.pixel_type != ref.pixel_type) differs(i, "pixel type", ref.pixel_type, o.pixel_type);
  }
  TileGrid grid(ref.id.full_width, ref.id.full_height, ref.id.tile_size);
  std::map<std::int64_t, std::size_t> by_index;
  for (std::size_t i = 0; i < infos.size(); ++i) {
    const OutputInfo& o = infos[i];
    if (o.tile_index >= grid.count())
      throw Error(ErrorKind::Input, "assemble: '" + inputs[i] + "' claims tile " +
                                        std::to_string(o.tile_index) + " of a grid of " + grid.describe());
    TileRect t = grid.tile(o.tile_index);
    if (o.x != t.x0 || o.y != t.y0 || o.width != t.width || o.height != t.height)
      throw Error(ErrorKind::Input, "assemble: '" + inputs[i] + "': its window does not match tile " +
                                        std::to_string(o.tile_index) + " of the grid");
    auto [it, fresh] = by_index.emplace(o.tile_index, i);
    if (!fresh)
      throw Error(ErrorKind::Input, "assemble: tile " + std::to_string(o.tile_index) + " given twice: '" +
                                        inputs[it->second] + "' and '" + inputs[i] + "'");
  }
  if (std::int64_t(by_index.size()) != grid.count()) {
    std::vector<std::int64_t> missing;
    for (std::int64_t i = 0; i < grid.count(); ++i)
      if (!by_index.count(i)) missing.push_back(i);
    throw Error(ErrorKind::Input, "assemble: " + std::to_string(missing.size()) + " tile(s) missing: " +
                                      format_index_list(missing) + " (the grid has " + grid.describe() + ")");
  }
  RenderIdentity id = ref.id;
  TiledImageWriter writer(output, grid, id, settings);
  for (const auto& [index, i] : by_index) {
    TileRect t = grid.tile(index);
    std::vector<float> px = read_output_pixels(inputs[i]);
    if (px.size() != std::size_t(t.width) * t.height * id.channels)
      throw Error(ErrorKind::Input, "assemble: '" + inputs[i] + "' has the wrong number of pixels");
    writer.write_tile(t, px);
  }
  writer.finish();
  AssembleResult r;
  r.tiles = grid.count();
  r.width = grid.width();
  r.height = grid.height();
  r.channels = id.channels;
  r.identity = id;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace stex::farm
