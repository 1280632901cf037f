// tridex command — PROGRAM: a G-code file or a CAMotics project, interpreted into moves.
#pragma once

#include <filesystem>
#include <functional>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "inputs/stock.hpp"
#include "inputs/tool_table.hpp"
#include "checks/machining_time.hpp"
#include "pipeline/memory.hpp"
#include "tridex/gcode/interpreter.hpp"

namespace tridex::cli {

struct ProgramInput {
  std::filesystem::path program;             // what the user named
  std::vector<std::filesystem::path> files;  // the G-code file(s), in order
  std::optional<ToolTable> tools;            // --tools, else from a project
  std::optional<StockSpec> stock;            // from a project
  gcode::MachineConfig machine;              // --machine, --subprograms
  bool project = false;                      // a CAMotics project
  // A project's "fixtures" (STL files in the work frame; check's machine check).
  std::vector<std::filesystem::path> fixtures;
};

// --machine NAME|FILE and --subprograms: a bundled machine (tridex/gcode/machine.hpp's registry)
// or a machine file; an empty name is the default machine. `subprogram_dirs` are searched before
// the machine file's own. Throws InputError naming the option, or the file, the key and the value.
gcode::MachineConfig load_machine(const std::string& name_or_file,
                                  const std::vector<std::string>& subprogram_dirs = {});

// Throws InputError if the file is missing, the project is malformed or the machine unknown.
ProgramInput resolve_program(const CommonOptions& options);
// resolve_program's last step, for a program that comes without a file (embed/session.hpp):
// --tool-units, --initial-tool and --tools into `input` and its machine (G41/G42 D, G43 H).
void apply_tool_options(const CommonOptions& options, ProgramInput& input);

// Every file the run reads that is known before it interprets the program: the program (or
// project) and its G-code files, the machine file and the tool table. No output may name one of
// them (output.hpp: check_output_path); the subprograms the program calls are checked once known
// (check_outputs_not_read), and the stock and design by the commands that read them.
std::vector<std::filesystem::path> files_read(const CommonOptions& options,
                                              const ProgramInput& input);

// Where each tool was first selected, for messages: "file:line".
struct ToolSelection {
  std::string file;
  int line = 0;
};

struct InterpretResult {
  std::vector<std::string> warnings;  // "file:line:col: message"
  std::map<int, ToolSelection> tool_first_line;
  bool selects_tool = false;  // some file ran a T word or M61 (Interpreter::selects_tool)
  long long moves = 0;
  std::vector<std::string> files;  // Move::file's table over all runs: the program's files, then
                                   // the subprogram files they called, each once
  std::vector<std::string> read;   // every file the runs read, moves or not: no output may be one
};

// The interpreter's options from the command's: arc tolerance, --lenient, --block-delete and
// --max-blocks.
gcode::InterpreterOptions interpreter_options(const CommonOptions& options);

// Counts the moves a command keeps in memory against its --max-memory, so that a program that
// expands into too many moves (nested M98 ... L loops, arcs at a tiny --arc-tolerance) stops with
// exit status 2 and the count instead of running out of memory.
class MoveBudget {
 public:
  // What the process holds when the budget is made (its libraries, a design read) counts too.
  MoveBudget(std::uint64_t max_bytes, double bytes_per_move)
      : max_bytes_(max_bytes), per_move_(bytes_per_move), held_(peak_rss_bytes()) {}
  // Throws InputError, naming the file and line of the move that crosses the limit.
  // (A path, not its string: nothing is made per move unless the limit is crossed.)
  void keep(const gcode::Move& move, const std::filesystem::path& file);
  long long kept() const { return kept_; }
  double bytes() const { return static_cast<double>(kept_) * per_move_; }

 private:
  std::uint64_t max_bytes_;
  double per_move_;
  double held_;
  long long kept_ = 0;
};

// Runs every file of the program through the interpreter, streaming moves to `sink` with the
// index of the program file they came from (input.files) and with Move::file renumbered into
// InterpretResult::files (one table for all the runs), and dwells to `dwell_sink` where given.
// GcodeError propagates (exit status 2); running past options.max_blocks is an InputError that
// names --max-blocks.
// More than `max_moves` moves (0: no bound) is an InputError that names --max-moves.
InterpretResult interpret(const ProgramInput& input, const gcode::InterpreterOptions& options,
                          const std::function<void(const gcode::Move&, std::size_t file)>& sink,
                          const std::function<void(const gcode::Dwell&)>& dwell_sink = {},
                          long long max_moves = 0);

}  // namespace tridex::cli
