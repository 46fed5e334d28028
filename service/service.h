// stex serve's request handling, independent of the HTTP library (service/server.h adapts it to
// cpp-httplib): routes, parameter parsing (400 with a message), models (404 for an unknown one, reload on
// change), the tile cache, the bounded device queue (503 with Retry-After when full or past the
// per-request time limit) and metrics. docs/serve.md has the endpoint table.
//
// Tiles are addressed like a map tile server: zoom level Z means scale 2^Z output pixels per exemplar pixel
// (Z in [-10, 10]; Z < 0 zooms out and uses S1 §5 filtering for texton models of order 1), tile (X, Y) is the
// region [X*T, (X+1)*T) x [Y*T, (Y+1)*T) of output pixels at that scale, T = the tile size (256).
#pragma once
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "runtime/context.h"
#include "service/device_queue.h"
#include "service/metrics.h"
#include "service/model_store.h"
#include "service/tile_cache.h"
#include "service/tile_render.h"

namespace stex::service {

struct ServiceOptions {
  std::string models_dir = ".";
  std::string device;                   // as --device: cpu, gpu, an index, a name substring; "" default
  std::size_t queue_capacity = 16;      // device jobs waiting; more get 503
  int time_limit_ms = 10000;            // per request, queueing included; past it 503
  std::size_t cache_bytes = std::size_t(64) << 20;  // encoded tiles kept (LRU)
  int tile_size = 256;
  std::uint64_t max_region_pixels = std::uint64_t(1) << 21;  // the region endpoint's largest w * h
  bool warm_up = true;  // build every model's renderers and kernels before serving (Service::warm_up)
};

inline constexpr int k_min_zoom = -10, k_max_zoom = 10;  // scale 2^Z within [1/1024, 1024]

struct Request {
  std::string path;                               // decoded path, e.g. "/api/tiles/gravel/0/3/-2.png"
  std::multimap<std::string, std::string> query;  // decoded query parameters
};

struct Response {
  int status = 200;
  std::string content_type = "application/json";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;
};

class Service {
 public:
  // Opens the device (Error(Device) when none matches) and starts the device worker.
  explicit Service(ServiceOptions options);
  ~Service();
  Service(const Service&) = delete;
  Service& operator=(const Service&) = delete;

  // Answers one GET request; never throws. Thread-safe: the HTTP server calls it from its worker threads.
  Response handle(const Request& request);
  // Stops the device worker; later renders get 503.
  void stop();
  // Loads every model of the directory and builds its renderers and kernels on the device (a 1x1 render;
  // filtered too where it applies), so that first requests do not pay kernel builds against their time
  // limit. Returns one line per model ("name: ok" or "name: the error"). The constructor calls it when
  // options.warm_up is set.
  std::vector<std::string> warm_up();
  const std::vector<std::string>& warm_up_report() const { return warm_report_; }

  const ServiceOptions& options() const { return options_; }
  const DeviceInfo& device() const { return ctx_->info(); }
  const TileCache& cache() const { return cache_; }
  const Metrics& metrics() const { return metrics_; }

 private:
  Response route(const Request& request, std::string* endpoint);
  Response render(const std::string& name, TileRequest r, const char* endpoint);
  Response model_info(const std::string& name);
  Response models();
  Response health();
  Response metrics_json();
  std::shared_ptr<const ServedModel> model_or_404(const std::string& name, Response* error);
  // Runs `work` on the device worker within the time limit; false with *error set (503) otherwise.
  bool run_on_device(const std::function<void()>& work, Clock::time_point deadline, Response* error);

  ServiceOptions options_;
  std::unique_ptr<Context> ctx_;
  DeviceRenderers renderers_;  // worker thread only
  ModelStore store_;
  TileCache cache_;
  Metrics metrics_;
  Encoder encoder_;
  Clock::time_point started_;
  std::uint64_t rejected_ = 0, timed_out_ = 0;  // under stats_mutex_
  std::mutex stats_mutex_;
  std::vector<std::string> warm_report_;
  DeviceQueue queue_;  // last: its worker stops first
};

}  // namespace stex::service
