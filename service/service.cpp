// Routes, parameters and the request path of stex serve (service/service.h).
#include "service/service.h"

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "model/kinds.h"
#include "core/error.h"
#include "service/selftest_health.h"
#include "service/web_assets.h"

namespace stex::service {
namespace {

using json = nlohmann::json;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

Response json_response(int status, const json& j) {
  Response r;
  r.status = status;
  r.body = j.dump(2) + "\n";
  r.headers.emplace_back("Cache-Control", "no-store");
  return r;
}

Response error_response(int status, const std::string& message) {
  return json_response(status, json{{"error", message}, {"status", status}});
}

[[noreturn]] void bad(const std::string& m) { throw Error(ErrorKind::Usage, m); }

// Query parameters: each at most once, only the ones the endpoint knows.
class Query {
 public:
  Query(const std::multimap<std::string, std::string>& q, std::initializer_list<const char*> known) : q_(q) {
    for (const auto& kv : q) {
      bool ok = false;
      for (const char* k : known) ok = ok || kv.first == k;
      if (!ok) bad("unknown parameter '" + kv.first + "'");
      if (q.count(kv.first) > 1) bad("parameter '" + kv.first + "' given more than once");
    }
  }
  const std::string* get(const char* name) const {
    auto it = q_.find(name);
    return it == q_.end() ? nullptr : &it->second;
  }

 private:
  const std::multimap<std::string, std::string>& q_;
};

std::int64_t parse_i64(const std::string& s, const std::string& what) {
  errno = 0;
  char* end = nullptr;
  const long long v = s.empty() ? 0 : std::strtoll(s.c_str(), &end, 10);
  if (s.empty() || errno != 0 || end != s.c_str() + s.size())
    bad(what + " must be a 64-bit integer, got '" + s + "'");
  return v;
}

std::uint64_t parse_u64(const std::string& s, const std::string& what) {
  errno = 0;
  char* end = nullptr;
  const unsigned long long v = (s.empty() || s[0] == '-') ? 0 : std::strtoull(s.c_str(), &end, 10);
  if (s.empty() || s[0] == '-' || errno != 0 || end != s.c_str() + s.size())
    bad(what + " must be an unsigned 64-bit integer, got '" + s + "'");
  return v;
}

double parse_double(const std::string& s, const std::string& what) {
  errno = 0;
  char* end = nullptr;
  const double v = s.empty() ? 0 : std::strtod(s.c_str(), &end);
  if (s.empty() || errno != 0 || end != s.c_str() + s.size() || !std::isfinite(v))
    bad(what + " must be a finite number, got '" + s + "'");
  return v;
}

// seed, mni, cell, filter, bits: shared by tiles and regions.
void parse_common(const Query& q, TileRequest* r) {
  if (const auto* v = q.get("seed")) r->params.seed = parse_u64(*v, "seed");
  if (const auto* v = q.get("mni")) r->params.mni = parse_double(*v, "mni");
  if (const auto* v = q.get("cell")) r->params.cell_factor = parse_double(*v, "cell");
  if (const auto* v = q.get("bits")) r->bits = int(parse_i64(*v, "bits"));
  if (const auto* v = q.get("filter")) {
    if (*v == "auto") r->filter = FilterMode::Auto;
    else if (*v == "on") r->filter = FilterMode::On;
    else if (*v == "off") r->filter = FilterMode::Off;
    else bad("filter must be auto, on or off, got '" + *v + "'");
  }
}

// "name.ext" -> (name, ext); ext must be png or exr.
void split_format(const std::string& s, std::string* stem, std::string* format) {
  const auto dot = s.find_last_of('.');
  if (dot == std::string::npos || dot == 0) bad("'" + s + "' needs a format extension: .png or .exr");
  *stem = s.substr(0, dot);
  *format = s.substr(dot + 1);
  if (*format != "png" && *format != "exr") bad("format must be png or exr, got '" + *format + "'");
}

std::vector<std::string> split_path(const std::string& p) {
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i <= p.size()) {
    const auto j = p.find('/', i);
    const std::string part = p.substr(i, j == std::string::npos ? std::string::npos : j - i);
    if (!part.empty()) out.push_back(part);
    if (j == std::string::npos) break;
    i = j + 1;
  }
  return out;
}

std::string cache_key(const ServedModel& m, const TileRequest& r) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "|%lld|%lld|%d|%d|%.17g|%.17g|%.17g|%llu|%d|%d|", (long long)r.x, (long long)r.y,
                r.width, r.height, r.params.scale, r.params.mni, r.params.cell_factor,
                (unsigned long long)r.params.seed, r.bits, int(uses_filter(m, r)));
  return m.sha256 + buf + r.format;
}

