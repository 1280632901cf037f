// batch_pipe.hpp: every item reaches the worker once, in the order pushed, with or without the
// worker thread; an exception thrown by the consumer comes back to the producer; a producer that
// gives up mid-way leaves no thread behind.
#include <doctest/doctest.h>

#include <stdexcept>
#include <vector>

#include "pipeline/batch_pipe.hpp"

using tridex::cli::BatchPipe;

TEST_CASE("BatchPipe: items arrive once and in order") {
  for (bool threaded : {false, true})
    for (std::size_t count : {std::size_t{0}, std::size_t{1}, BatchPipe<int>::kBatchItems,
                              BatchPipe<int>::kBatchItems * BatchPipe<int>::kBatches * 3 + 17}) {
      CAPTURE(threaded);
      CAPTURE(count);
      std::vector<int> seen;
      BatchPipe<int> pipe([&](const int& item) { seen.push_back(item); }, threaded);
      for (std::size_t k = 0; k < count; ++k) pipe.push(static_cast<int>(k));
      pipe.finish();
      REQUIRE(seen.size() == count);
      bool in_order = true;
      for (std::size_t k = 0; k < count; ++k) in_order = in_order && seen[k] == static_cast<int>(k);
      CHECK(in_order);
    }
}

TEST_CASE("BatchPipe: the consumer's exception reaches the producer") {
  for (bool threaded : {false, true}) {
    CAPTURE(threaded);
    const int failing = 100'000;
    std::size_t consumed = 0;
    BatchPipe<int> pipe(
        [&](const int& item) {
          if (item == failing) throw std::runtime_error("item " + std::to_string(item));
          ++consumed;
        },
        threaded);
    bool thrown = false;
    try {
      for (int k = 0; k < 2 * failing; ++k) pipe.push(k);
      pipe.finish();
    } catch (const std::runtime_error& e) {
      thrown = std::string(e.what()) == "item 100000";
    }
    CHECK(thrown);
    CHECK(consumed == static_cast<std::size_t>(failing));  // nothing after the failing item
  }
}

TEST_CASE("BatchPipe: a producer that stops early is not kept waiting") {
  std::size_t consumed = 0;
  {
    BatchPipe<int> pipe([&](const int&) { ++consumed; }, true);
    for (int k = 0; k < 50'000; ++k) pipe.push(k);
    // No finish(): the destructor stops the worker, whatever it had not reached.
  }
  CHECK(consumed <= 50'000);
}
