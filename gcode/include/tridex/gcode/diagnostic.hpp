// tridex::gcode — where a problem is in a program, and the errors that carry it.
#pragma once

#include <string>
#include <utility>

#include "tridex/error.hpp"

namespace tridex::gcode {

struct Diagnostic {
  std::string file;
  int line = 0;    // 1-based
  int column = 0;  // 1-based column of the offending word or character; 0 for the whole line
  std::string message;

  // "file:line:column: message", the form compilers use, so editors can jump to it.
  std::string to_string() const {
    return file + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " + message;
  }
};

// Anything the interpreter rejects: unsupported codes, bad arcs, ambiguous spindle directions.
class GcodeError : public tridex::Error {
 public:
  explicit GcodeError(Diagnostic diagnostic)
      : tridex::Error(diagnostic.to_string()), where(std::move(diagnostic)) {}
  Diagnostic where;
};

// A block that cannot be split into words (bad characters, numbers, comments).
class SyntaxError : public GcodeError {
 public:
  using GcodeError::GcodeError;
};

}  // namespace tridex::gcode
