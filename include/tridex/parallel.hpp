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
//
// By default each parallel call starts its threads and joins them. An embedder that makes many
// short calls (a session asked after every few moves, issue 38) keeps a ThreadPool instead and
// puts it in place with UsePool for a scope: the calling thread's parallel calls then run on the
// pool's threads, started once. Opt-in, so that the command's long calls are as they were.
#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace tridex::detail {

// Threads started once and reused by every parallel call of the threads that put it in place
// (UsePool). try_run() gives one job at a time to the caller and up to size() − 1 kept threads;
// while the pool is busy (a parallel call inside a job, or from another thread) it declines, and
// the call starts threads of its own.
class ThreadPool {
 public:
  // `threads` in all, the caller's included (0: every hardware thread).
  explicit ThreadPool(unsigned threads);
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;
  ~ThreadPool();

  unsigned size() const { return static_cast<unsigned>(threads_.size()) + 1; }
  // Calls job(id) for every id in [0, count), count ≤ size(): id 0 on the calling thread, the
  // others on the kept threads; returns true when every call has returned, or false at once,
  // calling nothing, when the pool is busy. `job` must not throw.
  bool try_run(unsigned count, const std::function<void(unsigned)>& job);

 private:
  void serve(unsigned id);

  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(unsigned)>* job_ = nullptr;
  unsigned count_ = 0, pending_ = 0;
  std::uint64_t generation_ = 0;
  bool stop_ = false;
  std::atomic<bool> busy_{false};
  std::vector<std::thread> threads_;
};

// The pool the calling thread's parallel calls use (nullptr: threads started per call).
inline ThreadPool*& current_pool() {
  thread_local ThreadPool* pool = nullptr;
  return pool;
}

// Puts `pool` in place for the calling thread's parallel calls until the end of the scope.
class UsePool {
 public:
  explicit UsePool(ThreadPool& pool) : previous_(std::exchange(current_pool(), &pool)) {}
  UsePool(const UsePool&) = delete;
  UsePool& operator=(const UsePool&) = delete;
  ~UsePool() { current_pool() = previous_; }

 private:
  ThreadPool* previous_;
};

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
  if (ThreadPool* kept = current_pool();
      kept && count > 1 &&
      kept->try_run(std::min(count, kept->size()), [&](unsigned id) { worker(id); })) {
    if (error) std::rethrow_exception(error);
    return;
  }
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

inline ThreadPool::ThreadPool(unsigned threads) {
  const unsigned count = resolve_threads(threads);
  threads_.reserve(count - 1);
  try {
    for (unsigned id = 1; id < count; ++id) threads_.emplace_back([this, id] { serve(id); });
  } catch (...) {  // no thread to be had: stop those started, then report it
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : threads_) t.join();
    throw;
  }
}

inline ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : threads_) t.join();
}

inline bool ThreadPool::try_run(unsigned count, const std::function<void(unsigned)>& job) {
  if (busy_.exchange(true)) return false;
  count = std::clamp(count, 1u, size());
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = &job, count_ = count, pending_ = count - 1;
    ++generation_;
  }
  wake_.notify_all();
  job(0);
  {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return pending_ == 0; });
    job_ = nullptr;
  }
  busy_.store(false);
  return true;
}

inline void ThreadPool::serve(unsigned id) {
  std::uint64_t seen = 0;
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
    if (stop_) return;
    seen = generation_;
    if (id >= count_) continue;  // not needed this time
    const std::function<void(unsigned)>* job = job_;
    lock.unlock();
    (*job)(id);
    lock.lock();
    if (--pending_ == 0) done_.notify_one();
  }
}

}  // namespace tridex::detail
