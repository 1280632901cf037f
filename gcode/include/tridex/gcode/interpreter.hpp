// tridex::gcode — the modal interpreter: a milling program in, a stream of tool-tip moves out.
//
// Codes: G0 G1 G2 G3 (I/J/K and R, full circles, helices) in G17/G18/G19, G20/G21, G90/G91,
// G90.1/G91.1, G54–G59 and G54.1 Pn, G10 L2/L20 (P0 the active system), LinuxCNC's G10 L1/L10/L11
// (tool table entries), G52, G92/G92.1/G92.2/ G92.3, G43/G44/G49 H and G43.1
// (MachineConfig::tool_lengths), T, M6, M61 Q, F, S, M3/M4/M5, M0/M1/M2/M30, G93/G94/G95,
// G28/G30/G53, canned cycles G73 G81 G82 G83 G85 G86 G89 with G98/G99 and repeats (L or K), cutter
// radius compensation G41/G42 D (MachineConfig::tool_diameters), G41.1/G42.1 D and G40 as LinuxCNC
// computes it, M98 P L / M99 with O (or ':') numbers, G65 macro calls, G4; tilted planes Fanuc
// G68.2 (Euler Z-X-Z), G53.1, G53.6, G69 and Haas G268 (Q123), G253, G269; with
// MachineConfig::kinematics, A/B/C words on G0/G1 (raw machine coordinates), Haas DWO G254/G255 and
// Fanuc TCP G43.4/G43.5 I J K (part coordinates), rotary limits and G53.1 reachability
// (gcode/README.md, "Rotary words, DWO and TCP"); Fanuc Macro B and LinuxCNC parameters,
// expressions and o-word control flow (lexer.hpp). Accepted without effect on the tool path: G15
// G61 G64 (P Q) G80 G97, look-ahead/smoothing G5.1 (Q R), G8 (P), G187 (P E), M7 M8 M9 and any
// other M-code (one warning per code unless the MachineConfig declares it). Anything else is an
// error naming file, line, column and word (a warning in lenient mode, which then skips the word).
//
// Conventions (docs/design.md): the programmed point is the tool tip after work offsets;
// G20 values are converted to mm; G68.2 R = Rz(I)·Rx(J)·Rz(K) and the tool axis is R·(0,0,1)
// once G53.1/G53.6 orient the tool; G268 R = Rz(K)·Ry(J)·Rx(I), oriented by G253. A home return
// (G28, G30 — but X/Y alone with the tool along +Z is a rapid at the current height — and G53
// Z), a tool change and a change of spindle direction leave the tip "far" along the tool axis;
// moves that leave the coordinate along the tool axis unset stay far and emit nothing; the first
// move that sets it comes straight back along the axis to its end. The program starts far along +Z
// (unless InterpreterOptions::start_position says otherwise).
//
// Emitted points are in the work frame: machine coordinates minus the G54 offset configured in
// MachineConfig (the machine frame itself when none is configured).
#pragma once

#include <functional>
#include <iosfwd>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "tridex/gcode/diagnostic.hpp"
#include "tridex/gcode/machine.hpp"
#include "tridex/gcode/move.hpp"
#include "tridex/geometry.hpp"

namespace tridex::gcode {

struct InterpreterOptions {
  double arc_tolerance = 0.001;   // mm, largest chord error of a linearised arc
  bool lenient = false;           // unsupported words become warnings and are skipped
  bool block_delete = true;       // skip blocks that start with '/' (the switch on)
  int max_call_depth = 16;        // nested M98 / G65 / o-word calls
  double peck_clearance = 0.254;  // mm, G73 back-off and G83 re-entry gap (LinuxCNC's 0.010 in)
  // Error once this many blocks ran: bounds endless loops (M98 L, WHILE, GOTO); 0 = no bound.
  long long max_blocks = 100'000'000;
  // run() reads and lexes the program's lines on a second thread while it interprets the blocks
  // before them (gcode/README.md, "Reading ahead"); moves, messages and errors are the same.
  // Until the first jump (M98, GOTO, a loop, an o-word call) only: from there on, one thread.
  bool read_ahead = false;
};

class Interpreter {
 public:
  explicit Interpreter(InterpreterOptions options = {}, MachineConfig machine = {});
  ~Interpreter();
  Interpreter(Interpreter&&) noexcept;
  Interpreter& operator=(Interpreter&&) noexcept;

  // Streams every move of the program to `sink` in program order; throws GcodeError (or its
  // SyntaxError) on bad input. Memory does not grow with the program's length. Each call starts
  // from a fresh machine state. M98 needs a seekable stream (files and string streams are).
  void run(std::istream& program, const std::string& file_name,
           const std::function<void(const Move&)>& sink);
  // The same, streaming every dwell to `dwell_sink` as well. The time word follows the dialect:
  // LinuxCNC reads G4 P and a cycle's P in seconds; Fanuc reads P in milliseconds and G4 X in
  // seconds (Haas's `P1.`, seconds for its decimal point, reads as 1 ms). A cycle's P is sticky,
  // as its Q is.
  void run(std::istream& program, const std::string& file_name,
           const std::function<void(const Move&)>& sink,
           const std::function<void(const Dwell&)>& dwell_sink);

  // A program fed in pieces, as a controller receives it: each call runs one more piece of the
  // same program, keeping the machine state (modes, position, tool, offsets, parameters, line
  // numbers) from the last; moves go to `sink` as they are read. A call, its subprogram body and
  // a loop must lie within one piece (M98 finds bodies only in the piece or in other files).
  // Text after the program's end (M2, M30, '%') is not run (one warning). finish() ends the
  // program: the moves cutter compensation still holds go to `sink`, a program that did not end
  // is warned about, and the next feed() starts a fresh machine. run() is unaffected.
  void feed(std::istream& piece, const std::string& file_name,
            const std::function<void(const Move&)>& sink,
            const std::function<void(const Dwell&)>& dwell_sink = {});
  void finish(const std::string& file_name, const std::function<void(const Move&)>& sink);
  // An interpreter in this one's state: what a piece would do can be tried on the copy.
  Interpreter clone() const;
  // Lets a fed program that ended (M2, M30, '%') take more pieces in the state it ended in: a
  // block tried after the end (Session::would_cut) runs instead of being ignored.
  void resume();

  const std::vector<Diagnostic>& warnings() const;
  const std::set<int>& tools_used() const;            // tools of the emitted moves
  const std::map<int, int>& tool_first_line() const;  // tool -> line of the M6 that loaded it
                                                      // (its first move's line if none)
  bool selects_tool() const;  // a T word or M61 ran (a program with none: CAMotics' tool 1)
  long long blocks() const;   // blocks executed by the last run
                              // (or the pieces fed so far)
  // The files of the current (or last) run, Move::file's table: the program given to run(), then
  // each subprogram file in the order it was first called (its path as found). Grows during a run.
  const std::vector<std::string>& files() const;

  struct State;  // the implementation (gcode/src/state.hpp)

 private:
  std::unique_ptr<State> state_;
};

// Reads a whole program file into memory as moves (convenient for small programs and tests).
std::vector<Move> read_moves(const std::string& path, InterpreterOptions options = {},
                             MachineConfig machine = {});

}  // namespace tridex::gcode
