// tridex::gcode — splitting one block (line) of a program into words.
//
// A word is a letter and a number: `G1`, `X-2.5`, `g53.1`. Spaces between words are optional
// (`G1X10.Y-2.5F300`), letters may be lower case, `( )` and `;` comments are dropped, a leading
// `/` marks a block-delete block and a line holding only `%` is a tape delimiter. Numbers have an
// optional sign, digits and at most one point, no exponent (`1e3` is not a G-code number); they
// are parsed by fast_float. Parameters and expressions (`#1`, `[1+2]`) are rejected.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace tridex::gcode {

struct Word {
  char letter = 0;     // 'A'..'Z', upper case
  double value = 0;    // finite, |value| <= kMaxWordValue
  int column = 0;      // 1-based column of the letter
};

// Larger magnitudes are rejected as out of range: no coordinate, feed or code is near it, and it
// keeps every later computation far from overflow.
inline constexpr double kMaxWordValue = 1e9;

struct Block {
  std::vector<Word> words;
  bool block_delete = false;  // the block starts with '/'
  bool percent = false;       // the line is a '%' tape delimiter
  void clear() {
    words.clear();
    block_delete = false;
    percent = false;
  }
};

// Why a line could not be lexed; column is 1-based.
struct LexError {
  int column = 0;
  std::string message;
};

// Splits `line` (without its newline) into `block`, reusing its storage. Returns false and fills
// `error` when the line is malformed; `block` is then unspecified.
bool lex_line(std::string_view line, Block& block, LexError& error);

}  // namespace tridex::gcode
