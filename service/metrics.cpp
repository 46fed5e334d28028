// Request counters and latency percentiles (service/metrics.h).
#include "service/metrics.h"

#include <algorithm>
#include <cmath>

namespace stex::service {

Percentiles percentiles(std::vector<double>& s) {
  Percentiles p;
  p.count = s.size();
  if (s.empty()) return p;
  std::sort(s.begin(), s.end());
  auto rank = [&](double q) {  // nearest rank: the smallest sample with at least q of the samples <= it
    std::size_t k = std::size_t(std::ceil(q * double(s.size())));
    if (k < 1) k = 1;
    return s[std::min(k, s.size()) - 1];
  };
  p.p50 = rank(0.50);
  p.p90 = rank(0.90);
  p.p99 = rank(0.99);
  p.max = s.back();
  double sum = 0;
  for (double v : s) sum += v;
  p.mean = sum / double(s.size());
  return p;
}

void LatencyRing::add(double ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (ring_.size() < k_window) {
    ring_.push_back(ms);
  } else {
    ring_[next_] = ms;
    next_ = (next_ + 1) % k_window;
  }
}

Percentiles LatencyRing::summary() const {
  std::vector<double> copy;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    copy = ring_;
  }
  return percentiles(copy);
}

void Metrics::record(const std::string& endpoint, int status, double ms) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++requests_;
    ++by_status_[status];
    ++by_endpoint_[endpoint];
  }
  latency_.add(ms);
}

void Metrics::record_render(double device_ms, double /*worker_ms*/) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++renders_;
    device_ms_total_ += device_ms;
  }
  device_.add(device_ms);
}

std::uint64_t Metrics::requests() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return requests_;
}
std::map<int, std::uint64_t> Metrics::by_status() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return by_status_;
}
std::map<std::string, std::uint64_t> Metrics::by_endpoint() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return by_endpoint_;
}
std::uint64_t Metrics::renders() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return renders_;
}
double Metrics::device_ms_total() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return device_ms_total_;
}

}  // namespace stex::service
