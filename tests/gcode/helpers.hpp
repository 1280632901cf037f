// Shared helpers of the G-code suite: run a program held in a string.
#pragma once

#include <cmath>
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

// The message of the tridex::Error that `f` must throw.
std::string message_of(auto&& f) {
  try {
    f();
  } catch (const tridex::Error& e) {
    return e.what();
  }
  FAIL("no error");
  return {};
}

// A machine that starts at the origin and changes tools in place (as rs274 standalone does).
inline MachineConfig at_origin(MachineConfig machine = {}) {
  machine.start_position = Vec3(0.0);
  machine.tool_change = ToolChange::in_place;
  return machine;
}

// The LinuxCNC dialect on such a machine.
inline MachineConfig linuxcnc_at_origin() {
  MachineConfig machine = at_origin();
  machine.dialect = Dialect::linuxcnc;
  return machine;
}

// Rotation by `degrees` about a unit axis (Rodrigues): a reference independent of the library's
// rotation helpers.
inline Mat3 about(const Vec3& k, double degrees) {
  double t = degrees * std::acos(-1.0) / 180, c = std::cos(t), s = std::sin(t);
  Mat3 m;
  for (int col = 0; col < 3; ++col) {
    Vec3 e(0.0);
    e[col] = 1;
    m[col] = e * c + glm::cross(k, e) * s + k * glm::dot(k, e) * (1 - c);
  }
  return m;
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
