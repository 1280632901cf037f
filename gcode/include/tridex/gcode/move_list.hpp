// tridex::gcode — MoveList: a direction's moves, stored compactly in chunks that never move.
//
// Why not std::vector<Move>: a big program's groups hold millions of moves (the model-D-like
// program of bench/backends.md: 5.2 M moves). A growing vector copies all of them at each
// doubling and leaves up to half its capacity unused, so it touches about three times the bytes
// it keeps; fresh memory is paid for in page faults and zeroing, which dominated `parse`
// (bench/gcode/README.md). Chunks are filled once and never copied: the first are small (a short
// program stays small), then they double up to a chunk of at least 8 MiB (huge pages:
// tools/cli/pipeline/huge_pages.hpp).
//
// Why not whole Moves (184 bytes): what a move shares with the moves around it (spindle axis,
// feed, spindle speed, tool, file, kind and pose law) is stored once per change, and the rotary
// and machine positions (a kinematic machine's only) only from the first move that has any. A
// 3+2 program keeps 56 bytes a move (bench/README.md, issue 37). Every field reads back exactly
// as it was pushed (bit for bit: -0.0 and NaN included).
//
// The interface is the part of std::vector the simulation reads: push_back, size, indexing,
// front/back, random-access iteration in program order, erase_if. Moves read back as const values
// (a `const Move&` bound to one lives as long as the reference; a pointer to one dangles once the
// statement ends; writing to one does not compile); the one change the simulation makes in
// place, a tool number, is replace_tool.
#pragma once

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

#include "tridex/gcode/move.hpp"

namespace tridex::gcode {

// An array that grows in chunks that never move: chunk k holds kFirst · 2^k elements up to
// kMax, every chunk after that kMax. T is trivially copyable; elements are written once by
// push_back (a chunk's pages are first touched by its elements, not by a constructor).
template <class T>
class ChunkedArray {
 public:
  static_assert(std::is_trivially_destructible_v<T> && std::is_trivially_copyable_v<T>,
                "chunks are freed without destroying their elements");
  static constexpr std::size_t kFirst = 256;
  // The largest power of two whose chunk stays within 16 MiB: at least 8 MiB, the size from
  // which the command gives a block huge pages.
  static constexpr std::size_t kMax = std::bit_floor((std::size_t{16} << 20) / sizeof(T));
  static_assert(kMax * sizeof(T) >= (std::size_t{8} << 20));

  ChunkedArray() = default;
  ChunkedArray(ChunkedArray&&) noexcept = default;
  ChunkedArray& operator=(ChunkedArray&&) noexcept = default;
  ChunkedArray(const ChunkedArray& other) {
    for (std::size_t i = 0; i < other.size_; ++i) push_back(other[i]);
  }
  ChunkedArray& operator=(const ChunkedArray& other) {
    if (this != &other) {
      ChunkedArray copy(other);
      *this = std::move(copy);
    }
    return *this;
  }

  std::size_t size() const { return size_; }
  void push_back(const T& value) {
    if (size_ == capacity_) {
      const std::size_t chunk = chunk_size(chunks_.size());
      chunks_.emplace_back(static_cast<T*>(::operator new(chunk * sizeof(T))));
      capacity_ += chunk;
    }
    const Place p = place(size_);
    std::construct_at(chunks_[p.chunk].get() + p.offset, value);
    ++size_;
  }
  T& operator[](std::size_t i) {
    const Place p = place(i);
    return chunks_[p.chunk].get()[p.offset];
  }
  const T& operator[](std::size_t i) const {
    const Place p = place(i);
    return chunks_[p.chunk].get()[p.offset];
  }
  // Keeps the first `size` elements (size <= size()); the chunks stay for what comes next.
  void shrink(std::size_t size) { size_ = size; }
  void clear() {
    chunks_.clear();
    size_ = capacity_ = 0;
  }

  // The element at `i` and the end of its chunk: a walk in order steps a pointer between them.
  const T* at(std::size_t i, const T** chunk_end) const {
    const Place p = place(i);
    const T* chunk = chunks_[p.chunk].get();
    *chunk_end = chunk + chunk_size(p.chunk);
    return chunk + p.offset;
  }

 private:
  struct Place {
    std::size_t chunk, offset;
  };

  // The doubling chunks hold kFirst · (2^k − 1) elements before chunk k.
  static constexpr std::size_t kDoublingChunks = std::bit_width(kMax / kFirst);
  static constexpr std::size_t kDoublingElements =
      kFirst * ((std::size_t{1} << kDoublingChunks) - 1);

