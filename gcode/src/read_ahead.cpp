// tridex::gcode — the read-ahead task (read_ahead.hpp).
#include "read_ahead.hpp"

#include <cstring>
#include <optional>
#include <utility>

namespace tridex::gcode {
namespace {

// Notes whether lexing asked for anything beyond the line's text; the answers are never used.
class ReadAheadProbe final : public ParameterReader {
 public:
  Value numbered(int) override {
    asked = true;
    return Value{};
  }
  std::optional<Value> named(std::string_view) override {
    asked = true;
    return Value{};
  }
  bool vacant_words_omitted() const override {
    asked = true;
    return true;
  }
  mutable bool asked = false;
};

// A block that is words and the block-delete and '%' marks only: no setting, no statement or
// o-word (not even a column left by a statement that did nothing), no program name.
bool read_ahead_plain(const Block& block) {
  return block.assignments.empty() && block.control.kind == ControlKind::none &&
         block.control.column == 0 && block.program_name.empty() &&
         block.program_name_column == 0 && block.vacant_words.empty();
}

}  // namespace

ReadAhead::ReadAhead(std::istream& in, std::uint64_t start, bool first_line)
    : in_(in), offset_(start), first_line_(first_line) {
  task_.start([this, start] { produce_from(start); });
}

ReadAhead::~ReadAhead() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  try {
    task_.join();
  } catch (...) {  // produce_from() keeps its own failures: nothing comes back here
  }
}

void ReadAhead::produce_from(std::uint64_t at) {
  try {
    std::string rest;  // the start of a line the next chunk ends
    bool more = true;
    while (more) {
      std::unique_ptr<Chunk> chunk = spare();
      if (!chunk) break;  // stopping
      chunk->text = rest;
      const std::size_t kept = chunk->text.size();
      chunk->text.resize(kept + kChunkBytes);
      in_.read(chunk->text.data() + kept, static_cast<std::streamsize>(kChunkBytes));
      chunk->text.resize(kept + static_cast<std::size_t>(in_.gcount()));
      const bool eof = !in_;
      more = lex_chunk(*chunk, rest, at, eof);
      if (!hand_over(std::move(chunk))) break;
    }
  } catch (...) {
    // Whatever failed (memory), the interpreter's own reader goes on after the last line handed
    // over, and meets the same trouble where it is its own.
  }
  {
    std::lock_guard lock(mutex_);
    finished_ = true;
  }
  changed_.notify_all();
}

bool ReadAhead::lex_chunk(Chunk& chunk, std::string& rest, std::uint64_t& at, bool eof) {
  ReadAheadProbe probe;
  Block block;
  LexError error;
  const char* base = chunk.text.data();
  const std::size_t size = chunk.text.size();
  std::size_t pos = 0;
  while (pos < size) {
    const void* newline = std::memchr(base + pos, '\n', size - pos);
    if (!newline && !eof) {  // an unfinished line: the next chunk starts with it
      rest.assign(base + pos, size - pos);
      chunk.text.resize(pos);
      return rest.size() < kLongLine;  // else LineReader's "line longer than" at that line
    }
    const std::size_t length =
        newline ? static_cast<std::size_t>(static_cast<const char*>(newline) - (base + pos))
                : size - pos;
    if (length >= kLongLine) return false;  // LineReader's to read (and refuse)
    Line line;
    line.begin = static_cast<std::uint32_t>(pos);
    line.length = static_cast<std::uint32_t>(length);
    line.end = at + length + (newline ? 1 : 0);
    std::string_view text(base + pos, length);
    if (first_line_) {
      first_line_ = false;
      if (text.substr(0, 3) == "\xEF\xBB\xBF") {  // UTF-8 BOM, as ProgramFlow::read drops it
        text.remove_prefix(3);
        line.begin += 3;
        line.length -= 3;
      }
    }
    probe.asked = false;
    if (lex_line(text, block, error, &probe) && !probe.asked && read_ahead_plain(block)) {
      line.lexed = true;
      line.block_delete = block.block_delete;
      line.percent = block.percent;
      line.first_word = static_cast<std::uint32_t>(chunk.words.size());
      line.words = static_cast<std::uint32_t>(block.words.size());
      chunk.words.insert(chunk.words.end(), block.words.begin(), block.words.end());
    }
    chunk.lines.push_back(line);
    at = line.end;
    pos += length + (newline ? 1 : 0);
  }
  rest.clear();
  return !eof;
}

std::unique_ptr<ReadAhead::Chunk> ReadAhead::spare() {
  std::lock_guard lock(mutex_);
  if (stopping_) return nullptr;
  if (spares_.empty()) return std::make_unique<Chunk>();
  std::unique_ptr<Chunk> chunk = std::move(spares_.back());
  spares_.pop_back();
  chunk->lines.clear();
  chunk->words.clear();
  return chunk;
}

bool ReadAhead::hand_over(std::unique_ptr<Chunk> chunk) {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return ready_.size() < kChunks || stopping_; });
  if (stopping_) return false;
  ready_.push_back(std::move(chunk));
  changed_.notify_all();
  return true;
}

bool ReadAhead::next(std::string_view& text, const Line*& line) {
  for (;;) {
    if (current_ && index_ < current_->lines.size()) {
      line = &current_->lines[index_++];
      text = std::string_view(current_->text.data() + line->begin, line->length);
      offset_ = line->end;
      return true;
    }
    if (done_) return false;
    std::unique_lock lock(mutex_);
    if (current_) {
      spares_.push_back(std::move(current_));
      changed_.notify_all();
    }
    changed_.wait(lock, [&] { return !ready_.empty() || finished_; });
    if (ready_.empty()) {
      done_ = true;
      return false;
    }
    current_ = std::move(ready_.front());
    ready_.pop_front();
    index_ = 0;
    changed_.notify_all();
  }
}

void ReadAhead::fill(const Line& line, Block& block) const {
  block.clear();
  const Word* first = current_->words.data() + line.first_word;
  block.words.assign(first, first + line.words);
  block.block_delete = line.block_delete;
  block.percent = line.percent;
}

}  // namespace tridex::gcode