std::string asset_type(const std::string& name) {
  auto ends = [&](const char* e) {
    const std::string s(e);
    return name.size() >= s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0;
  };
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".js")) return "text/javascript; charset=utf-8";
  if (ends(".css")) return "text/css; charset=utf-8";
  return "application/octet-stream";
}

json percentiles_json(const Percentiles& p) {
  return json{{"count", p.count}, {"p50_ms", p.p50}, {"p90_ms", p.p90}, {"p99_ms", p.p99},
              {"max_ms", p.max},  {"mean_ms", p.mean}};
}

}  // namespace

Service::Service(ServiceOptions options)
    : options_(std::move(options)),
      ctx_(Context::create(options_.device)),
      renderers_(*ctx_),
      store_(options_.models_dir),
      cache_(options_.cache_bytes),
      started_(Clock::now()),
      queue_(options_.queue_capacity) {
  if (options_.tile_size < 1 || options_.tile_size > 4096)
    throw Error(ErrorKind::Usage, "the tile size must be in [1, 4096]");
  if (options_.time_limit_ms < 1) throw Error(ErrorKind::Usage, "the time limit must be at least 1 ms");
  if (options_.warm_up) warm_report_ = warm_up();
}

std::vector<std::string> Service::warm_up() {
  std::vector<std::string> report;
  for (const std::string& name : store_.names()) {
    try {
      auto m = store_.get(name);
      if (!m) continue;
      auto job = queue_.submit(
          [this, m] {
            TileRequest r;
            r.width = r.height = 1;
            renderers_.render(*m, r);
            if (m->filterable()) {
              r.params.scale = 0.5;  // filter=auto filters below scale 1
              renderers_.render(*m, r);
            }
          },
          Clock::now() + std::chrono::hours(1));
      if (!job || !job->wait_until(Clock::now() + std::chrono::hours(1))) {
        report.push_back(name + ": not warmed (device queue stopped)");
        continue;
      }
      if (auto e = job->error()) std::rethrow_exception(e);
      report.push_back(name + ": ok (" + m->container.kind + ")");
    } catch (const std::exception& e) {
      report.push_back(name + ": " + e.what());
    }
  }
  return report;
}

Service::~Service() { stop(); }

void Service::stop() { queue_.stop(); }

Response Service::handle(const Request& request) {
  const auto t0 = Clock::now();
  std::string endpoint = "other";
  Response r;
  try {
    r = route(request, &endpoint);
  } catch (const Error& e) {
    switch (e.kind()) {
      case ErrorKind::Usage:
      case ErrorKind::Limit: r = error_response(400, e.what()); break;
      case ErrorKind::Input: r = error_response(500, std::string("model cannot be loaded: ") + e.what()); break;
      case ErrorKind::Retryable:
        r = error_response(503, e.what());
        r.headers.emplace_back("Retry-After", "1");
        break;
      default: r = error_response(500, e.what()); break;
    }
  } catch (const std::bad_alloc&) {
    r = error_response(503, "out of memory");
    r.headers.emplace_back("Retry-After", "1");
  } catch (const std::exception& e) {
    r = error_response(500, std::string("internal error: ") + e.what());
  }
  const double ms = ms_since(t0);
  metrics_.record(endpoint, r.status, ms);
  if ((endpoint == "tile" || endpoint == "region") && r.status == 200) metrics_.record_render_request(ms);
  return r;
}

