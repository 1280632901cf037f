// tridex — the one thread pool: independent chunks of work spread over a few threads, and one
// background task beside the caller.
//
// Why one: every parallel loop in the kernel (milling, fine cells, dexelizing, surface
// extraction, dexel operations) and the command's pipe needs the same three things, done once
// here: a worker takes the next chunk not yet taken (so uneven chunks balance), each worker may
// own scratch memory that lives across its chunks, and an exception thrown by the work comes
// back to the caller instead of ending the process (std::terminate, had it escaped a thread).
// Results must not depend on the thread count: a chunk's result goes to a place fixed by the
// chunk's index (or is merged in an order that does not depend on which worker ran it).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace tridex::detail {

// 0 threads means every hardware thread.
inline unsigned resolve_threads(unsigned threads) {
  return threads ? threads : std::max(1u, std::thread::hardware_concurrency());
}

// How many workers the for_each_chunk family uses for `chunks` chunks on up to `threads` threads
// (0: every hardware thread): never more than there are chunks, and at least one (the caller).
inline unsigned chunk_workers(std::size_t chunks, unsigned threads) {
  return static_cast<unsigned>(
      std::min<std::size_t>(resolve_threads(threads), std::max<std::size_t>(1, chunks)));
}

// Calls work(c, scratch) once for every chunk c in [0, chunks), on chunk_workers(chunks, threads)
// workers (the caller's thread is worker 0), each taking the next chunk not yet taken; `scratch`
// is the worker's own object, made once per worker by make_scratch(worker index) before its first
// chunk and kept across its chunks. Returns when every worker has stopped. If the work (or
// make_scratch) throws, no further chunk is handed out, every worker is joined, and the first
// exception caught is rethrown here; chunks already taken by other workers run to their end.
template <class MakeScratch, class Work>
void for_each_chunk_with(std::size_t chunks, unsigned threads, MakeScratch&& make_scratch,
                         Work&& work) {
  const unsigned count = chunk_workers(chunks, threads);
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto worker = [&](unsigned id) {
    try {
      auto scratch = make_scratch(id);
      for (std::size_t c;
           !failed.load(std::memory_order_relaxed) && (c = next.fetch_add(1)) < chunks;)
        work(c, scratch);
    } catch (...) {
      failed.store(true, std::memory_order_relaxed);
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(count - 1);
  try {
    for (unsigned id = 1; id < count; ++id) pool.emplace_back(worker, id);
  } catch (...) {  // no thread to be had: stop those started, then report it
    failed.store(true, std::memory_order_relaxed);
    for (std::thread& t : pool) t.join();
    throw;
  }
  worker(0);
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

// The same, telling the work which worker (0 to chunk_workers(chunks, threads) − 1) runs the
// chunk: work(c, worker), for results gathered per worker and merged afterwards.
template <class Work>
void for_each_chunk_indexed(std::size_t chunks, unsigned threads, Work&& work) {
  for_each_chunk_with(
      chunks, threads, [](unsigned id) { return id; },
      [&](std::size_t c, unsigned id) { work(c, id); });
}

// The same with no scratch: work(c) once for every chunk c.
template <class Work>
void for_each_chunk(std::size_t chunks, unsigned threads, Work&& work) {
  for_each_chunk_with(
      chunks, threads, [](unsigned) { return 0; }, [&](std::size_t c, int) { work(c); });
}

// One task run on a thread of its own beside the caller's, started by start() and waited for by
// join(), which rethrows what the task threw. Destroying a started task waits for it (and drops
// its exception): the task must be told to stop first if it would not end by itself.
class BackgroundTask {
 public:
  BackgroundTask() = default;
  BackgroundTask(const BackgroundTask&) = delete;
  BackgroundTask& operator=(const BackgroundTask&) = delete;
  ~BackgroundTask() {
    if (thread_.joinable()) thread_.join();
  }

  // Starts `task` (callable with no arguments). The task must not be running already.
  template <class Task>
  void start(Task&& task) {
    error_ = nullptr;
    thread_ = std::thread([this, task = std::forward<Task>(task)]() mutable {
      try {
        task();
      } catch (...) {
        error_ = std::current_exception();
      }
    });
  }

  // Whether a task was started and not yet joined.
  bool running() const { return thread_.joinable(); }

  // Waits for the task; rethrows its exception, if it threw one.
  void join() {
    if (thread_.joinable()) thread_.join();
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  }

 private:
  std::exception_ptr error_;  // written by the task's thread, read after the join
  std::thread thread_;
};

}  // namespace tridex::detail
