#include <doctest/doctest.h>

#include <random>
#include <string>

#include "tridex/gcode/lexer.hpp"

using namespace tridex::gcode;

namespace {
Block lex(const std::string& text) {
  Block block;
  LexError error;
  bool ok = lex_line(text, block, error);
  INFO(text << " -> " << error.message);
  REQUIRE(ok);
  return block;
}
LexError lex_error(const std::string& text) {
  Block block;
  LexError error;
  CHECK_MESSAGE(!lex_line(text, block, error), text);
  return error;
}
}  // namespace

TEST_CASE("lexer: words without spaces, lower case, signs, points") {
  Block b = lex("g1X10.y-2.5 z+.5F300");
  REQUIRE(b.words.size() == 5);
  CHECK(b.words[0].letter == 'G');
  CHECK(b.words[0].value == 1);
  CHECK(b.words[1].letter == 'X');
  CHECK(b.words[1].value == 10);
  CHECK(b.words[1].column == 3);
  CHECK(b.words[2].letter == 'Y');
  CHECK(b.words[2].value == -2.5);
  CHECK(b.words[3].value == 0.5);
  CHECK(b.words[4].value == 300);
  CHECK(lex("G53.1").words[0].value == doctest::Approx(53.1));
  CHECK(lex("X - 3").words[0].value == -3);
  // No exponents: "1e3" is X1 followed by an E word, which the interpreter then rejects.
  Block e = lex("X1e3");
  REQUIRE(e.words.size() == 2);
  CHECK(e.words[0].value == 1);
  CHECK(e.words[1].letter == 'E');
}

TEST_CASE("lexer: comments, sequence numbers, block delete, percent") {
  Block b = lex("N10 G0 (move up) ; trailing X1");
  REQUIRE(b.words.size() == 2);
  CHECK(b.words[0].letter == 'N');
  CHECK(b.words[1].letter == 'G');
  b = lex("(only a comment)");
  CHECK(b.words.empty());
  b = lex("/G1 X2");
  CHECK(b.block_delete);
  CHECK(b.words.size() == 2);
  b = lex("  %  (tape)");
  CHECK(b.percent);
  CHECK(lex("").words.empty());
  CHECK(lex("G1 X1\r").words.size() == 2);
}

TEST_CASE("lexer: malformed lines name the column") {
  CHECK(lex_error("G1 X1 (open").column == 7);
  CHECK(lex_error("G1 X").column == 4);
  CHECK(lex_error("G1 X1.2.3").column == 5);
  CHECK(lex_error("G1 X#1").message.find("parameters") != std::string::npos);
  CHECK(lex_error("G1 X[1+2]").column == 5);
  CHECK(lex_error("G1 X1 %").column == 7);
  CHECK(lex_error("G1 /X1").column == 4);
  CHECK(lex_error(std::string("G1 \x01")).message.find("0x01") != std::string::npos);
  CHECK(lex_error("X" + std::string(400, '9')).message.find("out of range") != std::string::npos);
  CHECK(lex_error("X1000000000.5").message.find("out of range") != std::string::npos);
  CHECK(lex_error("G1 X=1").column == 4);
  CHECK(lex_error("G1 Xnan").column == 4);
}

TEST_CASE("lexer: random numbers round-trip through text") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> value(-1e6, 1e6);
  for (int i = 0; i < 2000; ++i) {
    double v = value(rng);
    char text[64];
    std::snprintf(text, sizeof text, "X%.6f", v);
    Block b = lex(text);
    REQUIRE(b.words.size() == 1);
    CHECK(b.words[0].value == std::strtod(text + 1, nullptr));
  }
}

TEST_CASE("lexer: random bytes never crash, and every word it returns is sane") {
  std::mt19937_64 rng(11);
  const std::string alphabet = "GXYZIJKRFgxyz0123456789.-+ ()%;/#\t\x01\xff";
  Block block;
  LexError error;
  for (int i = 0; i < 20000; ++i) {
    std::string line(rng() % 40, ' ');
    for (char& c : line) c = alphabet[rng() % alphabet.size()];
    if (lex_line(line, block, error)) {
      for (const Word& w : block.words) {
        CHECK((w.letter >= 'A' && w.letter <= 'Z'));
        CHECK(std::abs(w.value) <= kMaxWordValue);
        CHECK(w.column >= 1);
        CHECK(w.column <= static_cast<int>(line.size()));
      }
    } else {
      CHECK(error.column >= 1);
      CHECK(error.column <= static_cast<int>(line.size()) + 1);
      CHECK(!error.message.empty());
    }
  }
}
