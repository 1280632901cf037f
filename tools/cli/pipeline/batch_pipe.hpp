// tridex command — BatchPipe: hands items from one thread to a worker thread, in order.
//
// Why: parsing a big program is two serial jobs of about the same size, the interpreter making
// moves and the grouping that keeps them (whose cost is mostly the kernel zeroing the fresh pages
// they are written to). With a second core the two can overlap: the interpreter's thread pushes
// moves, a worker consumes them in the same order. Items travel in batches through a bounded
// queue of reused buffers, so the pipe allocates nothing after its first batches and never holds
// more than kBatches of them.
//
// Exceptions: one thrown by `consume` stops the worker; the producer sees it again from its next
// push() at a batch boundary, or from finish(). Without a worker (threaded == false) `consume`
// runs inside push(), as a plain call would.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <utility>
#include <vector>

#include "tridex/parallel.hpp"

namespace tridex::cli {

template <class Item>
class BatchPipe {
 public:
  static constexpr std::size_t kBatchItems = 4096;
  static constexpr std::size_t kBatches = 4;

  BatchPipe(std::function<void(const Item&)> consume, bool threaded)
      : consume_(std::move(consume)) {
    if (!threaded) return;
    current_.reserve(kBatchItems);
    worker_.start([this] { work(); });
  }
  BatchPipe(const BatchPipe&) = delete;
  BatchPipe& operator=(const BatchPipe&) = delete;
  // Stops the worker; what it had not consumed is dropped (the producer failed, or finish() ran).
  ~BatchPipe() { stop(); }

  void push(const Item& item) {
    if (!worker_.running()) {
      consume_(item);
      return;
    }
    current_.push_back(item);
    if (current_.size() == kBatchItems) hand_over();
  }

  // Waits until the worker has consumed everything pushed; rethrows what `consume` threw.
  void finish() {
    if (worker_.running()) {
      if (!current_.empty()) hand_over();
      {
        std::unique_lock lock(mutex_);
        changed_.wait(lock, [&] { return (ready_.empty() && !busy_) || error_; });
      }
      stop();
    }
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void hand_over() {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return ready_.size() < kBatches || error_; });
    if (error_) std::rethrow_exception(error_);
    ready_.push_back(std::move(current_));
    if (spare_.empty()) {
      current_ = {};
      current_.reserve(kBatchItems);
    } else {
      current_ = std::move(spare_.back());
      spare_.pop_back();
    }
    changed_.notify_all();
  }

  void work() {
    std::unique_lock lock(mutex_);
    for (;;) {
      changed_.wait(lock, [&] { return !ready_.empty() || stopping_; });
      if (ready_.empty()) return;  // stopping, nothing left
      std::vector<Item> batch = std::move(ready_.front());
      ready_.pop_front();
      busy_ = true;
      lock.unlock();
      try {
        for (const Item& item : batch) consume_(item);
      } catch (...) {
        lock.lock();
        error_ = std::current_exception();
        busy_ = false;
        ready_.clear();
        changed_.notify_all();
        return;
      }
      batch.clear();
      lock.lock();
      busy_ = false;
      spare_.push_back(std::move(batch));
      changed_.notify_all();
    }
  }

  void stop() {
    if (!worker_.running()) return;
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
      ready_.clear();
    }
    changed_.notify_all();
    worker_.join();
  }

  std::function<void(const Item&)> consume_;
  std::vector<Item> current_;  // the producer's batch being filled
  std::mutex mutex_;           // guards everything below
  std::condition_variable changed_;
  std::deque<std::vector<Item>> ready_;  // full batches, oldest first
  std::vector<std::vector<Item>> spare_;
  bool busy_ = false;  // the worker holds a batch
  bool stopping_ = false;
  std::exception_ptr error_;
  detail::BackgroundTask worker_;  // runs work(), which keeps what consume_ throws in error_
};

}  // namespace tridex::cli
