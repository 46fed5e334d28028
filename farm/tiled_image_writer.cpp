// Out-of-core tiled image writer (farm/tiled_image_writer.h).
#include "farm/tiled_image_writer.h"

#include <algorithm>
#include <cerrno>

#include "core/atomic_file.h"
#include "core/error.h"
#include "farm/oiio_detail.h"

namespace stex::farm {

using OIIO::ImageOutput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

struct TiledImageWriter::Impl {
  std::string path;
  TileGrid grid;
  int channels;
  std::unique_ptr<TempOutput> tmp;
  std::unique_ptr<ImageOutput> out;
  std::int64_t next = 0;      // next tile index expected
  std::vector<float> buffer;  // one padded tile (tiled) or one strip of tile rows (scanline)
  bool finished = false;

  Impl(const std::string& p, const TileGrid& g, int c) : path(p), grid(g), channels(c) {}

  [[noreturn]] void fail(const std::string& what) {
    int saved_errno = errno;
    std::string err = out ? out->geterror() : std::string();
    std::string cause = write_failure_cause(path, saved_errno);
    throw Error(ErrorKind::Output, "cannot write '" + path + "': " + (cause.empty() ? "" : cause + ": ") +
                                       what + (err.empty() ? "" : ": " + err));
  }
};

TiledImageWriter::TiledImageWriter(const std::string& path, const TileGrid& grid, const RenderIdentity& id,
                                   const OutputSettings& settings)
    : impl_(std::make_unique<Impl>(path, grid, id.channels)) {
  if (id.full_width != grid.width() || id.full_height != grid.height() || id.tile_size != grid.tile_size())
    throw Error(ErrorKind::Internal, "tiled writer: identity and grid disagree for '" + path + "'");
  if (id.channels < 1) throw Error(ErrorKind::Internal, "tiled writer: no channels for '" + path + "'");
  ImageSpec spec = detail::make_output_spec(path, id, settings, -1, 0, 0, grid.width(), grid.height());
  make_parent_dirs(path);
  impl_->tmp = std::make_unique<TempOutput>(path, /*fault_hook=*/true);
  impl_->out = ImageOutput::create(impl_->tmp->path());
  if (!impl_->out) throw Error(ErrorKind::Output, "cannot write '" + path + "': " + OIIO::geterror());
  std::string ext = detail::lower_extension(path);
  tiled_ = impl_->out->supports("tiles");
  if (tiled_ && (ext == "tif" || ext == "tiff") && grid.tile_size() % 16 != 0) {
    throw Error(ErrorKind::Usage, "output '" + path +
                                      "': TIFF tiles must be a multiple of 16 pixels, got --tile-size " +
                                      std::to_string(grid.tile_size()));
  }
  if (tiled_) {
    spec.tile_width = grid.tile_size();
    spec.tile_height = grid.tile_size();
    spec.tile_depth = 1;
    impl_->buffer.assign(std::size_t(grid.tile_size()) * grid.tile_size() * id.channels, 0.0f);
  } else {
    impl_->buffer.assign(std::size_t(grid.width()) * grid.tile_size() * id.channels, 0.0f);
  }
  if (!impl_->out->open(impl_->tmp->path(), spec)) impl_->fail("open");
}

TiledImageWriter::~TiledImageWriter() {
  if (impl_ && !impl_->finished) {
    if (impl_->out) {
      impl_->out->close();  // errors ignored: the temp file is removed next
      impl_->out.reset();
    }
    impl_->tmp.reset();  // removes the temp file
  }
}

const std::string& TiledImageWriter::temp_path() const { return impl_->tmp->path(); }

void TiledImageWriter::write_tile(const TileRect& tile, const std::vector<float>& pixels) {
  Impl& m = *impl_;
  if (m.finished) throw Error(ErrorKind::Internal, "tiled writer: write after finish for '" + m.path + "'");
  if (tile.index != m.next) {
    throw Error(ErrorKind::Internal, "tiled writer: tile " + std::to_string(tile.index) +
                                         " out of order (expected " + std::to_string(m.next) + ") for '" +
                                         m.path + "'");
  }
  const std::size_t row_values = std::size_t(tile.width) * m.channels;
  if (pixels.size() != row_values * tile.height)
    throw Error(ErrorKind::Internal,
                "tiled writer: wrong pixel count for tile " + std::to_string(tile.index));
  const int t = m.grid.tile_size();
  if (tiled_) {
    // A full tile's worth of data even for ragged edge tiles (ImageOutput::write_tile's contract).
    const float* src = pixels.data();
    if (tile.width != t || tile.height != t) {
      for (int r = 0; r < tile.height; ++r)
        std::copy_n(pixels.begin() + r * row_values, row_values,
                    m.buffer.begin() + std::size_t(r) * t * m.channels);
      src = m.buffer.data();
    }
    if (!m.out->write_tile(tile.x0, tile.y0, 0, TypeDesc::FLOAT, src))
      m.fail("tile " + std::to_string(tile.index));
  } else {
    const std::size_t stride = std::size_t(m.grid.width()) * m.channels;
    for (int r = 0; r < tile.height; ++r)
      std::copy_n(pixels.begin() + r * row_values, row_values,
                  m.buffer.begin() + r * stride + std::size_t(tile.x0) * m.channels);
    if (tile.tx == m.grid.nx() - 1) {
      if (!m.out->write_scanlines(tile.y0, tile.y0 + tile.height, 0, TypeDesc::FLOAT, m.buffer.data()))
        m.fail("rows " + std::to_string(tile.y0) + "-" + std::to_string(tile.y0 + tile.height - 1));
    }
  }
  ++m.next;
}

void TiledImageWriter::finish() {
  Impl& m = *impl_;
  if (m.finished) return;
  if (m.next != m.grid.count()) {
    throw Error(ErrorKind::Internal, "tiled writer: only " + std::to_string(m.next) + " of " +
                                         std::to_string(m.grid.count()) + " tiles written to '" + m.path +
                                         "'");
  }
  bool ok = m.out->close();
  if (!ok || m.out->has_error()) m.fail("close");
  m.out.reset();
  m.tmp->commit();
  m.finished = true;
}

}  // namespace stex::farm
