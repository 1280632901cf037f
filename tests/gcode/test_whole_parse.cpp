// The plain-program fast paths against the general ones: the lexer's one-pass number reading
// against a correctly rounded conversion (strtod), digit for digit.
#include <doctest/doctest.h>

#include <cstdlib>
#include <random>
#include <string>

#include "tridex/gcode/lexer.hpp"

namespace test_whole_parse {

using namespace tridex::gcode;

// A random decimal of 1 to 18 digits with the point anywhere (or none), leading zeros included.
std::string random_decimal(std::mt19937_64& random) {
  std::uniform_int_distribution<int> length(1, 18), digit(0, 9);
  const int digits = length(random);
  std::uniform_int_distribution<int> point(-1, digits);
  const int at = point(random);
  std::string text;
  for (int k = 0; k < digits; ++k) {
    if (k == at) text += '.';
    text += static_cast<char>('0' + digit(random));
  }
  if (at == digits) text += '.';
  return text;
}

TEST_CASE("fast parse: word values equal the correctly rounded decimal, bit for bit") {
  std::mt19937_64 random(37);
  Block block;
  LexError error;
  int read = 0;
  for (int i = 0; i < 100000; ++i) {
    const std::string number = random_decimal(random);
    const bool ok = lex_line("X-" + number + " Y" + number, block, error);
    const double expected = std::strtod(number.c_str(), nullptr);
    if (expected > kMaxWordValue) {  // refused as out of range, whichever path read it
      CHECK_MESSAGE(!ok, number);
      continue;
    }
    REQUIRE_MESSAGE(ok, number << ": " << error.message);
    REQUIRE(block.words.size() == 2);
    CHECK_MESSAGE(block.words[1].value == expected, number);
    CHECK_MESSAGE(block.words[0].value == -expected, number);
    ++read;
  }
  CHECK(read > 50000);
  // Exact halfway and near-halfway cases, 15 and 16 digits, and malformed numbers.
  for (const std::string number :
       {"0.1", "0.3", "123456789.012345", "999999999.999999", "1000000000", "1000000000.",
        "0.000000000000001", "900719925.4740993", "0.30000000000000004", "1.0000000000000002"}) {
    REQUIRE_MESSAGE(lex_line("Z" + number, block, error), number);
    CHECK_MESSAGE(block.words[0].value == std::strtod(number.c_str(), nullptr), number);
  }
  CHECK(!lex_line("X1.2.3", block, error));
  CHECK(error.message == "word X: malformed number");
  CHECK(error.column == 2);
  CHECK(!lex_line("X1000000000.5", block, error));
  CHECK(error.message.find("out of range") != std::string::npos);
}

}  // namespace test_whole_parse
