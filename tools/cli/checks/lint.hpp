// tridex command — the post lint (issue 39): mistakes a post-processor makes that a simulation
// may not show as a change of the part, each at file:line. `tridex lint`, and inside `diff`.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "json_text.hpp"

namespace tridex::cli {

struct LintFinding {
  std::string file;
  int line = 0;
  std::string code;  // units_change, g43_missing, g43_h_mismatch, integer_coordinate,
                     // arc_centre_mode, program_error
  std::string message;
};

struct LintSettings {
  // G43 H is expected after every tool change even when this program writes none (diff: the
  // reference program writes it).
  bool expect_g43 = false;
  // The machine file's "decimal_point_input": true (calculator input: X102 is 102 mm), false
  // (X102 is 102 least increments, 0.102 mm), unset (not known: integers are only warned about).
  std::optional<bool> decimal_point_input;
  // Every units switch and every G43 H that is not the loaded tool's (diff, where findings the
  // reference program shares are dropped); otherwise only those that look like mistakes (a
  // switch whose coordinates keep the other unit's sizes; an H unlike the program's other G43s).
  bool strict = false;
  // LinuxCNC reads X102 as 102 units always (no decimal-point-input setting): integers are fine.
  bool linuxcnc = false;
};

// What the program text says about itself (no interpretation): also used by diff to expect
// G43 in the other program.
bool program_uses_g43(std::string_view text);

// The findings of one G-code file's text, in line order.
std::vector<LintFinding> lint_text(std::string_view text, const std::string& file,
                                   const LintSettings& settings);

// An interpreter error as a finding (arc_centre_mode when the interpreter's message says the
// centres fit the other G90.1/G91.1 mode, else program_error).
LintFinding lint_error_finding(const std::string& file, int line, const std::string& message);

Json lint_json(const LintFinding& finding);
std::string lint_text_line(const LintFinding& finding);  // "file:line: code: message"

}  // namespace tridex::cli