Response Service::route(const Request& request, std::string* endpoint) {
  const std::vector<std::string> parts = split_path(request.path);
  if (parts.empty() || (parts.size() == 1 && parts[0] != "api")) {  // the viewer's files
    *endpoint = "viewer";
    const std::string name = parts.empty() ? "index.html" : parts[0];
    std::size_t n = 0;
    const WebAsset* assets = web_assets(&n);
    for (std::size_t i = 0; i < n; ++i)
      if (name == assets[i].name) {
        Response r;
        r.content_type = asset_type(name);
        r.body = assets[i].text;
        r.headers.emplace_back("Cache-Control", "no-cache");
        return r;
      }
    return error_response(404, "no such page '" + request.path + "'");
  }
  if (parts[0] != "api" || parts.size() < 2) return error_response(404, "no such endpoint '" + request.path + "'");
  const std::string& what = parts[1];
  if (what == "health" && parts.size() == 2) {
    *endpoint = "health";
    Query q(request.query, {});
    return health();
  }
  if (what == "metrics" && parts.size() == 2) {
    *endpoint = "metrics";
    Query q(request.query, {});
    return metrics_json();
  }
  if (what == "models" && parts.size() == 2) {
    *endpoint = "models";
    Query q(request.query, {});
    return models();
  }
  if (what == "models" && parts.size() == 3) {
    *endpoint = "model";
    Query q(request.query, {});
    return model_info(parts[2]);
  }
  if (what == "tiles" && parts.size() == 6) {  // /api/tiles/MODEL/Z/X/Y.FMT
    *endpoint = "tile";
    Query q(request.query, {"seed", "mni", "cell", "filter", "bits"});
    TileRequest r;
    std::string y_text;
    split_format(parts[5], &y_text, &r.format);
    const std::int64_t z = parse_i64(parts[3], "zoom level");
    if (z < k_min_zoom || z > k_max_zoom)
      bad("zoom level must be in [" + std::to_string(k_min_zoom) + ", " + std::to_string(k_max_zoom) + "], got " +
          std::to_string(z));
    const std::int64_t tx = parse_i64(parts[4], "tile x"), ty = parse_i64(y_text, "tile y");
    const std::int64_t t = options_.tile_size;
    const std::int64_t lim = k_max_pixel_coordinate / t;
    if (tx <= -lim || tx >= lim || ty <= -lim || ty >= lim)
      bad("tile (" + std::to_string(tx) + ", " + std::to_string(ty) + ") is beyond the coordinate range (|x|, |y| < 2^46 pixels)");
    r.x = tx * t;
    r.y = ty * t;
    r.width = r.height = int(t);
    r.params.scale = std::ldexp(1.0, int(z));
    parse_common(q, &r);
    return render(parts[2], r, "tile");
  }
  if (what == "region" && parts.size() == 3) {  // /api/region/MODEL.FMT?x=&y=&w=&h=&scale=
    *endpoint = "region";
    Query q(request.query, {"x", "y", "w", "h", "scale", "seed", "mni", "cell", "filter", "bits"});
    TileRequest r;
    std::string name;
    split_format(parts[2], &name, &r.format);
    const std::string *w = q.get("w"), *h = q.get("h");
    if (!w || !h) bad("the region needs w and h (pixels)");
    const std::int64_t wi = parse_i64(*w, "w"), hi = parse_i64(*h, "h");
    if (wi < 1 || hi < 1) bad("w and h must be at least 1");
    if (wi > INT32_MAX || hi > INT32_MAX || std::uint64_t(wi) * std::uint64_t(hi) > options_.max_region_pixels)
      bad("the region is " + std::to_string(wi) + "x" + std::to_string(hi) + ", above the limit of " +
          std::to_string(options_.max_region_pixels) + " pixels per request (--max-region)");
    r.width = int(wi);
    r.height = int(hi);
    if (const auto* v = q.get("x")) r.x = parse_i64(*v, "x");
    if (const auto* v = q.get("y")) r.y = parse_i64(*v, "y");
    if (const auto* v = q.get("scale")) r.params.scale = parse_double(*v, "scale");
    parse_common(q, &r);
    return render(name, r, "region");
  }
  return error_response(404, "no such endpoint '" + request.path + "'");
}

