// What a tile or region request renders, and how its bytes are made: the same render path as `stex render`
// (ModelRenderers of model/render_request.h: the kind's renderer, or the S1 §5 filtered texton renderer for
// zoomed-out texton views) and the same writer, options and metadata, so a tile is byte-identical to
// `stex render MODEL -o t.png --size 256x256 --origin X*256,Y*256 --scale 2^Z --seed S --mni M [--filter]`
// (tests/serve: TilesEqualCliRenders).
#pragma once
#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "analysis/image_io.h"
#include "model/render_request.h"
#include "runtime/context.h"
#include "service/model_store.h"

namespace stex::service {

// A render request (filter Auto: filtered when the model is filterable and scale < 1; no camera, no UV map)
// and its encoding.
struct TileRequest : RenderRequest {
  std::string format = "png";  // "png" or "exr"
  int bits = 0;                // 0: the CLI's default for the format (png 8, exr 32); png 8|16, exr 16|32
};

// Error(Usage) naming the problem: region and parameters (validate_render_region), format and bits, and
// filter=on for a model the filter does not apply to.
void validate_request(const ServedModel& model, const TileRequest& r);

struct RenderedImage {
  Image image;
  std::string strategy;  // as `stex render` reports it ("splat", "gather", "filtered", ...)
  double device_ms = 0.0;
  bool filtered = false;
};

// The device's renderers, one ModelRenderers per model (rebuilt when the model's SHA-256 changes). Used only
// by the device queue's worker thread: Context and renderers are not shared between threads.
class DeviceRenderers {
 public:
  explicit DeviceRenderers(Context& ctx) : ctx_(ctx) {}
  RenderedImage render(const ServedModel& model, const TileRequest& r);
  int channels(const ServedModel& model);

 private:
  struct Entry {
    std::string sha256;
    std::unique_ptr<ModelRenderers> renderers;
  };
  Entry& entry(const ServedModel& model);
  Context& ctx_;
  std::map<std::string, Entry> by_name_;
};

// Encodes through analysis/image_io's write_image_atomic (the CLI's writer) into a private scratch
// directory and returns the file's bytes; WriteOptions and metadata are the CLI's. Thread-safe.
class Encoder {
 public:
  Encoder();   // creates the scratch directory in $TMPDIR, else /dev/shm, else /tmp; Error(Output) on failure
  ~Encoder();  // removes it
  Encoder(const Encoder&) = delete;
  Encoder& operator=(const Encoder&) = delete;
  std::string encode(const ServedModel& model, const TileRequest& r, const RenderedImage& img);
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
  std::atomic<std::uint64_t> next_{0};
};

std::string content_type(const std::string& format);

}  // namespace stex::service
