#include "inputs/program_input.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>

#include "errors.hpp"
#include "inputs/project.hpp"
#include "inputs/json_input.hpp"
#include "pipeline/memory.hpp"
#include "tridex/parallel.hpp"

namespace tridex::cli {

namespace fs = std::filesystem;

gcode::MachineConfig load_machine(const std::string& name_or_file,
                                  const std::vector<std::string>& subprogram_dirs) {
  gcode::MachineConfig machine;
  if (name_or_file.empty()) {
    machine = *gcode::MachineConfig::bundled("default");
  } else if (auto bundled = gcode::MachineConfig::bundled(name_or_file)) {
    machine = *bundled;
  } else {
    std::error_code error;
    if (!fs::is_regular_file(name_or_file, error))
      input_error("--machine ", name_or_file, ": neither a bundled machine (",
                  gcode::bundled_machine_names(), ") nor a machine file");
    nlohmann::json doc = read_json_file(name_or_file);
    try {
      machine = gcode::machine_from_json(doc, name_or_file);
    } catch (const gcode::MachineError& e) {
      throw InputError(e.what());  // bad input: exit status 2, as the command's other files
    }
  }
  for (const std::string& dir : subprogram_dirs) {
    std::error_code error;
    if (!fs::is_directory(dir, error)) input_error("--subprograms ", dir, ": not a folder");
    machine.subprogram_dirs.insert(machine.subprogram_dirs.begin(), dir);
  }
  return machine;
}

void apply_tool_options(const CommonOptions& options, ProgramInput& input) {
  if (!options.tool_units.empty()) {  // --tool-units states a .tbl's units, as "linear_units"
    input.machine.tool_table_in_inches = options.tool_units == "inch";
    input.machine.linear_units_stated = true;
  }
  // The tool in the spindle at start: --initial-tool, else the machine file's, else CAMotics'
  // tool 1 for a CAMotics project (CAMotics cuts a program with no tool change with it).
  if (options.initial_tool >= 0) {
    input.machine.initial_tool = options.initial_tool;
    input.machine.initial_tool_stated = true;
  } else if (!input.machine.initial_tool_stated && input.project) {
    input.machine.initial_tool = 1;
  }
  if (!options.tools.empty())
    input.tools = ToolTable::read(options.tools, input.machine.tool_table_in_inches ? 25.4 : 1.0);
  if (input.tools) {  // cutter compensation (G41/G42 D) offsets by half a tool's diameter
    for (const auto& [number, spec] : input.tools->tools())
      input.machine.tool_diameters[number] = spec.diameter_mm;
    for (int number : input.tools->zero_diameter()) input.machine.tool_diameters[number] = 0;
    input.machine.tool_lengths = input.tools->tool_lengths();  // G43 H
  }
}

ProgramInput resolve_program(const CommonOptions& options) {
  const std::string& program = options.program;
  ProgramInput input;
  input.machine = load_machine(options.machine, options.subprograms);
  input.program = program;
  std::error_code error;
  if (fs::is_directory(input.program, error))
    input_error(program, ": is a directory, not a program file");
  if (!fs::is_regular_file(input.program, error)) input_error(program, ": no such program file");
  if (is_project_file(input.program)) {
    Project project = read_project(input.program);
    input.files = std::move(project.files);
    input.tools = std::move(project.tools);
    input.stock = project.stock;
    input.fixtures = std::move(project.fixtures);
    input.project = true;
  } else {
    input.files.push_back(input.program);
  }
  // CAMotics' .tpl files are TPL, JavaScript that writes G-code when CAMotics runs it: read as
  // G-code, the first "var" would be refused as a word 'v' with no number.
  for (const fs::path& file : input.files) {
    std::string extension = file.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (extension == ".tpl")
      input_error(file.string(), ": a CAMotics TPL program (JavaScript that writes G-code), not ",
                  "G-code; run it with CAMotics' tplang and give tridex the G-code it writes");
  }
  apply_tool_options(options, input);
  return input;
}

std::vector<fs::path> files_read(const CommonOptions& options, const ProgramInput& input) {
  std::vector<fs::path> files(input.files.begin(), input.files.end());
  files.push_back(input.program);
  if (!options.machine.empty() && !gcode::MachineConfig::bundled(options.machine))
    files.push_back(options.machine);
  if (!options.tools.empty()) files.push_back(options.tools);
  return files;
}

gcode::InterpreterOptions interpreter_options(const CommonOptions& options) {
  gcode::InterpreterOptions o;
  o.arc_tolerance = options.arc_tolerance;
  o.lenient = options.lenient;
  o.block_delete = options.block_delete == "on";
  o.max_blocks = options.max_blocks;
  o.read_ahead = detail::resolve_threads(0) > 1;  // lexing beside interpreting (a second core)
  return o;
}

void MoveBudget::keep(const gcode::Move& move, const fs::path& file) {
  ++kept_;
  if (held_ > static_cast<double>(max_bytes_))
    input_error(file.string(), ":", move.line, ": tridex holds ", format_mib(held_),
                " before keeping any move (its libraries ",
                "and the files read), more than --max-memory ",
                format_mib(static_cast<double>(max_bytes_)), "; raise --max-memory");
  if (held_ + bytes() > static_cast<double>(max_bytes_))
    input_error(
        file.string(), ":", move.line, ": the program expands into more than ", kept_ - 1,
        " moves (", format_mib(bytes()), " to keep them, with ", format_mib(held_),
        " in use before reading), more than --max-memory ",
        format_mib(static_cast<double>(max_bytes_)),
        "; raise --max-memory, or give a larger --arc-tolerance if fine arcs make the moves");
}

InterpretResult interpret(const ProgramInput& input, const gcode::InterpreterOptions& options,
                          const std::function<void(const gcode::Move&, std::size_t file)>& sink,
                          const std::function<void(const gcode::Dwell&)>& dwell_sink,
                          long long max_moves) {
  InterpretResult result;
  gcode::Interpreter interpreter(options, input.machine);
  for (std::size_t f = 0; f < input.files.size(); ++f) {
    const fs::path& path = input.files[f];
    std::ifstream in(path, std::ios::binary);
    if (!in) input_error(path.string(), ": cannot open the program file");
    // The interpreter numbers the files of each run from 0: mapped into result.files as they come.
    std::vector<int> global;
    try {
      interpreter.run(
          in, path.string(),
          [&](const gcode::Move& move) {
            if (++result.moves > max_moves && max_moves > 0)
              input_error(path.string(), ":", move.line, ": more than ", max_moves,
                          " moves generated (--max-moves ", max_moves,
                          "; a loop of arcs at a fine --arc-tolerance?); raise --max-moves if the "
                          "program needs more");
            while (global.size() <= static_cast<std::size_t>(move.file)) {
              const std::string& name = interpreter.files()[global.size()];
              const auto known = std::find(result.files.begin(), result.files.end(), name);
              global.push_back(static_cast<int>(known - result.files.begin()));
              if (known == result.files.end()) result.files.push_back(name);
            }
            gcode::Move renumbered = move;
            renumbered.file = global[static_cast<std::size_t>(move.file)];
            sink(renumbered, f);
          },
          dwell_sink);
    } catch (const gcode::GcodeError& e) {
      if (options.max_blocks <= 0 || interpreter.blocks() <= options.max_blocks) throw;
      input_error(e.where.file, ":", e.where.line, ":", e.where.column, ": more than ",
                  options.max_blocks, " blocks executed (--max-blocks ", options.max_blocks,
                  "; an endless GOTO or WHILE loop, or nested M98 ... L repeats?); raise "
                  "--max-blocks if the "
                  "program needs more");
    }
    for (const std::string& name : interpreter.files())
      if (std::find(result.read.begin(), result.read.end(), name) == result.read.end())
        result.read.push_back(name);
    for (const gcode::Diagnostic& d : interpreter.warnings())
      result.warnings.push_back(d.to_string());
    for (const auto& [tool, line] : interpreter.tool_first_line())
      result.tool_first_line.try_emplace(tool, ToolSelection{path.string(), line});
    result.selects_tool = result.selects_tool || interpreter.selects_tool();
  }
  return result;
}

}  // namespace tridex::cli