  static constexpr std::size_t chunk_size(std::size_t chunk) {
    return chunk < kDoublingChunks ? kFirst << chunk : kMax;
  }
  static Place place(std::size_t i) {
    if (i < kDoublingElements) {
      // i / kFirst + 1 lies in [2^k, 2^(k+1)) for the elements of chunk k.
      const std::size_t chunk = static_cast<std::size_t>(std::bit_width(i / kFirst + 1)) - 1;
      return {chunk, i - kFirst * ((std::size_t{1} << chunk) - 1)};
    }
    const std::size_t past = i - kDoublingElements;
    return {kDoublingChunks + past / kMax, past % kMax};
  }

  struct Free {
    void operator()(T* chunk) const { ::operator delete(chunk); }
  };

  std::vector<std::unique_ptr<T, Free>> chunks_;
  std::size_t size_ = 0;
  std::size_t capacity_ = 0;
};

class MoveList {
 private:
  // What each move keeps for itself.
  struct Record {
    Vec3 start, end;
    int line;
    std::uint32_t attributes;  // index into attributes_
  };
  // What a move nearly always shares with the moves around it.
  struct Attributes {
    Vec3 axis;
    double feed, spindle;
    int tool, file;
    MoveKind kind;
    bool from_far;
    unsigned char rotary_axes;
    PoseLaw pose;
  };
  // A kinematic machine's positions (Move::rotary, machine, rotary_start).
  struct Kinematic {
    std::array<double, 3> rotary{};
    Vec3 machine{0.0};
    std::array<double, 3> rotary_start{};
  };
  static_assert(sizeof(Record) == 56);

 public:
  class Iterator;
  using value_type = Move;
  using size_type = std::size_t;
  using const_iterator = Iterator;
  using iterator = Iterator;  // moves read back by value: nothing to write through

  // What one move costs to keep, about: its record, the attributes it shares with its
  // neighbours (counted as a tenth of a record each) and, with a kinematic machine, its rotary and
  // machine positions. For a budget set before the moves are read (MoveBudget).
  static constexpr double bytes_per_move(bool kinematic) {
    return static_cast<double>(sizeof(Record)) + 0.1 * sizeof(Attributes) +
           (kinematic ? static_cast<double>(sizeof(Kinematic)) : 0.0);
  }

  MoveList() = default;
  MoveList(std::initializer_list<Move> moves) {
    for (const Move& m : moves) push_back(m);
  }

  std::size_t size() const { return records_.size(); }
  bool empty() const { return records_.size() == 0; }

  void push_back(const Move& move) {
    Record r;
    r.start = move.start;
    r.end = move.end;
    r.line = move.line;
    r.attributes = attributes_of(move);
    const Kinematic k = kinematic_of(move);
    if (kinematics_.size() > 0 || !all_zero(k)) {
      // The moves before the first that has positions read zeros, as they were pushed.
      while (kinematics_.size() < records_.size()) kinematics_.push_back(Kinematic{});
      kinematics_.push_back(k);
    }
    records_.push_back(r);
  }

  const Move operator[](std::size_t i) const { return decode(records_[i], i); }
  const Move front() const { return (*this)[0]; }
  const Move back() const { return (*this)[size() - 1]; }

  // Every move whose tool is `from` gets tool `to` (a tool the control starts with).
  void replace_tool(int from, int to) {
    for (std::size_t a = 0; a < attributes_.size(); ++a)
      if (attributes_[a].tool == from) attributes_[a].tool = to;
  }

  void clear() {
    records_.clear();
    attributes_.clear();
    kinematics_.clear();
  }

  const_iterator begin() const { return const_iterator(this, 0); }
  const_iterator end() const { return const_iterator(this, size()); }

  // Removes the moves `remove` holds true for, keeping the others' order, in place (as
  // std::erase_if on a vector); returns how many it removed.
  template <class Predicate>
  friend std::size_t erase_if(MoveList& list, Predicate remove) {
    const std::size_t size = list.size();
    const bool kinematic = list.kinematics_.size() > 0;
    std::size_t kept = 0, held = 0;
    for (std::size_t i = 0; i < size; ++i)
      if (!remove(list[i])) {
        if (kept != i) list.records_[kept] = list.records_[i];
        // Positions are held for a prefix of the moves (zeros after it), so for one of the kept.
        if (kinematic && i < list.kinematics_.size()) {
          list.kinematics_[kept] = list.kinematics_[i];
          held = kept + 1;
        }
        ++kept;
      }
    if (kinematic) list.kinematics_.shrink(held);
    list.records_.shrink(kept);
    return size - kept;
  }

  // Random access in program order. Stepping walks a pointer inside the current chunk of
  // records; a jump finds the chunk from the index.
  class Iterator {
   public:
    using iterator_category = std::input_iterator_tag;  // references are values
    using iterator_concept = std::random_access_iterator_tag;
    using value_type = Move;
    using difference_type = std::ptrdiff_t;
    using reference = const Move;
    struct pointer {
      Move move;
      const Move* operator->() const { return &move; }
    };

    Iterator() = default;
    Iterator(const MoveList* list, std::size_t index) : list_(list) { seek(index); }

