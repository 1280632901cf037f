// tridex::gcode — reading a program line by line: a fixed buffer over the stream (constant
// memory, no per-line allocation) and byte offsets for jumps (M98, GOTO, loops, o-word calls).
#pragma once

#include <cstdint>
#include <cstring>
#include <istream>
#include <string_view>
#include <vector>

namespace tridex::gcode {

class LineReader {
 public:
  static constexpr std::size_t kCapacity = 1 << 16;

  explicit LineReader(std::istream& in) : in_(in), buffer_(kCapacity) {
    std::streamoff start = in_.tellg();
    seekable_ = start >= 0;
    base_ = seekable_ ? static_cast<std::uint64_t>(start) : 0;
  }

  // The next line without its '\n'; false at the end of the input; `too_long` when a line
  // does not fit the buffer.
  bool next(std::string_view& line, bool& too_long) {
    too_long = false;
    for (;;) {
      const char* start = buffer_.data() + pos_;
      std::size_t available = end_ - pos_;
      const void* newline = available ? std::memchr(start, '\n', available) : nullptr;
      if (newline) {
        std::size_t length = static_cast<std::size_t>(static_cast<const char*>(newline) - start);
        line = std::string_view(start, length);
        pos_ += length + 1;
        return true;
      }
      if (eof_) {
        if (available == 0) return false;
        line = std::string_view(start, available);
        pos_ = end_;
        return true;
      }
      if (available == kCapacity) {
        too_long = true;
        return true;
      }
      std::memmove(buffer_.data(), start, available);
      base_ += pos_;
      pos_ = 0;
      end_ = available;
      in_.read(buffer_.data() + end_, static_cast<std::streamsize>(kCapacity - end_));
      std::streamsize got = in_.gcount();
      end_ += static_cast<std::size_t>(got);
      if (!in_) eof_ = true;
    }
  }

  std::uint64_t offset() const { return base_ + pos_; }  // where the next line starts
  bool seekable() const { return seekable_; }

  // Reads from `offset` on after someone else read the stream (ReadAhead): nothing buffered is
  // kept. False when the stream cannot go there.
  bool restart(std::uint64_t offset) {
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(offset));
    if (!in_) return false;
    base_ = offset;
    pos_ = end_ = 0;
    eof_ = false;
    return true;
  }

  bool seek(std::uint64_t offset) {
    // A jump back into what the buffer holds (a loop's body) needs no I/O.
    if (offset >= base_ && offset <= base_ + end_) {
      pos_ = static_cast<std::size_t>(offset - base_);
      return true;
    }
    return seekable_ && restart(offset);
  }

 private:
  std::istream& in_;
  std::vector<char> buffer_;
  std::size_t pos_ = 0, end_ = 0;
  std::uint64_t base_ = 0;
  bool eof_ = false;
  bool seekable_ = false;
};

// `O1234` alone on its line (comments allowed): a program or subprogram label.
inline bool parse_label(std::string_view text, int& number) {
  std::size_t i = 0, n = text.size();
  while (i < n && (text[i] == ' ' || text[i] == '\t')) ++i;
  if (i == n || (text[i] != 'O' && text[i] != 'o')) return false;
  ++i;
  long long value = 0;
  std::size_t digits = 0;
  while (i < n && text[i] >= '0' && text[i] <= '9' && digits < 10) {
    value = value * 10 + (text[i] - '0');
    ++i;
    ++digits;
  }
  if (digits == 0 || value > 999'999'999) return false;
  // Only a comment may follow: `o100 sub`, `o100 call` and the like are LinuxCNC o-words, and a
  // numbered subroutine noted as program 100 could not be called before its definition.
  while (i < n && (text[i] == ' ' || text[i] == '\t' || text[i] == '\r')) ++i;
  if (i < n && text[i] != '(' && text[i] != ';') return false;
  number = static_cast<int>(value);
  return true;
}

}  // namespace tridex::gcode