std::shared_ptr<const ServedModel> Service::model_or_404(const std::string& name, Response* error) {
  if (!valid_model_name(name)) {
    *error = error_response(400, "invalid model name '" + name + "' (letters, digits, '.', '_', '-')");
    return nullptr;
  }
  auto m = store_.get(name);  // Error(Input) for a corrupt file
  if (!m) *error = error_response(404, "unknown model '" + name + "' (no " + name + ".stex in the models directory)");
  return m;
}

bool Service::run_on_device(const std::function<void()>& work, Clock::time_point deadline, Response* error) {
  auto job = queue_.submit(work, deadline);
  if (!job) {
    {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      ++rejected_;
    }
    // Retry after about the time the waiting jobs need (mean render time in the worker), at least 1 s.
    const Percentiles d = metrics_.device_latency();
    const double wait_s = double(queue_.depth() + 1) * (d.count ? d.mean : 50.0) / 1000.0;
    *error = error_response(503, "the device queue is full (" + std::to_string(queue_.capacity()) +
                                     " requests waiting); retry later");
    error->headers.emplace_back("Retry-After", std::to_string(std::max<long>(1, long(std::ceil(wait_s)))));
    return false;
  }
  if (!job->wait_until(deadline)) {
    {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      ++timed_out_;
    }
    *error = error_response(503, "the request exceeded the time limit of " + std::to_string(options_.time_limit_ms) +
                                     " ms (device busy); retry later");
    error->headers.emplace_back("Retry-After", "1");
    return false;
  }
  if (auto e = job->error()) std::rethrow_exception(e);
  return true;
}

Response Service::render(const std::string& name, TileRequest r, const char* /*endpoint*/) {
  const auto t0 = Clock::now();
  const auto deadline = t0 + std::chrono::milliseconds(options_.time_limit_ms);
  Response err;
  auto model = model_or_404(name, &err);
  if (!model) return err;
  validate_request(*model, r);
  const std::string key = cache_key(*model, r);
  if (auto hit = cache_.get(key)) {
    Response resp;
    resp.content_type = hit->content_type;
    resp.body = hit->body;
    resp.headers = {{"X-Stex-Cache", "hit"}, {"X-Stex-Strategy", hit->strategy}, {"Cache-Control", "no-cache"}};
    return resp;
  }
  auto result = std::make_shared<RenderedImage>();
  if (!run_on_device(
          [this, model, r, result] {
            const auto w0 = Clock::now();
            *result = renderers_.render(*model, r);
            metrics_.record_render(result->device_ms, ms_since(w0));
          },
          deadline, &err))
    return err;
  auto body = std::make_shared<CachedBody>();
  body->content_type = content_type(r.format);
  body->body = encoder_.encode(*model, r, *result);
  body->strategy = result->strategy;
  Response resp;
  resp.content_type = body->content_type;
  resp.body = body->body;
  char dms[32];
  std::snprintf(dms, sizeof dms, "%.3f", result->device_ms);
  resp.headers = {{"X-Stex-Cache", "miss"},
                  {"X-Stex-Strategy", body->strategy},
                  {"X-Stex-Device-Ms", dms},
                  {"Cache-Control", "no-cache"}};
  cache_.put(key, std::move(body));
  return resp;
}

