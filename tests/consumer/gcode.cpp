// A program outside the project that uses the installed G-code library: a program fed in two
// pieces, the feed rate set in the first used in the second.
#include <cstdio>
#include <sstream>
#include <vector>

#include <tridex/gcode/interpreter.hpp>

int main() {
  tridex::gcode::Interpreter interpreter;
  std::vector<tridex::gcode::Move> moves;
  auto sink = [&](const tridex::gcode::Move& m) { moves.push_back(m); };
  std::istringstream first("G21 G90 T1 M6\nG0 X0 Y0 Z5\nF300\n"), second("G1 Z-1\nM30\n");
  interpreter.feed(first, "consumer.nc", sink);
  interpreter.feed(second, "consumer.nc", sink);
  interpreter.finish("consumer.nc", sink);
  std::printf("%zu moves, the last at %g mm/min\n", moves.size(), moves.back().feed);
  return moves.size() == 2 && moves.back().feed == 300 ? 0 : 1;
}
