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
#include <istream>
#include <numbers>
#include <string_view>
#include <utility>

#include "tridex/gcode/lexer.hpp"

#include "line_reader.hpp"
#include "state.hpp"

namespace tridex::gcode {

// ---- the public class -----------------------------------------------------------------------
Interpreter::Interpreter(InterpreterOptions options, MachineConfig machine)
    : state_(std::make_unique<State>()) {
  detail::require_positive(options.arc_tolerance, "arc_tolerance");
  detail::require_positive(options.arc_radius_tolerance, "arc_radius_tolerance");
  detail::require_positive(options.peck_clearance, "peck_clearance");
  detail::require_positive(machine.far_distance, "far_distance");
  if (options.start_position && !is_finite(*options.start_position))
    detail::fail("start_position must be finite");
  if (!is_finite(machine.home) || !is_finite(machine.reference2))
    detail::fail("home and reference2 must be finite");
  for (const auto& [key, offset] : machine.work_offsets)
    if (!is_finite(offset)) detail::fail("work offset ", key, " must be finite");
  state_->options = options;
  state_->machine = std::move(machine);
}

Interpreter::~Interpreter() = default;
Interpreter::Interpreter(Interpreter&&) noexcept = default;
Interpreter& Interpreter::operator=(Interpreter&&) noexcept = default;

const std::vector<Diagnostic>& Interpreter::warnings() const { return state_->warnings; }
const std::set<int>& Interpreter::tools_used() const { return state_->tools_used; }
const std::map<int, int>& Interpreter::tool_first_line() const { return state_->tool_first_line; }
long long Interpreter::blocks() const { return state_->blocks; }

void Interpreter::run(std::istream& program, const std::string& file_name,
                      const std::function<void(const Move&)>& sink) {
  // A fresh machine for every run.
  auto fresh = std::make_unique<State>();
  fresh->options = state_->options;
  fresh->machine = state_->machine;
  state_ = std::move(fresh);
  State& s = *state_;
  s.file = &file_name;
  s.sink = &sink;
  s.offsets = s.machine.work_offsets;
  if (auto it = s.offsets.find(1); it != s.offsets.end()) s.work_offset = it->second;
  s.world_origin = s.work_offset;
  s.update_frame();
  if (s.options.start_position) {
    s.pos = s.world_origin + *s.options.start_position;
    s.far = false;
  } else {
    s.pos = s.world_origin;
    s.far = true;
  }

  LineReader reader(program);
  s.scanned_to = reader.offset();
  Block block;
  LexError lex_error;
  std::string_view text;
  int line = 0;
  bool started = false, percent_seen = false, ended = false;

  auto read = [&](std::string_view& out) {
    std::uint64_t at = reader.offset();
    bool too_long = false;
    if (!reader.next(out, too_long)) return false;
    ++line;
    s.line = line;
    if (too_long) s.error(0, "line longer than 65535 characters");
    if (at >= s.scanned_to) {  // first visit: note labels for M98
      int number;
      if (parse_label(out, number) && !s.labels.count(number))
        s.labels[number] = State::Label{reader.offset(), line};
      s.scanned_to = reader.offset();
      s.scanned_line = line;
    }
    return true;
  };
  auto jump = [&](std::uint64_t offset, int line_number) {
    if (!reader.seek(offset)) s.error(0, "M98/M99 need a seekable input stream");
    line = line_number;
  };

  while (read(text)) {
    if (line == 1 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // UTF-8 BOM
    if (!lex_line(text, block, lex_error))
      throw SyntaxError(Diagnostic{file_name, line, lex_error.column, lex_error.message});
    if (block.percent) {
      if (!started && !percent_seen) {
        percent_seen = true;
        continue;
      }
      if (!s.calls.empty())
        s.error(1, "'%' (end of tape) inside subprogram O" + std::to_string(s.calls.back().label));
      ended = true;
      break;
    }
    if (block.words.empty()) continue;
    if (block.block_delete && s.options.block_delete) continue;
    if (block.words.front().letter == 'O') {
      const Word& label = block.words.front();
      if (block.words.size() > 1)
        s.error(block.words[1].column, "an O number must be alone on its line");
      if (label.value < 0 || label.value != std::floor(label.value))
        s.error(label.column, "O number must be a non-negative integer");
      if (!s.calls.empty())
        s.error(label.column, "subprogram O" + std::to_string(s.calls.back().label) +
                                  " runs into O" + format_number(label.value) + " without M99");
      if (!started) {
        started = true;
        continue;
      }
      std::string message = "the main program runs into O" + format_number(label.value) +
                            " without M2/M30";
      if (!s.options.lenient) s.error(label.column, message);
      s.warn(label.column, message + "; treated as the end of the program");
      ended = true;
      break;
    }
    started = true;
    if (++s.blocks > s.options.max_blocks && s.options.max_blocks > 0)
      s.error(0, "more than " + std::to_string(s.options.max_blocks) + " blocks executed (max_blocks)");
    Flow flow = s.execute(block);
    if (flow == Flow::end) {
      ended = true;
      break;
    }
    if (flow == Flow::call) {
      if (s.call_repeats == 0) continue;
      if (static_cast<int>(s.calls.size()) >= s.options.max_call_depth)
        s.error(s.w.find_m(98), "subprogram calls nested deeper than " +
                                    std::to_string(s.options.max_call_depth));
      if (!reader.seekable()) s.error(s.w.find_m(98), "M98 needs a seekable input stream");
      State::Call call;
      call.label = s.call_label;
      call.return_offset = reader.offset();
      call.return_line = line;
      call.remaining = s.call_repeats;
      auto it = s.labels.find(call.label);
      if (it == s.labels.end()) {  // look further down the file, noting labels on the way
        int return_column = s.w.find_m(98);
        jump(s.scanned_to, s.scanned_line);
        std::string_view skipped;
        while (!s.labels.count(call.label) && read(skipped)) {
        }
        s.line = call.return_line;
        it = s.labels.find(call.label);
        if (it == s.labels.end())
          s.error(return_column, "M98 P" + std::to_string(call.label) + ": no O" +
                                     std::to_string(call.label) + " in the program");
      }
      call.body = it->second;
      s.calls.push_back(call);
      jump(call.body.body, call.body.line);
      continue;
    }
    if (flow == Flow::ret) {
      if (s.calls.empty()) {
        s.warn(s.w.find_m(99), "M99 in the main program: treated as the end of the program");
        ended = true;
        break;
      }
      State::Call& call = s.calls.back();
      if (--call.remaining > 0) {
        jump(call.body.body, call.body.line);
      } else {
        std::uint64_t offset = call.return_offset;
        int return_line = call.return_line;
        s.calls.pop_back();
        jump(offset, return_line);
      }
    }
  }
  if (!ended) {
    s.line = line;
    if (!s.calls.empty())
      s.error(0, "end of file inside subprogram O" + std::to_string(s.calls.back().label) +
                     " (missing M99)");
    s.warn(0, "the program ends without M2, M30 or '%' (truncated?)");
  }
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
