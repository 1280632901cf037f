// Interpreter::feed (issue 38): a program fed in pieces gives run()'s moves, line numbers and
// warnings whatever the split; the state (modes, feed, tool, offsets, parameters) carries over;
// finish() ends the program; run() still starts fresh.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tridex/gcode/interpreter.hpp"

namespace test_interpreter_feed {

using namespace tridex;
using namespace tridex::gcode;

std::vector<std::string> example_lines() {
  std::ifstream in(std::filesystem::path(TRIDEX_SOURCE_DIR) / "gcode" / "examples" /
                   "mold_3plus2.nc");
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line + "\n");
  return lines;
}

bool same_move(const Move& a, const Move& b) {
  return a.start == b.start && a.end == b.end && a.axis == b.axis && a.tool == b.tool &&
         a.line == b.line && a.kind == b.kind && a.feed == b.feed && a.from_far == b.from_far;
}

std::vector<Move> fed(Interpreter& interpreter, const std::vector<std::string>& lines,
                      const std::vector<std::size_t>& cuts) {
  std::vector<Move> moves;
  auto sink = [&](const Move& m) { moves.push_back(m); };
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
    std::string text;
    for (std::size_t l = cuts[k]; l < cuts[k + 1]; ++l) text += lines[l];
    std::istringstream piece(text);
    interpreter.feed(piece, "mold.nc", sink);
  }
  interpreter.finish("mold.nc", sink);
  return moves;
}

TEST_CASE("feed: the example in pieces gives run()'s moves, for any split") {
  const std::vector<std::string> lines = example_lines();
  std::string all;
  for (const std::string& l : lines) all += l;
  std::istringstream whole(all);
  std::vector<Move> reference;
  Interpreter runner;
  runner.run(whole, "mold.nc", [&](const Move& m) { reference.push_back(m); });
  REQUIRE(reference.size() > 20000);
  const std::size_t n = lines.size();
  for (const std::vector<std::size_t>& cuts : {std::vector<std::size_t>{0, n},
                                               {0, 1, 2, 17, 373, 5000, 21936, 21937, n},
                                               {0, n / 3, n / 2, n - 1, n}}) {
    CAPTURE(cuts.size());
    Interpreter interpreter;
    const std::vector<Move> moves = fed(interpreter, lines, cuts);
    REQUIRE(moves.size() == reference.size());
    std::size_t differ = 0;
    for (std::size_t k = 0; k < moves.size(); ++k) differ += !same_move(moves[k], reference[k]);
    CHECK(differ == 0);
    CHECK(interpreter.warnings().size() == runner.warnings().size());
  }
}

TEST_CASE("feed: state carries over; the end, finish() and run() start afresh") {
  Interpreter interpreter;
  std::vector<Move> moves;
  auto sink = [&](const Move& m) { moves.push_back(m); };
  auto feed = [&](const std::string& text) {
    std::istringstream piece(text);
    interpreter.feed(piece, "p.nc", sink);
  };
  feed("G21 G90 T1 M6\nG0 X0 Y0 Z5\nF300 #1=2.5\n");
  feed("G91\nG1 Z-[#1]\n");  // the feed rate, G91 and #1 from the pieces before
  REQUIRE(moves.size() == 2);
  CHECK(moves.back().end.z == doctest::Approx(2.5));
  CHECK(moves.back().feed == doctest::Approx(300));
  CHECK(moves.back().line == 5);  // lines run on across pieces
  // A piece that ends inside a loop is refused (a loop stays within one piece).
  std::istringstream loop("o1 while [1 LT 2]\nG1 X1\n");
  CHECK_THROWS_AS(interpreter.clone().feed(loop, "p.nc", sink), GcodeError);
  // The end: text after M30 is not run, with one warning.
  feed("M30\n");
  const std::size_t before = moves.size();
  feed("G1 X10\n");
  CHECK(moves.size() == before);
  CHECK(interpreter.warnings().back().message.find("after the end") != std::string::npos);
  interpreter.finish("p.nc", sink);
  // The next feed starts a fresh machine: no feed rate is set.
  feed("G21 G90 T1 M6\nG0 X0 Y0 Z5\n");
  std::istringstream no_feed("G1 Z0\n");
  CHECK_THROWS_AS(interpreter.feed(no_feed, "p.nc", sink), GcodeError);
}

}  // namespace test_interpreter_feed
