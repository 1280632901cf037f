// libFuzzer harness over the G-code lexer, interpreter and grouping (clang
// -fsanitize=fuzzer,address,undefined; see run.sh). Any input must either run to the end or
// throw tridex::Error; moves must be finite with a unit spindle direction. Every crash it finds
// becomes a named case in tests/gcode/test_bad_input.cpp.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>
#include <string_view>

#include "tridex/gcode/grouping.hpp"
#include "tridex/gcode/interpreter.hpp"
#include "tridex/gcode/lexer.hpp"

using namespace tridex;
using namespace tridex::gcode;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);

  Block block;
  LexError error;
  std::string_view rest(text);
  while (!rest.empty()) {
    std::size_t newline = rest.find('\n');
    std::string_view line = rest.substr(0, newline);
    if (lex_line(line, block, error)) {
      for (const Word& w : block.words)
        if (!std::isfinite(w.value) || std::abs(w.value) > kMaxWordValue) std::abort();
    } else if (error.column < 1 || error.column > static_cast<int>(line.size()) + 1) {
      std::abort();
    }
    rest = newline == std::string_view::npos ? std::string_view() : rest.substr(newline + 1);
  }

  // Fanuc and Haas strict (they read the offset registers #2001… differently), LinuxCNC lenient.
  for (Dialect dialect : {Dialect::fanuc, Dialect::haas, Dialect::linuxcnc}) {
    const bool lenient = dialect == Dialect::linuxcnc;
    InterpreterOptions options;
    options.lenient = lenient;
    options.arc_tolerance = 0.01;  // keeps huge arcs cheap
    options.max_blocks = 20000;    // keeps M98 L loops bounded
    MachineConfig machine;         // no subprogram folders: calls stay inside the input
    machine.dialect = dialect;
    Interpreter interpreter(options, machine);
    DirectionGrouper grouper;
    std::istringstream in(text);
    long long moves = 0;
    try {
      interpreter.run(in, "fuzz", [&](const Move& m) {
        if (!is_finite(m.start) || !is_finite(m.end) || !std::isfinite(m.feed) ||
            std::abs(glm::length(m.axis) - 1) > 1e-9)
          std::abort();
        if (++moves < 5000) grouper.add(m);
      });
    } catch (const tridex::Error&) {
    }
  }
  return 0;
}
