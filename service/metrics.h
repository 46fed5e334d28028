// Counters and latency percentiles of stex serve (GET /api/metrics). Latencies are kept for the most recent
// k_window requests of each series (a ring), so percentiles describe recent behaviour in bounded memory.
// Thread-safe.
#pragma once
#include <cstddef>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace stex::service {

struct Percentiles {
  std::size_t count = 0;  // samples in the window
  double p50 = 0, p90 = 0, p99 = 0, max = 0, mean = 0;
};

// Nearest-rank percentiles of `samples` (sorted in place).
Percentiles percentiles(std::vector<double>& samples);

class LatencyRing {
 public:
  static constexpr std::size_t k_window = 4096;
  void add(double ms);
  Percentiles summary() const;

 private:
  mutable std::mutex mutex_;
  std::vector<double> ring_;
  std::size_t next_ = 0;
};

class Metrics {
 public:
  // One request answered with `status` after `ms` milliseconds; `endpoint` is a route name ("tile", ...).
  void record(const std::string& endpoint, int status, double ms);
  // One render on the device: its device time (kernel launches) and its time in the worker.
  void record_render(double device_ms, double worker_ms);

  std::uint64_t requests() const;
  std::map<int, std::uint64_t> by_status() const;
  std::map<std::string, std::uint64_t> by_endpoint() const;
  std::uint64_t renders() const;
  double device_ms_total() const;
  Percentiles latency() const { return latency_.summary(); }          // every answered request
  Percentiles render_latency() const { return render_.summary(); }    // tile/region requests answered 200
  Percentiles device_latency() const { return device_.summary(); }    // device time per render

  void record_render_request(double ms) { render_.add(ms); }

 private:
  mutable std::mutex mutex_;
  std::uint64_t requests_ = 0, renders_ = 0;
  double device_ms_total_ = 0.0;
  std::map<int, std::uint64_t> by_status_;
  std::map<std::string, std::uint64_t> by_endpoint_;
  LatencyRing latency_, render_, device_;
};

}  // namespace stex::service
