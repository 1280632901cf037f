// MoveList against std::vector<Move> on the same random operations: every index, forward and
// backward iteration, iterator jumps across chunk boundaries, erase_if and copies.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "tridex/gcode/move_list.hpp"

namespace test_move_list {

using namespace tridex;
using namespace tridex::gcode;

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

// Every field of a move, bit for bit: what moves share is stored once per change and the rotary
// and machine positions only from the first move that has any.
Move full(int n) {
  Move m = numbered(n);
  m.kind = static_cast<MoveKind>(n % 4);
  m.file = n % 3;
  m.start = Vec3(-n, 0.25 * n, -0.0);
  m.axis = n % 5 == 0 ? Vec3(0, -1, 0) : Vec3(0, 0, 1);
  m.feed = n % 2 == 0 ? 0.0 : -0.0;  // the sign of a zero is kept
  m.spindle = n % 6 < 3 ? 12000 : -8000;
  m.from_far = n % 9 == 0;
  if (n >= 300) {  // positions from the 301st move on: those before read zeros
    m.rotary_axes = static_cast<unsigned char>(n % 8);
    m.pose = static_cast<PoseLaw>(n % 3);
    m.rotary = {0.5 * n, n % 10 == 0 ? -0.0 : 1.0, -2.0 * n};
    m.machine = Vec3(n, n + 1, n + 2);
    m.rotary_start = {n % 7 == 0 ? std::nan("") : 1.0, 2, 3};
  }
  return m;
}

bool bits_equal(const Move& a, const Move& b) {
  const auto same_double = [](double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; };
  const auto same_vec = [&](const Vec3& x, const Vec3& y) {
    return same_double(x.x, y.x) && same_double(x.y, y.y) && same_double(x.z, y.z);
  };
  const auto same_array = [&](const std::array<double, 3>& x, const std::array<double, 3>& y) {
    return same_double(x[0], y[0]) && same_double(x[1], y[1]) && same_double(x[2], y[2]);
  };
  return a.line == b.line && a.kind == b.kind && a.tool == b.tool && a.file == b.file &&
         same_vec(a.start, b.start) && same_vec(a.end, b.end) && same_vec(a.axis, b.axis) &&
         same_double(a.feed, b.feed) && same_double(a.spindle, b.spindle) &&
         a.from_far == b.from_far && a.rotary_axes == b.rotary_axes && a.pose == b.pose &&
         same_array(a.rotary, b.rotary) && same_vec(a.machine, b.machine) &&
         same_array(a.rotary_start, b.rotary_start);
}

TEST_CASE("MoveList: every field reads back bit for bit, after erase_if and replace_tool") {
  MoveList list;
  std::vector<Move> reference;
  for (int n = 0; n < 70000; ++n) {
    list.push_back(full(n));
    reference.push_back(full(n));
  }
  const auto all_equal = [&] {
    bool equal = list.size() == reference.size();
    for (std::size_t i = 0; equal && i < reference.size(); ++i)
      equal = bits_equal(list[i], reference[i]);
    std::size_t i = 0;
    for (auto it = list.begin(); equal && it != list.end(); ++it, ++i)
      equal = bits_equal(*it, reference[i]) && it->line == reference[i].line;
    return equal;
  };
  CHECK(all_equal());
  // Removing moves with and without positions keeps the others' positions with them.
  auto remove = [](const Move& m) { return m.line % 4 == 1 || (m.line > 200 && m.line < 400); };
  CHECK(erase_if(list, remove) == static_cast<std::size_t>(std::erase_if(reference, remove)));
  CHECK(all_equal());
  list.replace_tool(3, 42);
  for (Move& m : reference)
    if (m.tool == 3) m.tool = 42;
  CHECK(all_equal());
  for (int n = 0; n < 1000; ++n) {  // and the list grows on
    list.push_back(full(n));
    reference.push_back(full(n));
  }
  CHECK(all_equal());
  // A list that never held positions reads zeros; one whose positions were all removed too.
  MoveList plain{numbered(1), numbered(2)};
  CHECK(bits_equal(plain[1], numbered(2)));
}

}  // namespace test_move_list
