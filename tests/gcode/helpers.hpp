// Shared helpers of the G-code suite: run a program held in a string.
#pragma once

#include <doctest/doctest.h>

#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "tridex/gcode/interpreter.hpp"

namespace tridex::gcode::test {

struct Result {
  std::vector<Move> moves;
  std::vector<Diagnostic> warnings;
  std::set<int> tools;
  std::map<int, int> tool_lines;
};

inline Result run_program(const std::string& text, InterpreterOptions options = {},
                          MachineConfig machine = {}) {
  std::istringstream in(text);
  Interpreter interpreter(options, machine);
  Result result;
  interpreter.run(in, "test.nc", [&](const Move& m) { result.moves.push_back(m); });
  result.warnings = interpreter.warnings();
  result.tools = interpreter.tools_used();
  result.tool_lines = interpreter.tool_first_line();
  return result;
}

// The diagnostic of a program that must be rejected.
inline Diagnostic error_of(const std::string& text, InterpreterOptions options = {},
                           MachineConfig machine = {}) {
  try {
    run_program(text, options, machine);
  } catch (const GcodeError& e) {
    return e.where;
  }
  FAIL("program was accepted: " << text);
  return {};
}

// A machine that starts at the origin and changes tools in place (as rs274 standalone does).
inline MachineConfig at_origin(MachineConfig machine = {}) {
  machine.start_position = Vec3(0.0);
  machine.tool_change = ToolChange::in_place;
  return machine;
}

inline bool near(const Vec3& a, const Vec3& b, double eps = 1e-9) {
  return glm::length(a - b) <= eps;
}

// Concatenation through a stream (GCC 12 warns falsely on "literal" + std::string chains).
template <class... Parts>
std::string cat(const Parts&... parts) {
  std::ostringstream out;
  (out << ... << parts);
  return out.str();
}

inline std::string fmt(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.4f", v);
  return text;
}

}  // namespace tridex::gcode::test
