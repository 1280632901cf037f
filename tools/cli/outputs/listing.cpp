// tridex moves / tridex groups: the interpreted program as JSON, for scripts and post checks.
#include <algorithm>
#include <array>
#include <iostream>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "errors.hpp"
#include "inputs/program_input.hpp"
#include "json_text.hpp"
#include "outputs/output.hpp"
#include "pipeline/memory.hpp"
#include "tridex/gcode/grouping.hpp"
#include "tridex/gcode/simultaneous.hpp"

namespace tridex::cli {

namespace {

// {"A": .., "C": ..}: the positions, in degrees, of the machine's rotary axes.
Json rotary_json(const gcode::Move& m, const std::array<double, 3>& rotary) {
  Json j = Json::object();
  for (std::size_t i = 0; i < 3; ++i)
    if ((m.rotary_axes >> i) & 1u) j[std::string(1, static_cast<char>('A' + i))] = rotary[i];
  return j;
}
Json rotary_json(const gcode::Move& m) { return rotary_json(m, m.rotary); }

// A simultaneous move's own fields (docs/command-line.md, `moves`): its pose law and its start's
// joints (the end's are "rotary" and "machine").
void append_simultaneous(std::string& record, const gcode::Move& m,
                         const gcode::Kinematics& kinematics) {
  record += ",\"pose\":\"";
  record += m.pose == gcode::PoseLaw::tcp ? "tcp" : "joints";
  record += "\",\"rotary_start\":";
  record += rotary_json(m, m.rotary_start).dump();
  record += ",\"machine_start\":";
  append_vec3(record, gcode::MovePath(kinematics, m).machine_start());
}

// Writes through an atomic file, or to stdout for "-".
template <class Write>
void write_output(const std::string& path, Write&& write) {
  if (path == "-") {
    write(std::cout);
    std::cout.flush();
    return;
  }
  AtomicOutput out(path);
  write(out.stream());
  out.commit();
}

void check_output(const ListOptions& options, const ProgramInput& input) {
  if (options.output == "-") return;
  check_output_path("-o", options.output, files_read(options, input));
}

// The subprograms the program called, known once it ran: none may be the output.
void check_output_after(const ListOptions& options, const InterpretResult& result) {
  const std::pair<std::string, std::filesystem::path> output{"-o", options.output};
  check_outputs_not_read({&output, 1}, result.read);
}

void print_warnings(const std::vector<std::string>& warnings, bool quiet) {
  if (quiet) return;
  for (const std::string& w : warnings) std::cerr << "warning: " << terminal_safe(w) << '\n';
}

}  // namespace

int run_moves(const ListOptions& options) {
  if (!options.diff.empty()) return run_moves_diff(options);
  ProgramInput input = resolve_program(options);
  check_output(options, input);
  InterpretResult result;
  write_output(options.output, [&](std::ostream& out) {
    std::string record;
    bool several_files = input.files.size() > 1;
    result = interpret(
        input, interpreter_options(options),
        [&](const gcode::Move& m, std::size_t file) {
          record.clear();
          record += "{\"line\":";
          record += std::to_string(m.line);
          if (several_files) {
            record += ",\"file\":";
            record += dump_json(Json(input.files[file].string()));
          }
          record += ",\"kind\":\"";
          record += gcode::to_string(m.kind);
          record += "\",\"tool\":";
          record += std::to_string(m.tool);
          record += ",\"start\":";
          append_vec3(record, m.start);
          record += ",\"end\":";
          append_vec3(record, m.end);
          record += ",\"axis\":";
          append_vec3(record, m.axis);
          record += ",\"feed\":";
          append_number(record, m.feed);
          record += ",\"spindle\":";
          append_number(record, m.spindle);
          if (m.from_far) record += ",\"from_far\":true";
          if (m.rotary_axes) {  // a kinematic model is in use (machine file)
            record += ",\"rotary\":";
            record += rotary_json(m).dump();
            record += ",\"machine\":";
            append_vec3(record, m.machine);
            if (m.pose != gcode::PoseLaw::fixed)
              append_simultaneous(record, m, *input.machine.kinematics);
          }
          record += "}\n";
          out << record;
        },
        {}, options.max_moves);
    check_output_after(options, result);
  });
  print_warnings(result.warnings, options.quiet);
  return kSuccess;
}

int run_groups(const ListOptions& options) {
  ProgramInput input = resolve_program(options);
  check_output(options, input);
  // The groups hold every move, each once (MoveList).
  MoveBudget budget(max_memory_bytes(options.max_memory),
                    gcode::MoveList::bytes_per_move(input.machine.kinematics.has_value()));
  gcode::DirectionGrouper grouper;
  struct Extra {
    long long kinds[4] = {0, 0, 0, 0};
    int first_line = 0, last_line = 0;
    Aabb local;  // tool-tip box of the cutting moves in the group's frame
    std::vector<std::array<double, 3>> rotary;  // the distinct rotary positions (kinematics)
  };
  std::vector<Extra> extras;
  MachiningTimer timer(input.machine);
  // Moves whose tool turns belong to no direction: counted apart, by tool.
  long long simultaneous = 0;
  std::map<std::string, long long> simultaneous_by_tool;
  InterpretResult result = interpret(
      input, interpreter_options(options),
      [&](const gcode::Move& m, std::size_t file) {
        budget.keep(m, input.files[file]);
        timer.add(m);
        if (m.pose != gcode::PoseLaw::fixed) {
          ++simultaneous;
          ++simultaneous_by_tool[std::to_string(m.tool)];
          return;
        }
        std::size_t g = grouper.add(m);
        if (g >= extras.size()) extras.resize(g + 1);
        Extra& e = extras[g];
        ++e.kinds[static_cast<int>(m.kind)];
        if (e.first_line == 0) e.first_line = m.line;
        e.last_line = m.line;
        if (m.rotary_axes &&
            std::find(e.rotary.begin(), e.rotary.end(), m.rotary) == e.rotary.end())
          e.rotary.push_back(m.rotary);
        if (m.kind != gcode::MoveKind::rapid) {
          const Frame& frame = grouper.groups()[g].frame;
          if (!m.from_far) e.local.extend(frame.to_local(m.start));
          e.local.extend(frame.to_local(m.end));
        }
      },
      [&](const gcode::Dwell& d) { timer.add(d); }, options.max_moves);
  check_output_after(options, result);
  Json groups = Json::array();
  const auto& list = grouper.groups();
  for (std::size_t g = 0; g < list.size(); ++g) {
    const gcode::MoveGroup& group = list[g];
    const Extra& e = extras[g];
    Json j;
    j["axis"] = to_json(group.axis);
    j["frame"] = {{"x", to_json(group.frame.rotation[0])},
                  {"y", to_json(group.frame.rotation[1])},
                  {"z", to_json(group.frame.rotation[2])}};
    j["moves"] = group.moves.size();
    j["by_kind"] = {
        {"rapid", e.kinds[0]}, {"feed", e.kinds[1]}, {"arc", e.kinds[2]}, {"cycle", e.kinds[3]}};
    j["tools"] = group.tools;
    j["lines"] = {e.first_line, e.last_line};
    if (!group.moves.empty() && group.moves.front().rotary_axes) {
      Json positions = Json::array();
      for (const auto& r : e.rotary) {
        gcode::Move m;
        m.rotary_axes = group.moves.front().rotary_axes;
        m.rotary = r;
        positions.push_back(rotary_json(m));
      }
      j["rotary"] = std::move(positions);
    }
    if (!e.local.empty())
      j["cutting_bounds_local"] = {{"min", to_json(e.local.min)}, {"max", to_json(e.local.max)}};
    groups.push_back(std::move(j));
  }
  Json document;
  document["program"] = input.program.string();
  document["segments"] = result.moves;
  document["groups"] = std::move(groups);
  if (simultaneous)  // absent for 3+2 programs, whose output stays as it was
    document["simultaneous"] = {{"moves", simultaneous}, {"by_tool", simultaneous_by_tool}};
  document["machining_time"] = machining_time_json(timer);
  document["warnings"] = result.warnings;
  write_output(options.output, [&](std::ostream& out) { out << dump_json(document, 2) << '\n'; });
  print_warnings(result.warnings, options.quiet);
  return kSuccess;
}

}  // namespace tridex::cli
