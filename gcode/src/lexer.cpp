// tridex::gcode — the lexer (RS274/NGC word syntax, NIST IR 6556 §3.3, without parameters and
// expressions; Fanuc's block delete and '%' delimiters).
#include "tridex/gcode/lexer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <fast_float/fast_float.h>

namespace tridex::gcode {
namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }

std::string describe(char c) {
  unsigned char u = static_cast<unsigned char>(c);
  char text[32];
  if (u >= 0x21 && u < 0x7f)
    std::snprintf(text, sizeof text, "'%c'", c);
  else
    std::snprintf(text, sizeof text, "byte 0x%02X", u);
  return text;
}

bool fail(LexError& error, std::size_t index, std::string message) {
  error.column = static_cast<int>(index) + 1;
  error.message = std::move(message);
  return false;
}

}  // namespace

bool lex_line(std::string_view line, Block& block, LexError& error) {
  block.clear();
  const char* text = line.data();
  const std::size_t n = line.size();
  std::size_t i = 0;
  bool first = true;  // nothing but spaces seen yet
  while (i < n) {
    char c = text[i];
    if (is_space(c)) {
      ++i;
      continue;
    }
    if (c == '(') {
      std::size_t open = i;
      while (i < n && text[i] != ')') ++i;
      if (i == n) return fail(error, open, "comment '(' is not closed on this line");
      ++i;
      continue;
    }
    if (c == ';') break;
    if (c == '/') {
      if (!first || block.block_delete)
        return fail(error, i, "'/' (block delete) is only allowed at the start of a block");
      block.block_delete = true;
      ++i;
      continue;
    }
    if (c == '%') {
      if (!first) return fail(error, i, "'%' must be alone on its line");
      std::size_t j = i + 1;
      while (j < n && is_space(text[j])) ++j;
      if (j < n && text[j] != '(' && text[j] != ';')
        return fail(error, j, "'%' must be alone on its line");
      block.percent = true;
      return true;  // anything after it is a comment
    }
    char letter = c;
    if (letter >= 'a' && letter <= 'z') letter = static_cast<char>(letter - 'a' + 'A');
    if (letter < 'A' || letter > 'Z') {
      if (c == '#' || c == '[' || c == ']' || c == '=')
        return fail(error, i, describe(c) + ": parameters and expressions are not supported");
      return fail(error, i, "unexpected " + describe(c));
    }
    first = false;
    std::size_t start = i++;
    while (i < n && is_space(text[i])) ++i;
    bool negative = false;
    if (i < n && (text[i] == '+' || text[i] == '-')) {
      negative = text[i] == '-';
      ++i;
      while (i < n && is_space(text[i])) ++i;
    }
    std::size_t number = i;
    std::size_t digits = 0, points = 0;
    while (i < n && (is_digit(text[i]) || text[i] == '.')) {
      if (text[i] == '.')
        ++points;
      else
        ++digits;
      ++i;
    }
    if (digits == 0) {
      if (i < n && (text[i] == '#' || text[i] == '['))
        return fail(error, i, std::string("word ") + letter +
                                  ": parameters and expressions are not supported");
      return fail(error, start, std::string("word ") + letter + " has no number");
    }
    if (points > 1) return fail(error, number, std::string("word ") + letter + ": malformed number");
    double value = 0;
    auto result = fast_float::from_chars(text + number, text + i, value,
                                         fast_float::chars_format::fixed);
    if (result.ptr != text + i)
      return fail(error, number, std::string("word ") + letter + ": malformed number");
    if (result.ec != std::errc() || !std::isfinite(value) || value > kMaxWordValue)
      return fail(error, number,
                  std::string("word ") + letter + ": number out of range (limit 1e9) '" +
                      std::string(text + number, std::min<std::size_t>(i - number, 24)) + "'");
    block.words.push_back(Word{letter, negative ? -value : value, static_cast<int>(start) + 1});
  }
  return true;
}

}  // namespace tridex::gcode