Response Service::model_info(const std::string& name) {
  Response err;
  auto m = model_or_404(name, &err);
  if (!m) return err;
  auto channels_out = std::make_shared<int>(0);  // shared: a job past its time limit may still run
  if (!run_on_device([this, m, channels_out] { *channels_out = renderers_.channels(*m); },
                     Clock::now() + std::chrono::milliseconds(options_.time_limit_ms), &err))
    return err;
  const int channels = *channels_out;
  json j{{"name", m->name},
         {"kind", m->container.kind},
         {"sha256", m->sha256},
         {"file_bytes", m->file_size},
         {"channels", channels},
         {"linear", m->linear},
         {"filterable", m->filterable()},
         {"exemplar", model_exemplar_name(m->container)},
         {"generation", m->generation},
         {"tile_size", options_.tile_size},
         {"zoom", {{"min", k_min_zoom}, {"max", k_max_zoom}}},
         {"tiles", "/api/tiles/" + m->name + "/{z}/{x}/{y}.png?seed=0&mni=30"},
         {"metadata", m->container.metadata}};
  if (const TextonModel* t = m->as<TextonModel>()) {
    j["order"] = t->order;
    j["support"] = t->support;
  }
  return json_response(200, j);
}

Response Service::models() {
  json list = json::array();
  for (const std::string& name : store_.names()) {
    json e{{"name", name}};
    try {
      auto m = store_.get(name);
      if (!m) continue;  // removed meanwhile
      e["kind"] = m->container.kind;
      e["sha256"] = m->sha256;
      e["filterable"] = m->filterable();
      e["exemplar"] = model_exemplar_name(m->container);
    } catch (const std::exception& ex) {
      e["error"] = ex.what();
    }
    list.push_back(e);
  }
  return json_response(200, json{{"models", list}, {"dir", store_.dir()}});
}

Response Service::health() {
  return json_response(200, json{{"status", "ok"},
                                 {"version", STEX_VERSION_STRING},
                                 {"device", ctx_->info().name},
                                 {"platform", ctx_->info().platform_name},
                                 {"driver", ctx_->info().driver_version},
                                 {"uptime_s", ms_since(started_) / 1000.0},
                                 {"selftest", selftest_health(ctx_->info())}});
}

Response Service::metrics_json() {
  json status = json::object();
  for (const auto& kv : metrics_.by_status()) status[std::to_string(kv.first)] = kv.second;
  json endpoints = json::object();
  for (const auto& kv : metrics_.by_endpoint()) endpoints[kv.first] = kv.second;
  std::uint64_t rejected = 0, timed_out = 0;
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    rejected = rejected_;
    timed_out = timed_out_;
  }
  return json_response(
      200, json{{"requests", metrics_.requests()},
                {"by_status", status},
                {"by_endpoint", endpoints},
                {"queue",
                 {{"depth", queue_.depth()},
                  {"max_depth", queue_.max_depth()},
                  {"capacity", queue_.capacity()},
                  {"rejected", rejected},
                  {"timed_out", timed_out},
                  {"expired", queue_.expired()},
                  {"completed", queue_.completed()}}},
                {"latency", percentiles_json(metrics_.latency())},
                {"render_latency", percentiles_json(metrics_.render_latency())},
                {"device",
                 {{"name", ctx_->info().name},
                  {"renders", metrics_.renders()},
                  {"time_ms_total", metrics_.device_ms_total()},
                  {"per_render", percentiles_json(metrics_.device_latency())}}},
                {"cache",
                 {{"bytes", cache_.bytes()},
                  {"cap_bytes", cache_.cap()},
                  {"entries", cache_.entries()},
                  {"hits", cache_.hits()},
                  {"misses", cache_.misses()},
                  {"evictions", cache_.evictions()}}},
                {"models", {{"reloads", store_.reloads()}}},
                {"uptime_s", ms_since(started_) / 1000.0}});
}

}  // namespace stex::service
