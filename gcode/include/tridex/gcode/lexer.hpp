// tridex::gcode — splitting one block (line) of a program into words, parameter settings and a
// control statement, evaluating its expressions.
//
// A word is a letter and a value: `G1`, `X-2.5`, `g53.1`, `X#1`, `Y-[#2 * 2]`, `Z SIN[30]`.
// Spaces between words are optional (`G1X10.Y-2.5F300`), letters may be lower case, `( )` and
// `;` comments are dropped, a leading `/` marks a block-delete block, a line holding only `%` is a
// tape delimiter and `:1234` is a Fanuc ISO program number (read as `O1234`). A line holding only
// a program name that is not a number (`O7997A`, `OCIRCLE`, Fanuc's `<NAME>`) is read as a name
// (Block::program_name); the interpreter says where one may stand. Numbers have an
// optional sign, digits and at most one point, no exponent (`1e3` is not a G-code number); they
// are parsed by fast_float.
//
// With a ParameterReader, the macro languages of the two dialects users meet are read too:
// - parameters `#1`, `##1`, `#[#1+1]`, LinuxCNC's `#<name>` (local) and `#<_name>` (global);
// - expressions in `[ ]` with `**`, `* / MOD`, `+ -`, `EQ NE GT GE LT LE`, `AND OR XOR` (in that
//   order of precedence, LinuxCNC's; Fanuc programs bracket their conditions, so they read the
//   same) and the functions ABS ACOS ASIN ATAN COS EXP FIX FUP LN ROUND SIN SQRT TAN (degrees),
//   `ATAN[y]/[x]` and EXISTS[#<name>];
// - settings `#1 = expr` (Fanuc's right-hand side needs no brackets), applied after the block's
//   words are read (RS274/NGC §3.3.2);
// - Fanuc Macro B statements `IF [c] GOTO n`, `IF [c] THEN #i = e`, `GOTO n`, `WHILE [c] DO m`,
//   `DO m`, `END m`, evaluated here into a Control the interpreter carries out;
// - LinuxCNC o-words `o100 if [c]`, `o<name> call [a] [b]`, … as a Control whose arguments the
//   interpreter evaluates when (and only if) the branch runs.
// Fanuc's vacant value (`#0`, a local never set) is 0 in arithmetic, distinct from 0 in EQ/NE,
// and a word whose value is vacant is left out of the block (Fanuc) or reads 0 (LinuxCNC),
// as the ParameterReader says.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tridex::gcode {

struct Word {
  char letter = 0;   // 'A'..'Z' upper case, or LinuxCNC's polar '@' and '^'
  double value = 0;  // finite, |value| <= kMaxWordValue
  int column = 0;    // 1-based column of the letter
};

// Larger magnitudes are rejected as out of range: no coordinate, feed or code is near it, and it
// keeps every later computation far from overflow.
inline constexpr double kMaxWordValue = 1e9;

// A parameter's value; `vacant` is Fanuc's null (#0, or a local never set).
struct Value {
  double number = 0;
  bool vacant = false;
};

// Where expressions read parameters. The interpreter implements it over its parameter store and
// its modal state (system variables).
class ParameterReader {
 public:
  virtual ~ParameterReader() = default;
  // #n, n in [0, 999999]; may throw tridex::Error for a variable that cannot be read.
  virtual Value numbered(int n) = 0;
  // #<name>, the name lower case without spaces; nullopt when it is not defined.
  virtual std::optional<Value> named(std::string_view name) = 0;
  // Fanuc leaves a word whose value is vacant out of the block; LinuxCNC reads it as 0.
  virtual bool vacant_words_omitted() const = 0;
};

// `#n = value` (number >= 0) or `#<name> = value` (number < 0).
struct Assignment {
  int number = -1;
  std::string name;
  Value value;
  int column = 0;
};

// LinuxCNC o-word keywords.
enum class OKeyword : std::uint8_t {
  sub,
  endsub,
  call,
  if_,
  elseif,
  else_,
  endif,
  while_,
  endwhile,
  do_,
  repeat,
  endrepeat,
  break_,
  continue_,
  return_
};
const char* to_string(OKeyword keyword);

enum class ControlKind : std::uint8_t {
  none,
  jump,        // Fanuc GOTO n (or IF [true] GOTO n): continue at the block numbered N n
  while_loop,  // Fanuc WHILE [c] DO m (condition evaluated) or DO m (condition true)
  end_loop,    // Fanuc END m
  o_word,      // LinuxCNC o-word: label, keyword, unevaluated arguments
};

struct Control {
  ControlKind kind = ControlKind::none;
  int column = 0;         // 1-based column of the statement
  long long number = 0;   // jump: target N; while_loop / end_loop: the loop's m
  bool condition = true;  // while_loop
  std::string label;      // o_word: "100" or the name, lower case
  OKeyword keyword = OKeyword::sub;
  std::string_view arguments;  // o_word: the text after the keyword (a view into the line)
  int arguments_column = 0;
};

struct Block {
  std::vector<Word> words;
  std::vector<Assignment> assignments;
  Control control;
  bool block_delete = false;  // the block starts with '/'
  bool percent = false;       // the line is a '%' tape delimiter
  // A program name alone on its line (Fanuc's `O7997A`, `OCIRCLE`, `<NAME>`): as written.
  std::string program_name;
  int program_name_column = 0;
  // Fanuc: words left out because their value was vacant, as written ("F#650"), for messages.
  std::vector<std::string> vacant_words;
  void clear() {
    words.clear();
    vacant_words.clear();
    assignments.clear();
    control = Control{};
    block_delete = false;
    percent = false;
    program_name.clear();
    program_name_column = 0;
  }
};

// Why a line could not be lexed; column is 1-based.
struct LexError {
  int column = 0;
  std::string message;
};

// Splits `line` (without its newline) into `block`, reusing its storage. Returns false and fills
// `error` when the line is malformed or an expression fails (division by zero, an undefined
// parameter, unbalanced brackets, …); `block` is then unspecified. Without a ParameterReader,
// parameters and expressions are errors.
bool lex_line(std::string_view line, Block& block, LexError& error,
              ParameterReader* parameters = nullptr);

// Evaluates the bracketed expressions of an o-word's arguments (`[1] [#2*3]`), or a condition's
// single one; `column` is the 1-based column where `text` starts in its line.
bool evaluate_arguments(std::string_view text, int column, ParameterReader& parameters,
                        std::vector<Value>& values, LexError& error);

// What a line means for control flow, read without evaluating anything (for skipping over
// branches, loop bodies and subroutine definitions, and for finding GOTO targets).
struct Skim {
  long long sequence = -1;               // its N number, if it starts with one
  ControlKind kind = ControlKind::none;  // o_word, while_loop (WHILE/DO) or end_loop (END)
  long long number = 0;                  // while_loop / end_loop: m
  std::string label;                     // o_word
  OKeyword keyword = OKeyword::sub;
};
void skim_line(std::string_view line, Skim& skim);

}  // namespace tridex::gcode
