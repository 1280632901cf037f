// tridex::gcode — reading and lexing a program's lines on a second thread while the interpreter
// runs the blocks before them (InterpreterOptions::read_ahead).
//
// Why: on a big plain program (millions of `G1 X.. Y.. Z..` blocks) splitting lines and reading
// numbers costs about as much as interpreting them, and only the interpreting depends on what came
// before. The task reads the file from where the program starts, in chunks, and lexes each line
// with a ParameterReader that only notes that it was asked: a line whose lexing asked nothing (no
// parameter, no vacant word rule) lexed as a pure function of its text, so its words are what the
// interpreter's own lex_line would make of them. Every other line (parameters, expressions,
// settings, control statements, program names, lexing errors) comes with its text only and is
// lexed again by the interpreter as before, with the interpreter's parameters and messages.
//
// The interpreter takes lines in order and nothing else: the first jump (M98, GOTO, a loop, an
// o-word call, a look-ahead for a label) or a line too long for its LineReader ends the read-ahead
// and the LineReader goes on from where the last line taken ended (ProgramFlow::read, jump).
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <istream>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "tridex/gcode/lexer.hpp"
#include "tridex/parallel.hpp"

namespace tridex::gcode {

class ReadAhead {
 public:
  // One line of a chunk: its text in the chunk's text, and its words where it lexed purely.
  struct Line {
    std::uint64_t end = 0;  // the offset after the line and its '\n'
    std::uint32_t begin = 0, length = 0;
    std::uint32_t first_word = 0, words = 0;
    bool lexed = false;  // words, block_delete and percent are the whole Block
    bool block_delete = false, percent = false;
  };

  // Reads `in` from `start` (the stream's position, a seekable stream); `first_line`: whether
  // the first line read is the program's line 1 (its UTF-8 byte order mark is dropped).
  ReadAhead(std::istream& in, std::uint64_t start, bool first_line);
  ReadAhead(const ReadAhead&) = delete;
  ReadAhead& operator=(const ReadAhead&) = delete;
  ~ReadAhead();  // stops the task

  // The next line (valid until the next call); false when the task read no more: the end of the
  // input, a line of 65536 characters or more, or a failure of the task. The caller then goes on
  // with its own reader from offset().
  bool next(std::string_view& text, const Line*& line);
  // Where the line after the last one given starts.
  std::uint64_t offset() const { return offset_; }
  // `block` as lex_line would make it of a line that lexed purely.
  void fill(const Line& line, Block& block) const;

  static constexpr std::size_t kChunkBytes = 1 << 16;
  static constexpr std::size_t kChunks = 4;  // at most this many chunks read ahead
  static constexpr std::size_t kLongLine = 65536;

 private:
  struct Chunk {
    std::string text;
    std::vector<Line> lines;
    std::vector<Word> words;
  };

  void produce_from(std::uint64_t at);
  bool lex_chunk(Chunk& chunk, std::string& rest, std::uint64_t& at, bool eof);
  bool hand_over(std::unique_ptr<Chunk> chunk);
  std::unique_ptr<Chunk> spare();

  std::istream& in_;
  std::uint64_t offset_;  // the caller's (next)
  bool first_line_;       // the task's
  // The caller's side.
  std::unique_ptr<Chunk> current_;
  std::size_t index_ = 0;
  bool done_ = false;
  // Shared, under mutex_.
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::unique_ptr<Chunk>> ready_;
  std::vector<std::unique_ptr<Chunk>> spares_;
  bool stopping_ = false;
  bool finished_ = false;  // the task reads no more
  detail::BackgroundTask task_;
};

}  // namespace tridex::gcode
