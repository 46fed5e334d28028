// The bounded device queue of stex serve (service/device_queue.h).
#include "service/device_queue.h"

namespace stex::service {

bool DeviceJob::wait_until(Clock::time_point until) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (cv_.wait_until(lock, until, [&] { return state_ == State::Done || state_ == State::Dropped; }))
    return state_ == State::Done;
  if (state_ == State::Queued) state_ = State::Dropped;  // the worker skips it
  return false;
}

std::exception_ptr DeviceJob::error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

DeviceQueue::DeviceQueue(std::size_t capacity) : capacity_(capacity == 0 ? 1 : capacity) {
  worker_ = std::thread([this] { run(); });
}

DeviceQueue::~DeviceQueue() { stop(); }

std::shared_ptr<DeviceJob> DeviceQueue::submit(std::function<void()> work, Clock::time_point deadline) {
  auto job = std::make_shared<DeviceJob>();
  job->work_ = std::move(work);
  job->deadline_ = deadline;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_ || jobs_.size() >= capacity_) return nullptr;
    jobs_.push_back(job);
    if (jobs_.size() > max_depth_) max_depth_ = jobs_.size();
  }
  cv_.notify_one();
  return job;
}

void DeviceQueue::stop() {
  std::deque<std::shared_ptr<DeviceJob>> dropped;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    dropped.swap(jobs_);
  }
  cv_.notify_all();
  for (auto& job : dropped) {
    std::lock_guard<std::mutex> lock(job->mutex_);
    job->state_ = DeviceJob::State::Dropped;
    job->cv_.notify_all();
  }
  if (worker_.joinable()) worker_.join();
}

std::size_t DeviceQueue::depth() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return jobs_.size();
}
std::size_t DeviceQueue::max_depth() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return max_depth_;
}
std::uint64_t DeviceQueue::expired() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return expired_;
}
std::uint64_t DeviceQueue::completed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return completed_;
}

void DeviceQueue::run() {
  for (;;) {
    std::shared_ptr<DeviceJob> job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [&] { return stopping_ || !jobs_.empty(); });
      if (stopping_) return;
      job = jobs_.front();
      jobs_.pop_front();
    }
    bool run_it = false;
    {
      std::lock_guard<std::mutex> lock(job->mutex_);
      if (job->state_ == DeviceJob::State::Queued && Clock::now() < job->deadline_) {
        job->state_ = DeviceJob::State::Running;
        run_it = true;
      } else {
        job->state_ = DeviceJob::State::Dropped;
      }
    }
    if (!run_it) {
      job->cv_.notify_all();
      std::lock_guard<std::mutex> lock(mutex_);
      ++expired_;
      continue;
    }
    std::exception_ptr error;
    try {
      job->work_();
    } catch (...) {
      error = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lock(job->mutex_);
      job->error_ = error;
      job->state_ = DeviceJob::State::Done;
      job->work_ = nullptr;  // release captured buffers now
    }
    job->cv_.notify_all();
    std::lock_guard<std::mutex> lock(mutex_);
    ++completed_;
  }
}

}  // namespace stex::service