    const Move operator*() const { return list_->decode(*at_, index_); }
    pointer operator->() const { return {**this}; }
    const Move operator[](difference_type n) const { return *(*this + n); }

    Iterator& operator++() {
      ++index_;
      if (++at_ == chunk_end_) seek(index_);
      return *this;
    }
    Iterator operator++(int) {
      Iterator before = *this;
      ++*this;
      return before;
    }
    Iterator& operator--() {
      seek(index_ - 1);
      return *this;
    }
    Iterator operator--(int) {
      Iterator before = *this;
      --*this;
      return before;
    }
    Iterator& operator+=(difference_type n) {
      seek(static_cast<std::size_t>(static_cast<difference_type>(index_) + n));
      return *this;
    }
    Iterator& operator-=(difference_type n) { return *this += -n; }
    friend Iterator operator+(Iterator it, difference_type n) { return it += n; }
    friend Iterator operator+(difference_type n, Iterator it) { return it += n; }
    friend Iterator operator-(Iterator it, difference_type n) { return it -= n; }
    friend difference_type operator-(const Iterator& a, const Iterator& b) {
      return static_cast<difference_type>(a.index_) - static_cast<difference_type>(b.index_);
    }
    friend bool operator==(const Iterator& a, const Iterator& b) { return a.index_ == b.index_; }
    friend auto operator<=>(const Iterator& a, const Iterator& b) { return a.index_ <=> b.index_; }

   private:
    void seek(std::size_t index) {
      index_ = index;
      at_ = chunk_end_ = nullptr;
      if (index >= list_->size()) return;  // end(): nothing to point at
      at_ = list_->records_.at(index, &chunk_end_);
    }

    const MoveList* list_ = nullptr;
    std::size_t index_ = 0;
    const Record* at_ = nullptr;
    const Record* chunk_end_ = nullptr;
  };

 private:
  static bool same_bits(const double* a, const double* b, std::size_t n) {
    return std::memcmp(a, b, n * sizeof(double)) == 0;
  }
  static bool same(const Attributes& a, const Attributes& b) {
    return same_bits(&a.axis.x, &b.axis.x, 1) && same_bits(&a.axis.y, &b.axis.y, 1) &&
           same_bits(&a.axis.z, &b.axis.z, 1) && same_bits(&a.feed, &b.feed, 1) &&
           same_bits(&a.spindle, &b.spindle, 1) && a.tool == b.tool && a.file == b.file &&
           a.kind == b.kind && a.from_far == b.from_far && a.rotary_axes == b.rotary_axes &&
           a.pose == b.pose;
  }
  static bool all_zero(const Kinematic& k) {
    // Bit for bit: a -0.0 is kept.
    const double zeros[3] = {0.0, 0.0, 0.0};
    return same_bits(k.rotary.data(), zeros, 3) && same_bits(&k.machine.x, zeros, 1) &&
           same_bits(&k.machine.y, zeros, 1) && same_bits(&k.machine.z, zeros, 1) &&
           same_bits(k.rotary_start.data(), zeros, 3);
  }
  static Kinematic kinematic_of(const Move& m) { return {m.rotary, m.machine, m.rotary_start}; }

  // The index of `move`'s attributes: one of the last few (moves alternate between a few, as
  // feeds and rapids do), else a new entry.
  std::uint32_t attributes_of(const Move& move) {
    Attributes a{};
    a.axis = move.axis;
    a.feed = move.feed;
    a.spindle = move.spindle;
    a.tool = move.tool;
    a.file = move.file;
    a.kind = move.kind;
    a.from_far = move.from_far;
    a.rotary_axes = move.rotary_axes;
    a.pose = move.pose;
    const std::size_t n = attributes_.size();
    for (std::size_t back = 1; back <= 4 && back <= n; ++back)
      if (same(attributes_[n - back], a)) return static_cast<std::uint32_t>(n - back);
    attributes_.push_back(a);
    return static_cast<std::uint32_t>(n);
  }

  Move decode(const Record& r, std::size_t i) const {
    const Attributes& a = attributes_[r.attributes];
    Move m;
    m.line = r.line;
    m.kind = a.kind;
    m.tool = a.tool;
    m.file = a.file;
    m.start = r.start;
    m.end = r.end;
    m.axis = a.axis;
    m.feed = a.feed;
    m.spindle = a.spindle;
    m.from_far = a.from_far;
    m.rotary_axes = a.rotary_axes;
    m.pose = a.pose;
    if (i < kinematics_.size()) {
      const Kinematic& k = kinematics_[i];
      m.rotary = k.rotary;
      m.machine = k.machine;
      m.rotary_start = k.rotary_start;
    }
    return m;
  }

  ChunkedArray<Record> records_;
  ChunkedArray<Attributes> attributes_;
  ChunkedArray<Kinematic> kinematics_;  // for the moves before and at the last with positions
};

}  // namespace tridex::gcode
