// `stex serve [--models DIR] [--host H] [--port P] [--threads N] [--queue N] [--time-limit MS] [--cache-mb MB]
//  [--max-region PIXELS] [--port-file PATH]`: the long-running compute service (service/, docs/serve.md):
// keeps the device, its compiled programs and the models' renderers warm and serves tiles, regions, model
// lists and info, health and metrics over HTTP on loopback, plus the browser viewer. A thin client: parse,
// build the Service, run the server until SIGINT/SIGTERM (exit 0).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "cli/commands.h"
#include "core/error.h"
#include "service/server.h"
#include "service/service.h"

namespace stex::cli {
namespace {

struct ServeCliOptions {
  service::ServiceOptions service;
  service::ServerOptions server;
  double cache_mb = 64;
};

void run_serve(ServeCliOptions o, const GlobalOptions& global) {
  std::error_code ec;
  if (!std::filesystem::is_directory(o.service.models_dir, ec))
    throw Error(ErrorKind::Input, "--models '" + o.service.models_dir + "' is not a directory");
  if (o.service.queue_capacity < 1 || o.service.queue_capacity > 100000)
    throw Error(ErrorKind::Usage, "--queue must be in [1, 100000]");
  if (!(o.cache_mb >= 0 && o.cache_mb <= 1 << 20)) throw Error(ErrorKind::Usage, "--cache-mb must be in [0, 2^20]");
  if (o.service.max_region_pixels < 1 || o.service.max_region_pixels > (std::uint64_t(1) << 28))
    throw Error(ErrorKind::Usage, "--max-region must be in [1, 2^28] pixels");
  o.service.cache_bytes = std::size_t(o.cache_mb * 1024.0 * 1024.0);
  o.service.device = global.device;
  service::block_stop_signals();  // before any thread exists
  const auto t0 = std::chrono::steady_clock::now();
  service::Service svc(o.service);
  const bool quiet = global.quiet;
  if (!quiet) {
    for (const std::string& line : svc.warm_up_report()) std::printf("stex serve: model %s\n", line.c_str());
    std::printf("stex serve: %zu models warmed in %.1f s\n", svc.warm_up_report().size(),
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  const int sig = service::run_server(svc, o.server, [&](int port) {
    if (!quiet)
      std::printf("stex serve: listening on http://%s:%d/ (device %s, models %s, queue %zu, cache %.0f MB)\n",
                  o.server.host.c_str(), port, svc.device().name.c_str(), o.service.models_dir.c_str(),
                  o.service.queue_capacity, o.cache_mb);
    std::fflush(stdout);
  });
  if (!quiet) {
    std::printf("stex serve: stopped (%s), %llu requests\n", sig == 2 ? "SIGINT" : sig == 15 ? "SIGTERM" : "stop",
                (unsigned long long)svc.metrics().requests());
    std::fflush(stdout);
  }
}

}  // namespace

void add_serve(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<ServeCliOptions>();
  auto* sub = app.add_subcommand(
      "serve",
      "Run the compute service: an HTTP server (loopback by default) that keeps the device, its compiled "
      "kernels and the models warm and serves map-style tiles (/api/tiles/MODEL/Z/X/Y.png|exr), regions, "
      "model lists and info, health and metrics, and a browser viewer of the infinite texture at /. Tiles are "
      "byte-identical to `stex render` with the same parameters. Stops cleanly on SIGINT/SIGTERM "
      "(docs/serve.md).");
  sub->add_option("--models", o->service.models_dir, "Directory of models: DIR/NAME.stex is model NAME (default .)");
  sub->add_option("--host", o->server.host, "Address to listen on (default 127.0.0.1: loopback only)");
  sub->add_option("--port", o->server.port, "TCP port (default 8080; 0: any free port, printed)");
  sub->add_option("--port-file", o->server.port_file, "Write the bound port to this file once listening");
  sub->add_option("--threads", o->server.threads, "Connection threads (default 16)");
  sub->add_option("--queue", o->service.queue_capacity,
                  "Device jobs allowed to wait (default 16); more requests get 503 with Retry-After");
  sub->add_option("--time-limit", o->service.time_limit_ms,
                  "Per-request time limit in ms, queueing included (default 10000); past it 503");
  sub->add_option("--cache-mb", o->cache_mb, "Memory cap of the cache of encoded tiles, MiB (default 64)");
  sub->add_option("--max-region", o->service.max_region_pixels,
                  "Largest region request in pixels, w * h (default 2^21)");
  sub->add_flag("!--no-warm-up", o->service.warm_up,
                "Do not build the models' renderers and kernels before listening (first requests pay for it)");
  sub->callback([o, &global] { run_serve(*o, global); });
}

}  // namespace stex::cli
