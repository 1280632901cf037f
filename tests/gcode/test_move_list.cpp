// MoveList against std::vector<Move> on the same random operations: every index, forward and
// backward iteration, iterator jumps across chunk boundaries, erase_if and copies.
#include <doctest/doctest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "tridex/gcode/move_list.hpp"

using namespace tridex;
using namespace tridex::gcode;

namespace {

Move numbered(int n) {
  Move m;
  m.line = n;
  m.tool = n % 7;
  m.end = Vec3(n, -n, 0.5 * n);
  return m;
}

bool same(const Move& a, const Move& b) {
  return a.line == b.line && a.tool == b.tool && a.end == b.end;
}

void check_same(const MoveList& list, const std::vector<Move>& reference) {
  REQUIRE(list.size() == reference.size());
  CHECK(list.empty() == reference.empty());
  bool indexed = true, walked = true;
  for (std::size_t i = 0; i < reference.size(); ++i)
    indexed = indexed && same(list[i], reference[i]);
  std::size_t i = 0;
  for (const Move& m : list) walked = walked && same(m, reference[i++]);
  CHECK(indexed);
  CHECK(walked);
  CHECK(i == reference.size());
  CHECK(static_cast<std::size_t>(list.end() - list.begin()) == reference.size());
  if (!reference.empty()) {
    CHECK(same(list.front(), reference.front()));
    CHECK(same(list.back(), reference.back()));
  }
}

}  // namespace

TEST_CASE("MoveList: the same moves as a vector, whatever the size") {
  std::mt19937 random(11);
  // Past the doubling chunks (130,816 moves) and one more full chunk, then sizes around the
  // chunk boundaries and small ones.
  for (std::size_t size :
       {std::size_t{0}, std::size_t{1}, std::size_t{255}, std::size_t{256}, std::size_t{257},
        std::size_t{767}, std::size_t{768}, std::size_t{130815}, std::size_t{130816},
        std::size_t{130817}, std::size_t{130816 + 65536 + 3}}) {
    CAPTURE(size);
    MoveList list;
    std::vector<Move> reference;
    for (std::size_t k = 0; k < size; ++k) {
      list.push_back(numbered(static_cast<int>(k)));
      reference.push_back(numbered(static_cast<int>(k)));
    }
    check_same(list, reference);
    if (size == 0) continue;

    // Random jumps, both ways, and backward steps.
    std::uniform_int_distribution<std::size_t> pick(0, size - 1);
    bool jumped = true;
    for (int trial = 0; trial < 2000; ++trial) {
      const std::size_t a = pick(random), b = pick(random);
      MoveList::const_iterator it = list.begin() + static_cast<std::ptrdiff_t>(a);
      it += static_cast<std::ptrdiff_t>(b) - static_cast<std::ptrdiff_t>(a);
      jumped =
          jumped && same(*it, reference[b]) && it - list.begin() == static_cast<std::ptrdiff_t>(b);
      if (b > 0) {
        --it;
        jumped = jumped && same(*it, reference[b - 1]);
      }
    }
    CHECK(jumped);
    std::vector<Move> backwards(reference.rbegin(), reference.rend());
    std::vector<Move> walked_back;
    for (auto it = list.end(); it != list.begin();) walked_back.push_back(*--it);
    CHECK(std::equal(walked_back.begin(), walked_back.end(), backwards.begin(), backwards.end(),
                     same));

    // A copy is equal and independent.
    MoveList copy = list;
    copy.push_back(numbered(-1));
    check_same(list, reference);
    CHECK(copy.size() == size + 1);

    // erase_if keeps the others in order, and the list grows on after it.
    const int modulus = 2 + static_cast<int>(random() % 5);
    auto remove = [&](const Move& m) { return m.line % modulus == 1; };
    const std::size_t removed = erase_if(list, remove);
    CHECK(removed == static_cast<std::size_t>(std::erase_if(reference, remove)));
    check_same(list, reference);
    for (int k = 0; k < 1000; ++k) {
      list.push_back(numbered(k));
      reference.push_back(numbered(k));
    }
    check_same(list, reference);
  }
}

TEST_CASE("MoveList: standard algorithms take its iterators") {
  MoveList list;
  for (int k = 0; k < 5000; ++k) list.push_back(numbered(k % 10));
  CHECK(std::count_if(list.begin() + 100, list.begin() + 200,
                      [](const Move& m) { return m.line == 3; }) == 10);
  CHECK(std::find_if(list.begin(), list.end(), [](const Move& m) { return m.line == 9; }) -
            list.begin() ==
        9);
  list.clear();
  CHECK(list.empty());
  CHECK(list.begin() == list.end());
}
