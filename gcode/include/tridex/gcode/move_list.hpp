// tridex::gcode — MoveList: a direction's moves, stored in chunks that never move.
//
// Why not std::vector: a big program's groups hold millions of 160-byte moves (the model-D-like
// program of bench/backends.md: 5.2 M moves, 830 MB). A growing vector copies all of them at
// each doubling and leaves up to half its capacity unused, so it touches about three times the
// bytes it keeps; fresh memory is paid for in page faults and zeroing, which dominated `parse`
// (bench/gcode/README.md). Chunks are filled once and never copied: the first are small (a short
// program stays small), then they double up to kMaxChunk moves each.
//
// The interface is the part of std::vector the simulation uses: push_back, size, indexing,
// front/back, random-access iteration in program order, erase_if.
#pragma once

#include <bit>
#include <cstddef>
#include <iterator>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

#include "tridex/gcode/move.hpp"

namespace tridex::gcode {

class MoveList {
 public:
  // Chunk k holds kFirstChunk · 2^k moves up to kMaxChunk; every chunk after that kMaxChunk.
  static constexpr std::size_t kFirstChunk = 256;
  static constexpr std::size_t kMaxChunk = 65536;  // 10 MiB of moves: huge pages (huge_pages.hpp)

  template <bool Const>
  class Iterator;
  using value_type = Move;
  using size_type = std::size_t;
  using iterator = Iterator<false>;
  using const_iterator = Iterator<true>;

  MoveList() = default;
  MoveList(std::initializer_list<Move> moves) {
    for (const Move& m : moves) push_back(m);
  }
  MoveList(MoveList&&) noexcept = default;
  MoveList& operator=(MoveList&&) noexcept = default;
  MoveList(const MoveList& other) {
    for (const Move& m : other) push_back(m);
  }
  MoveList& operator=(const MoveList& other) {
    if (this != &other) {
      MoveList copy(other);
      *this = std::move(copy);
    }
    return *this;
  }

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

  void push_back(const Move& move) {
    if (size_ == capacity_) {
      const std::size_t chunk = chunk_size(chunks_.size());
      // Raw storage, constructed move by move: a chunk's pages are first written by its moves.
      chunks_.emplace_back(static_cast<Move*>(::operator new(chunk * sizeof(Move))));
      capacity_ += chunk;
    }
    const Place p = place(size_);
    std::construct_at(chunks_[p.chunk].get() + p.offset, move);
    ++size_;
  }

  Move& operator[](std::size_t i) {
    const Place p = place(i);
    return chunks_[p.chunk].get()[p.offset];
  }
  const Move& operator[](std::size_t i) const {
    const Place p = place(i);
    return chunks_[p.chunk].get()[p.offset];
  }
  Move& front() { return (*this)[0]; }
  const Move& front() const { return (*this)[0]; }
  Move& back() { return (*this)[size_ - 1]; }
  const Move& back() const { return (*this)[size_ - 1]; }

  void clear() {
    chunks_.clear();
    size_ = capacity_ = 0;
  }

  iterator begin() { return iterator(this, 0); }
  iterator end() { return iterator(this, size_); }
  const_iterator begin() const { return const_iterator(this, 0); }
  const_iterator end() const { return const_iterator(this, size_); }

  // Removes the moves `remove` holds true for, keeping the others' order, in place (as
  // std::erase_if on a vector); returns how many it removed.
  template <class Predicate>
  friend std::size_t erase_if(MoveList& list, Predicate remove) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < list.size_; ++i)
      if (!remove(list[i])) {
        if (kept != i) list[kept] = list[i];
        ++kept;
      }
    const std::size_t removed = list.size_ - kept;
    list.size_ = kept;
    return removed;
  }

  // Random access in program order. Stepping walks a pointer inside the current chunk; a jump
  // finds the chunk from the index.
  template <bool Const>
  class Iterator {
   public:
    using List = std::conditional_t<Const, const MoveList, MoveList>;
    using iterator_category = std::random_access_iterator_tag;
    using value_type = Move;
    using difference_type = std::ptrdiff_t;
    using pointer = std::conditional_t<Const, const Move*, Move*>;
    using reference = std::conditional_t<Const, const Move&, Move&>;

    Iterator() = default;
    Iterator(List* list, std::size_t index) : list_(list) { seek(index); }
    operator Iterator<true>() const requires(!Const) { return Iterator<true>(list_, index_); }

    reference operator*() const { return *at_; }
    pointer operator->() const { return at_; }
    reference operator[](difference_type n) const { return *(*this + n); }

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
      if (index >= list_->size_) return;  // end(): nothing to point at
      const Place p = place(index);
      at_ = list_->chunks_[p.chunk].get() + p.offset;
      chunk_end_ = list_->chunks_[p.chunk].get() + chunk_size(p.chunk);
    }

    List* list_ = nullptr;
    std::size_t index_ = 0;
    pointer at_ = nullptr;
    pointer chunk_end_ = nullptr;
  };

 private:
  struct Place {
    std::size_t chunk, offset;
  };

  // The doubling chunks hold kFirstChunk · (2^k − 1) moves before chunk k.
  static constexpr std::size_t kDoublingChunks = std::bit_width(kMaxChunk / kFirstChunk);  // 9
  static constexpr std::size_t kDoublingMoves =
      kFirstChunk * ((std::size_t{1} << kDoublingChunks) - 1);

  static constexpr std::size_t chunk_size(std::size_t chunk) {
    return chunk < kDoublingChunks ? kFirstChunk << chunk : kMaxChunk;
  }
  static Place place(std::size_t i) {
    if (i < kDoublingMoves) {
      // i / kFirstChunk + 1 lies in [2^k, 2^(k+1)) for the moves of chunk k.
      const std::size_t chunk = static_cast<std::size_t>(std::bit_width(i / kFirstChunk + 1)) - 1;
      return {chunk, i - kFirstChunk * ((std::size_t{1} << chunk) - 1)};
    }
    const std::size_t past = i - kDoublingMoves;
    return {kDoublingChunks + past / kMaxChunk, past % kMaxChunk};
  }

  static_assert(std::is_trivially_destructible_v<Move> && std::is_trivially_copyable_v<Move>,
                "chunks are freed without destroying their moves");
  struct FreeChunk {
    void operator()(Move* chunk) const { ::operator delete(chunk); }
  };

  std::vector<std::unique_ptr<Move, FreeChunk>> chunks_;
  std::size_t size_ = 0;
  std::size_t capacity_ = 0;
};

}  // namespace tridex::gcode
