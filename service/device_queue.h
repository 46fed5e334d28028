// The bounded queue in front of the device (stex serve): requests become jobs run one at a time by a single
// worker thread that owns every device object, so the OpenCL context, its compiled programs and the models'
// renderers stay warm and are never touched concurrently. The queue holds at most `capacity` waiting jobs:
// submit() refuses more (the caller answers 503 with Retry-After) instead of growing without bound. A job
// carries a deadline (the per-request time limit): one still waiting at its deadline, or abandoned by its
// caller, is dropped without running.
#pragma once
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

namespace stex::service {

using Clock = std::chrono::steady_clock;

class DeviceJob {
 public:
  enum class State { Queued, Running, Done, Dropped };
  // Waits until the job ran (true; error() holds its exception, if any) or `until` passed. On timeout a
  // job still queued is dropped (it will not run); a running one finishes and its result is discarded.
  bool wait_until(Clock::time_point until);
  std::exception_ptr error() const;

 private:
  friend class DeviceQueue;
  std::function<void()> work_;
  Clock::time_point deadline_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  State state_ = State::Queued;
  std::exception_ptr error_;
};

class DeviceQueue {
 public:
  explicit DeviceQueue(std::size_t capacity);
  ~DeviceQueue();  // stop()
  DeviceQueue(const DeviceQueue&) = delete;
  DeviceQueue& operator=(const DeviceQueue&) = delete;

  // Queues `work` to run on the worker thread before `deadline`; nullptr when `capacity` jobs are already
  // waiting or the queue is stopped.
  std::shared_ptr<DeviceJob> submit(std::function<void()> work, Clock::time_point deadline);
  // Stops the worker after the running job; waiting jobs are dropped (their waiters see a timeout).
  void stop();

  std::size_t capacity() const { return capacity_; }
  std::size_t depth() const;        // jobs waiting (not the running one)
  std::size_t max_depth() const;    // the largest depth seen
  std::uint64_t expired() const;    // jobs dropped at their deadline or by their caller
  std::uint64_t completed() const;  // jobs run

 private:
  void run();
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::shared_ptr<DeviceJob>> jobs_;
  bool stopping_ = false;
  std::size_t max_depth_ = 0;
  std::uint64_t expired_ = 0, completed_ = 0;
  std::thread worker_;
};

}  // namespace stex::service
