// tridex::gcode — the modal interpreter (see interpreter.hpp for the codes and conventions).
//
// Semantics follow RS274/NGC (Kramer, Proctor, Messina, NIST IR 6556, 2000) as LinuxCNC
// implements it — order of execution within a block, modal groups, arc and canned-cycle
// geometry — with Fanuc's tilted working plane (G68.2 / G53.1, Euler Z-X-Z) and Haas's G268 /
// G253 as docs/design.md fixes them, and its "far along the tool axis" rule for
// retracts and reorientations, which stands in for the machine's kinematics.
#include "tridex/gcode/interpreter.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <istream>
#include <numbers>
#include <string_view>
#include <utility>

#include "line_reader.hpp"
#include "state.hpp"
#include "tridex/gcode/lexer.hpp"

namespace tridex::gcode {

// ---- the public class -----------------------------------------------------------------------
Interpreter::Interpreter(InterpreterOptions options, MachineConfig machine)
    : state_(std::make_unique<State>()) {
  detail::require_positive(options.arc_tolerance, "arc_tolerance");
  detail::require_positive(options.peck_clearance, "peck_clearance");
  detail::require_positive(machine.far_distance, "far_distance");
  if (machine.arc_radius_tolerance)
    detail::require_positive(*machine.arc_radius_tolerance, "arc_radius_tolerance");
  if (machine.start_position && !is_finite(*machine.start_position))
    detail::fail("start_position must be finite");
  if (!is_finite(machine.tool_change_position)) detail::fail("tool_change_position must be finite");
  if (!is_finite(machine.home) || !is_finite(machine.reference2))
    detail::fail("home and reference2 must be finite");
  for (const auto& [key, offset] : machine.work_offsets)
    if (!is_finite(offset)) detail::fail("work offset ", key, " must be finite");
  state_->options = options;
  state_->machine = std::move(machine);
}

Interpreter::~Interpreter() = default;

void Interpreter::resume() {
  state_->continuation.ended = false;
  state_->continuation.percent_seen = false;
}

Interpreter Interpreter::clone() const {
  Interpreter copy(state_->options, state_->machine);
  copy.state_ = std::make_unique<State>(*state_);
  copy.state_->sink = nullptr;
  copy.state_->dwell_sink = nullptr;
  return copy;
}
Interpreter::Interpreter(Interpreter&&) noexcept = default;
Interpreter& Interpreter::operator=(Interpreter&&) noexcept = default;

const std::vector<Diagnostic>& Interpreter::warnings() const { return state_->summary.warnings; }
const std::set<int>& Interpreter::tools_used() const { return state_->summary.tools_used; }
const std::map<int, int>& Interpreter::tool_first_line() const {
  return state_->summary.tool_first_line;
}
bool Interpreter::selects_tool() const { return state_->summary.selects_tool; }
long long Interpreter::blocks() const { return state_->summary.blocks; }
const std::vector<std::string>& Interpreter::files() const { return state_->files; }

void Interpreter::run(std::istream& program, const std::string& file_name,
                      const std::function<void(const Move&)>& sink) {
  run(program, file_name, sink, {});
}

namespace {

// A fresh machine: the options and the machine configuration kept, everything else as at power-on.
void fresh_machine(std::unique_ptr<Interpreter::State>& state) {
  auto fresh = std::make_unique<Interpreter::State>();
  fresh->options = state->options;
  fresh->machine = state->machine;
  state = std::move(fresh);
  Interpreter::State& s = *state;
  s.frame.offsets = s.machine.work_offsets;
  for (const auto& [n, value] : s.machine.variables) s.preset(n, value);
  for (const auto& [name, value] : s.machine.named_variables)
    s.parameters.named_globals[name] = Value{value, false};
  if (auto it = s.frame.offsets.find(1); it != s.frame.offsets.end())
    s.frame.work_offset = it->second;
  s.frame.world_origin = s.frame.work_offset;
  s.modal.unit = s.machine.inch_at_start ? 25.4 : 1.0;
  s.modal.retract_to_r = s.machine.g99_at_start;
  s.frame.tcp_kinematics = s.machine.kinematics && s.machine.tcp_kinematics_at_start;
  s.update_frame();
  if (s.machine.start_position) {
    s.tool.pos = *s.machine.start_position;
    s.tool.far = false;
  } else {
    s.tool.pos = s.frame.world_origin;
    s.tool.far = true;
  }
}

// The end of a program: the moves cutter compensation still holds, an unfinished tilted plane,
// and what lenient mode skipped, summarised.
void end_program(Interpreter::State& s, const std::string& file_name) {
  s.comp_finish();  // compensated moves still waiting for a next move
  if (s.tilt.plane_blocks.code) {
    s.context.file = &file_name;
    s.context.line = s.tilt.plane_blocks.first_line;
    s.error(0, s.incomplete_plane());
  }
  // One line per kind of word lenient mode skipped or block it read otherwise, however many:
  // never silent.
  auto summarize = [&](const std::map<std::string, Interpreter::State::Skipped>& causes,
                       const char* verb) {
    for (const auto& [cause, skipped] : causes) {
      std::string lines;
      for (int l : skipped.lines) lines += (lines.empty() ? "" : ", ") + std::to_string(l);
      if (skipped.count > static_cast<long long>(skipped.lines.size())) lines += ", …";
      s.summary.warnings.push_back(Diagnostic{file_name, 0, 0,
                                              std::string("lenient mode ") + verb + " " +
                                                  std::to_string(skipped.count) + " × " + cause +
                                                  " (lines " + lines + ")"});
    }
  };
  summarize(s.summary.skipped, "skipped");
  summarize(s.summary.read_as, "read");
}

}  // namespace

void Interpreter::run(std::istream& program, const std::string& file_name,
                      const std::function<void(const Move&)>& sink,
                      const std::function<void(const Dwell&)>& dwell_sink) {
  fresh_machine(state_);  // a fresh machine for every run
  State& s = *state_;
  s.context.file = &file_name;
  s.sink = &sink;
  s.dwell_sink = &dwell_sink;
  run_program(s, program, file_name);
  end_program(s, file_name);
}

void Interpreter::feed(std::istream& piece, const std::string& file_name,
                       const std::function<void(const Move&)>& sink,
                       const std::function<void(const Dwell&)>& dwell_sink) {
  if (!state_->continuation.begun) {
    fresh_machine(state_);
    state_->continuation.begun = true;
  }
  State& s = *state_;
  s.context.file = &file_name;
  s.sink = &sink;
  s.dwell_sink = &dwell_sink;
  if (s.continuation.ended) {
    // As run() reads nothing after the end; said once, never silently.
    std::string rest{std::istreambuf_iterator<char>(piece), std::istreambuf_iterator<char>()};
    if (rest.find_first_not_of(" \t\r\n%") != std::string::npos &&
        !s.continuation.warned_after_end) {
      s.continuation.warned_after_end = true;
      s.summary.warnings.push_back(
          Diagnostic{file_name, s.continuation.line, 0,
                     "text fed after the end of the program (M2, M30, M99 or '%') is not run"});
    }
    return;
  }
  run_program_piece(s, piece, file_name);
  s.sink = nullptr;
  s.dwell_sink = nullptr;
}

void Interpreter::finish(const std::string& file_name,
                         const std::function<void(const Move&)>& sink) {
  State& s = *state_;
  if (!s.continuation.begun) return;
  std::function<void(const Dwell&)> no_dwells;
  s.sink = &sink;
  s.dwell_sink = &no_dwells;
  s.context.file = &file_name;
  if (!s.continuation.ended) {
    s.context.line = s.continuation.line;
    s.warn(0, "the program ends without M2, M30 or '%' (truncated?)");
  }
  end_program(s, file_name);
  s.sink = nullptr;
  s.dwell_sink = nullptr;
  s.continuation = {};
}

std::vector<Move> read_moves(const std::string& path, InterpreterOptions options,
                             MachineConfig machine) {
  std::ifstream in(path, std::ios::binary);
  if (!in) detail::fail("read_moves: cannot open '", path, "'");
  std::vector<Move> moves;
  Interpreter interpreter(options, std::move(machine));
  interpreter.run(in, path, [&](const Move& move) { moves.push_back(move); });
  return moves;
}

}  // namespace tridex::gcode
