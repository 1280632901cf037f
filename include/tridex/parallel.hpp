// tridex — independent chunks of work spread over a few threads.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace tridex::detail {

// 0 threads means every hardware thread.
inline unsigned resolve_threads(unsigned threads) {
  return threads ? threads : std::max(1u, std::thread::hardware_concurrency());
}

// Calls work(c) once for every chunk c in [0, chunks), on up to `threads` threads (0: every
// hardware thread), each thread taking the next chunk not yet taken; returns when all are done.
// A result that each chunk writes to its own place does not depend on the thread count.
template <class Work>
void for_each_chunk(std::size_t chunks, unsigned threads, Work&& work) {
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (std::size_t c; (c = next.fetch_add(1)) < chunks;) work(c);
  };
  const auto count = static_cast<unsigned>(std::min<std::size_t>(resolve_threads(threads), std::max<std::size_t>(1, chunks)));
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < count; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
}

}  // namespace tridex::detail
