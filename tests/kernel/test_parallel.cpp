// parallel.hpp, the one thread pool: every chunk runs once on 1 or many threads, each worker keeps
// its own scratch, and an exception thrown by the work (or by a background task) comes back to
// the caller instead of ending the process.
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "tridex/parallel.hpp"

using namespace tridex::detail;

TEST_CASE("parallel: every chunk runs exactly once, on 1 and on many threads") {
  for (unsigned threads : {1u, 2u, 3u, 8u, 0u}) {
    for (std::size_t chunks : {std::size_t{0}, std::size_t{1}, std::size_t{7}, std::size_t{1000}}) {
      std::vector<std::atomic<int>> runs(chunks);
      for_each_chunk(chunks, threads, [&](std::size_t c) { runs[c].fetch_add(1); });
      for (std::size_t c = 0; c < chunks; ++c) CHECK(runs[c].load() == 1);
    }
  }
}

TEST_CASE("parallel: workers are counted by chunks and threads") {
  CHECK(chunk_workers(0, 4) == 1);
  CHECK(chunk_workers(3, 4) == 3);
  CHECK(chunk_workers(100, 4) == 4);
  CHECK(chunk_workers(100, 1) == 1);
  CHECK(chunk_workers(100, 0) == resolve_threads(0));
}

TEST_CASE("parallel: each worker has its own scratch, made once, and its own index") {
  for (unsigned threads : {1u, 4u}) {
    const std::size_t chunks = 500;
    const unsigned workers = chunk_workers(chunks, threads);
    std::atomic<int> made{0};
    std::vector<int> chunk_worker(chunks, -1);
    std::vector<std::size_t> per_worker(workers, 0);
    struct Scratch {
      unsigned id;
      std::vector<std::size_t> seen;
    };
    for_each_chunk_with(
        chunks, threads,
        [&](unsigned id) {
          made.fetch_add(1);
          return Scratch{id, {}};
        },
        [&](std::size_t c, Scratch& s) {
          s.seen.push_back(c);  // no other worker touches s
          chunk_worker[c] = static_cast<int>(s.id);
          per_worker[s.id] = s.seen.size();
        });
    CHECK(made.load() == static_cast<int>(workers));
    std::size_t total = 0;
    for (std::size_t n : per_worker) total += n;
    CHECK(total == chunks);
    for (int w : chunk_worker) CHECK((w >= 0 && w < static_cast<int>(workers)));

    std::vector<std::vector<std::size_t>> found(workers);
    for_each_chunk_indexed(chunks, threads,
                           [&](std::size_t c, unsigned id) { found[id].push_back(c); });
    std::vector<int> runs(chunks, 0);
    for (const auto& list : found)
      for (std::size_t c : list) ++runs[c];
    for (int r : runs) CHECK(r == 1);
  }
}

TEST_CASE(
    "parallel: an exception thrown by a chunk reaches the caller, after every worker stopped") {
  for (unsigned threads : {1u, 2u, 8u}) {
    std::atomic<int> started{0};
    const std::size_t chunks = 10000;
    CHECK_THROWS_WITH_AS(for_each_chunk(chunks, threads,
                                        [&](std::size_t c) {
                                          started.fetch_add(1);
                                          if (c == 3) throw std::runtime_error("chunk 3");
                                        }),
                         "chunk 3", std::runtime_error);
    // No chunk is handed out after the failure: on one thread, none after chunk 3.
    if (threads == 1) CHECK(started.load() == 4);
  }
  // From the scratch maker too.
  CHECK_THROWS_AS(
      for_each_chunk_with(
          8, 4,
          [](unsigned id) -> int { return id == 2 ? throw std::logic_error("no scratch") : 0; },
          [](std::size_t, int&) {}),
      std::logic_error);
}

TEST_CASE(
    "parallel: a background task runs beside the caller and its exception is rethrown at join") {
  std::atomic<int> done{0};
  {
    BackgroundTask task;
    CHECK_FALSE(task.running());
    task.start([&] { done = 1; });
    CHECK(task.running());
    task.join();
    CHECK_FALSE(task.running());
    CHECK(done.load() == 1);
  }
  BackgroundTask failing;
  failing.start([] { throw std::runtime_error("background"); });
  CHECK_THROWS_WITH_AS(failing.join(), "background", std::runtime_error);
  CHECK_NOTHROW(failing.join());  // reported once
  {
    BackgroundTask dropped;  // destroyed unjoined: waits, drops the exception
    dropped.start([] { throw std::runtime_error("dropped"); });
  }
}

namespace test_parallel {

// Threads that ran a chunk for the first time: each thread's own marker, made on its first chunk
// (thread ids can be reused by the system; a thread-local is made anew in every new thread).
std::atomic<int> threads_seen{0};
struct ThreadMark {
  ThreadMark() { threads_seen.fetch_add(1); }
};

int new_threads_in_call(unsigned threads) {
  const int before = threads_seen.load();
  for_each_chunk(64, threads, [&](std::size_t) {
    thread_local ThreadMark mark;
    std::this_thread::sleep_for(std::chrono::microseconds(200));  // room for every worker
  });
  return threads_seen.load() - before;
}

TEST_CASE("parallel: a pool put in place runs every call on the same kept threads") {
  ThreadPool pool(3);
  CHECK(pool.size() == 3);
  const UsePool use(pool);
  new_threads_in_call(3);
  for (int call = 0; call < 4; ++call) CHECK(new_threads_in_call(3) == 0);  // none started
  // Every chunk once, and exceptions back to the caller, as without a pool.
  for (std::size_t chunks : {std::size_t{1}, std::size_t{7}, std::size_t{1000}}) {
    std::vector<std::atomic<int>> runs(chunks);
    for_each_chunk(chunks, 3, [&](std::size_t c) { runs[c].fetch_add(1); });
    for (std::size_t c = 0; c < chunks; ++c) CHECK(runs[c].load() == 1);
  }
  CHECK_THROWS_AS(for_each_chunk(100, 3,
                                 [](std::size_t c) {
                                   if (c == 42) throw std::runtime_error("chunk 42");
                                 }),
                  std::runtime_error);
  // A parallel call inside a chunk (the pool busy) starts threads of its own.
  std::atomic<int> inner{0};
  for_each_chunk(
      4, 3, [&](std::size_t) { for_each_chunk(10, 2, [&](std::size_t) { inner.fetch_add(1); }); });
  CHECK(inner.load() == 40);
  CHECK(new_threads_in_call(3) == 0);  // still the kept threads after a failure and a nesting
}

TEST_CASE("parallel: without a pool the calls start threads of their own") {
  int started = 0;
  for (int call = 0; call < 4; ++call) started += new_threads_in_call(3);
  CHECK(started > 0);
}

}  // namespace test_parallel
