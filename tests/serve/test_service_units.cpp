// The service's building blocks in-process, without a device or sockets: the tile cache's byte cap and LRU
// order, the device queue's bound and deadlines, nearest-rank percentiles.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "service/device_queue.h"
#include "service/metrics.h"
#include "service/tile_cache.h"

namespace stex::service {
namespace {

std::shared_ptr<const CachedBody> body(std::size_t n) {
  auto b = std::make_shared<CachedBody>();
  b->body.assign(n, 'x');
  return b;
}

TEST(ServiceUnits, CacheNeverHoldsMoreThanItsCapAndEvictsLeastRecentlyUsed) {
  const std::size_t entry = 1000 + 2 + TileCache::k_entry_overhead;  // body + key "kN" + overhead
  TileCache c(3 * entry);
  c.put("k1", body(1000));
  c.put("k2", body(1000));
  c.put("k3", body(1000));
  EXPECT_EQ(c.bytes(), 3 * entry);
  ASSERT_NE(c.get("k1"), nullptr);  // k1 is now the most recent: k2 goes first
  c.put("k4", body(1000));
  EXPECT_LE(c.bytes(), c.cap());
  EXPECT_EQ(c.entries(), 3u);
  EXPECT_EQ(c.get("k2"), nullptr);
  EXPECT_NE(c.get("k1"), nullptr);
  EXPECT_NE(c.get("k4"), nullptr);
  EXPECT_EQ(c.evictions(), 1u);
  c.put("big", body(10 * entry));  // larger than the cap: not stored, nothing evicted
  EXPECT_EQ(c.get("big"), nullptr);
  EXPECT_EQ(c.entries(), 3u);
  c.put("k1", body(10));  // replacing an entry accounts its new size
  EXPECT_EQ(c.bytes(), 2 * entry + 10 + 2 + TileCache::k_entry_overhead);
  TileCache none(0);
  none.put("a", body(1));
  EXPECT_EQ(none.entries(), 0u);
}

TEST(ServiceUnits, QueueRefusesBeyondCapacityAndDropsExpiredJobs) {
  DeviceQueue q(2);
  std::atomic<bool> release{false};
  std::atomic<int> ran{0};
  const auto far = Clock::now() + std::chrono::seconds(30);
  auto blocker = q.submit([&] {
    while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ++ran;
  }, far);
  ASSERT_NE(blocker, nullptr);
  while (q.depth() != 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));  // the worker took it
  auto a = q.submit([&] { ++ran; }, far);
  auto expiring = q.submit([&] { ++ran; }, Clock::now() + std::chrono::milliseconds(20));
  ASSERT_NE(a, nullptr);
  ASSERT_NE(expiring, nullptr);
  EXPECT_EQ(q.submit([&] { ++ran; }, far), nullptr);  // two waiting: full
  EXPECT_EQ(q.depth(), 2u);
  // The caller of `expiring` gives up at its deadline; it must not run later.
  EXPECT_FALSE(expiring->wait_until(Clock::now() + std::chrono::milliseconds(30)));
  release = true;
  EXPECT_TRUE(blocker->wait_until(far));
  EXPECT_TRUE(a->wait_until(far));
  // The worker reaches the dropped job after `a` (stop() would discard it uncounted): wait for it.
  for (int i = 0; i < 5000 && q.expired() == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  q.stop();
  EXPECT_EQ(ran.load(), 2);
  EXPECT_EQ(q.expired(), 1u);
  EXPECT_EQ(q.completed(), 2u);
  EXPECT_EQ(q.max_depth(), 2u);
  EXPECT_EQ(q.submit([] {}, far), nullptr);  // stopped
}

TEST(ServiceUnits, JobErrorsReachTheCaller) {
  DeviceQueue q(1);
  auto j = q.submit([] { throw std::runtime_error("boom"); }, Clock::now() + std::chrono::seconds(30));
  ASSERT_NE(j, nullptr);
  ASSERT_TRUE(j->wait_until(Clock::now() + std::chrono::seconds(30)));
  ASSERT_TRUE(j->error());
  EXPECT_THROW(std::rethrow_exception(j->error()), std::runtime_error);
}

TEST(ServiceUnits, NearestRankPercentiles) {
  std::vector<double> s;
  for (int i = 100; i >= 1; --i) s.push_back(i);
  const Percentiles p = percentiles(s);
  EXPECT_EQ(p.count, 100u);
  EXPECT_EQ(p.p50, 50);
  EXPECT_EQ(p.p90, 90);
  EXPECT_EQ(p.p99, 99);
  EXPECT_EQ(p.max, 100);
  EXPECT_DOUBLE_EQ(p.mean, 50.5);
  std::vector<double> one{7};
  EXPECT_EQ(percentiles(one).p50, 7);
  LatencyRing r;
  for (int i = 0; i < int(LatencyRing::k_window) + 10; ++i) r.add(i);
  EXPECT_EQ(r.summary().count, LatencyRing::k_window);  // bounded window
  EXPECT_EQ(r.summary().max, double(LatencyRing::k_window + 9));
}

}  // namespace
}  // namespace stex::service
