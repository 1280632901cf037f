// tridex::gcode — program flow: reading lines from the program and the subprogram files it calls,
// and carrying out calls (M98, G65, LinuxCNC o-word call), returns (M99, endsub, return), loops
// (Fanuc WHILE/DO/END, LinuxCNC while/do/repeat with break and continue), branches (Fanuc IF
// GOTO and GOTO, LinuxCNC if/elseif/else/endif) and subroutine definitions.
//
// Memory stays flat for long programs: control flow jumps by byte offset within a file, and what
// is remembered is bounded by the program's structure, not its length — the O labels, o-word
// subroutines and GOTO targets met, and a stack of calls, loops and branches. A GOTO or a call to
// a label not seen yet reads ahead (without executing) noting labels on the way, as M98 always
// did; a WHILE whose condition is false skips to its END the same way.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <set>

#include "line_reader.hpp"
#include "read_ahead.hpp"
#include "state.hpp"

namespace tridex::gcode {
namespace {

constexpr std::size_t kMaxControlDepth = 1000;  // open loops and branches

// One program file: the main program or a subprogram file found by name.
struct Source {
  std::string name;
  std::unique_ptr<std::ifstream> owned;  // null for the main program's stream
  LineReader reader;
  struct Label {
    std::uint64_t body = 0;  // offset of the line after the label
    int line = 0;            // line number of the label
  };
  std::map<int, Label> programs;             // O numbers
  std::map<std::string, Label> subroutines;  // o<name> sub / o100 sub
  std::map<long long, Label> sequences;      // N numbers that GOTO looked for (at the N line)
  std::uint64_t scanned_to = 0;
  int scanned_line = 0;
  std::uint64_t start = 0;

  Source(std::string n, std::istream& in) : name(std::move(n)), reader(in) {
    start = scanned_to = reader.offset();
  }
};

struct Position {
  std::size_t source = 0;
  std::uint64_t offset = 0;
  int line = 0;  // the line number of the line before `offset`
};

enum class CallKind { m98, m97, g65, o_call };  // M97: Haas, a block N of this program

struct Call {
  CallKind kind;
  std::string label;  // for messages and for matching endsub/return
  Position back;      // where the caller goes on
  Position body;
  long long remaining = 1;
  std::size_t loops = 0, branches = 0;  // depths of the control stacks at the call
  bool scope = false;                   // pushed a parameter scope
  std::array<Value, 34> arguments{};    // G65: the locals each repeat starts from
};

enum class LoopKind { fanuc, o_while, o_do, o_repeat };

struct Loop {
  LoopKind kind;
  long long id = 0;   // fanuc: DO m
  std::string label;  // o-words
  Position start;     // the loop's first line (WHILE / o-while: the condition line itself)
  long long remaining = 0;
};

struct Branch {
  std::string label;
  bool taken = false;
};

}  // namespace

class ProgramFlow {
 public:
  ProgramFlow(Interpreter::State& state, std::istream& program, const std::string& file_name)
      : s_(state) {
    sources_.push_back(std::make_unique<Source>(file_name, program));
    s_.context.file = &sources_[0]->name;
    s_.files = {file_name};  // sources_ and s_.files share their indices
    s_.context.file_index = 0;
  }

  void run();
  // Reads the main program ahead on a second thread (InterpreterOptions::read_ahead).
  void start_read_ahead(std::istream& program);
  // One piece of a longer program (Interpreter::feed): starts where the last piece stopped.
  void run_piece();

 private:
  Source& source() { return *sources_[current_]; }

  bool read(std::string_view& out);
  void jump(const Position& to);
  Position here() { return Position{current_, offset(), line_}; }
  // Where the next line starts in the current source (the read-ahead's, while it reads).
  std::uint64_t offset() { return read_ahead_ ? read_ahead_->offset() : source().reader.offset(); }
  void end_read_ahead();
  [[noreturn]] void error(int column, const std::string& message) { s_.error(column, message); }
  void count_block(int column);  // column: the statement's, named if it passes the block limit

  void note_label(std::string_view text, const Position& after);
  bool scan_for(const std::function<bool()>& found);
  std::optional<std::pair<std::size_t, Source::Label>> find_external(const std::string& label,
                                                                     bool o_word);
  std::optional<std::filesystem::path> find_by_o_number(const std::filesystem::path& dir,
                                                        int number);
  template <class Key>
  std::optional<Position> find_body(std::map<Key, Source::Label> Source::*table, const Key& key,
                                    const std::string& label, bool o_word, int column);

  void skip_until(const std::function<bool(const Skim&)>& stop, const std::string& what,
                  int column);
  void call(CallKind kind, const std::string& label, long long repeats, int column);
  void give_back(int column);
  void o_word(const Control& control);
  std::vector<Loop>::reverse_iterator find_o_loop(const std::string& label);
  OKeyword skip_to(const Control& control, std::initializer_list<OKeyword> keywords,
                   const std::string& what);
  void o_return(const Control& control);
  void o_if(const Control& control);
  void o_while(const Control& control);
  void o_repeat(const Control& control);
  void o_loop_end(const Control& control);
  void o_break(const Control& control);
  void linuxcnc_program_number(const Word& label);
  bool own_top() const;
  bool program_start(const std::string& name, int column);
  void loop_control(const Control& control);
  Position find_sequence(long long number, const std::string& what, int column);
  void jump_to_sequence(long long number, int column);
  std::vector<Value> arguments(const Control& control);
  bool condition(const Control& control);

  Interpreter::State& s_;
  std::vector<std::unique_ptr<Source>> sources_;
  std::size_t current_ = 0;
  int line_ = 0;
  std::vector<Call> calls_;
  std::vector<Loop> loops_;
  std::vector<Branch> branches_;
  Block block_;
  LexError lex_error_;
  std::unique_ptr<ReadAhead> read_ahead_;        // the main program's lines, until a jump
  const ReadAhead::Line* ahead_line_ = nullptr;  // the line read() gave from it
  bool started_ = false, percent_seen_ = false, ended_ = false;
  bool piece_ = false;                  // run_piece(): one piece of a program fed in pieces
  std::uint64_t statement_offset_ = 0;  // where the line being executed starts
  std::string_view skipped_;            // the line skip_until stopped at (until the next read)
  std::vector<Value> o_arguments_;      // an o-word call's arguments
  // Per subprogram folder, its files by the O number they start with (find_by_o_number).
  std::map<std::filesystem::path, std::map<int, std::filesystem::path>> o_numbers_;
};

bool ProgramFlow::read(std::string_view& out) {
  Source& src = source();
  std::uint64_t at = offset();
  ahead_line_ = nullptr;
  if (read_ahead_ && !read_ahead_->next(out, ahead_line_)) end_read_ahead();
  if (ahead_line_) {
    ++line_;
    s_.context.line = line_;  // the BOM is gone, as below; no line is too long (read_ahead.hpp)
  } else {
    bool too_long = false;
    if (!src.reader.next(out, too_long)) return false;
    ++line_;
    s_.context.line = line_;
    if (too_long) error(0, "line longer than 65535 characters");
    if (line_ == 1 && out.substr(0, 3) == "\xEF\xBB\xBF") out.remove_prefix(3);  // UTF-8 BOM
  }
  if (at >= src.scanned_to) {  // first visit: note labels
    note_label(out, here());
    src.scanned_to = offset();
    src.scanned_line = line_;
  }
  return true;
}

// Only the main program is read ahead, only from its start (run(), not a piece) and only from a
// stream the reader can go back into when the read-ahead ends.
void ProgramFlow::start_read_ahead(std::istream& program) {
  LineReader& reader = sources_[0]->reader;
  if (s_.options.read_ahead && reader.seekable())
    read_ahead_ = std::make_unique<ReadAhead>(program, reader.offset(), true);
}

// The main program's reader goes on after the last line the read-ahead gave.
void ProgramFlow::end_read_ahead() {
  const std::uint64_t at = read_ahead_->offset();
  read_ahead_.reset();
  if (!sources_[0]->reader.restart(at)) error(0, "the program file cannot be read again");
}

void ProgramFlow::note_label(std::string_view text, const Position& after) {
  Source& src = source();
  int number;
  if (parse_label(text, number)) {
    src.programs.emplace(number, Source::Label{after.offset, after.line});
    return;
  }
  std::size_t i = text.find_first_not_of(" \t");
  if (i == std::string_view::npos || (text[i] != 'o' && text[i] != 'O')) return;
  Skim skim;
  skim_line(text, skim);
  if (skim.kind == ControlKind::o_word && skim.keyword == OKeyword::sub)
    src.subroutines.emplace(skim.label, Source::Label{after.offset, after.line});
}

void ProgramFlow::jump(const Position& to) {
  if (read_ahead_) end_read_ahead();  // lines in order only
  current_ = to.source;
  s_.context.file = &source().name;
  s_.context.file_index = static_cast<int>(current_);
  if (!source().reader.seek(to.offset))
    error(0, "calls, loops and jumps need a seekable input stream");
  line_ = to.line;
}

void ProgramFlow::count_block(int column) {
  if (++s_.summary.blocks > s_.options.max_blocks && s_.options.max_blocks > 0)
    error(column, "more than " + std::to_string(s_.options.max_blocks) +
                      " blocks executed (the block limit; an endless loop?)");
}

// Reads ahead from the furthest line seen, noting labels, until `found` or the end of the file;
// then comes back. Returns whether `found` became true.
bool ProgramFlow::scan_for(const std::function<bool()>& found) {
  if (found()) return true;
  Position back = here();
  int line = s_.context.line;
  Source& src = source();
  jump(Position{current_, src.scanned_to, src.scanned_line});
  std::string_view skipped;
  bool ok = false;
  while (!(ok = found()) && read(skipped)) {
  }
  jump(back);
  s_.context.line = line;
  return ok;
}

// A subprogram file: `O1234.nc`-style names for an O number, `name.ngc` for a LinuxCNC o-word,
// in the machine's subprogram folders and the program's own folder; failing a name, for an O
// number, the file of those folders that starts with it (a control keeps programs by number).
std::optional<std::pair<std::size_t, Source::Label>> ProgramFlow::find_external(
    const std::string& label, bool o_word) {
  std::vector<std::string> names;
  if (label.find_first_of("/\\") != std::string::npos) return std::nullopt;  // a name, not a path
  if (o_word) {
    names = {label + ".ngc", label + ".NGC", label + ".nc"};
  } else {
    std::string padded = label;
    while (padded.size() < 4) padded = "0" + padded;
    for (const std::string& stem : {"O" + padded, "O" + label, "o" + padded, "o" + label, label})
      for (const char* ext : {".nc", ".NC", ".ngc", ".NGC", ".tap", ".txt", ".cnc", ""})
        names.push_back(stem + ext);
  }
  std::vector<std::filesystem::path> dirs;
  for (const std::string& d : s_.machine.subprogram_dirs) dirs.emplace_back(d);
  dirs.push_back(std::filesystem::path(sources_[0]->name).parent_path());
  for (std::size_t k = 0; k < sources_.size(); ++k)
    if (sources_[k]->name == label) return std::pair{k, Source::Label{sources_[k]->start, 0}};
  auto open = [&](const std::filesystem::path& path)
      -> std::optional<std::pair<std::size_t, Source::Label>> {
    std::string shown = path.string();
    for (std::size_t k = 0; k < sources_.size(); ++k)
      if (sources_[k]->name == shown) return std::pair{k, Source::Label{sources_[k]->start, 0}};
    auto file = std::make_unique<std::ifstream>(path, std::ios::binary);
    if (!*file) return std::nullopt;
    auto src = std::make_unique<Source>(shown, *file);
    src->owned = std::move(file);
    sources_.push_back(std::move(src));
    s_.files.push_back(shown);
    return std::pair{sources_.size() - 1, Source::Label{sources_.back()->start, 0}};
  };
  for (const auto& dir : dirs) {
    for (const std::string& name : names) {
      std::error_code ec;
      if (!std::filesystem::is_regular_file(dir / name, ec)) continue;
      if (auto found = open(dir / name)) return found;
    }
  }
  if (o_word) return std::nullopt;
  for (const auto& dir : dirs)
    if (auto path = find_by_o_number(dir, std::stoi(label)))
      if (auto found = open(*path)) return found;
  return std::nullopt;
}

// The file of `dir` whose program starts with O<number> (or Fanuc's `:<number>`) on its first line
// after `%`, blank lines and comments, whatever its name. The folder's files with a G-code
// extension (or none) are read once, their first kilobyte each.
std::optional<std::filesystem::path> ProgramFlow::find_by_o_number(const std::filesystem::path& dir,
                                                                   int number) {
  auto [index, fresh] = o_numbers_.try_emplace(dir);
  if (fresh) {
    static const std::set<std::string> kExtensions = {"",     ".nc",    ".ngc", ".tap", ".txt",
                                                      ".cnc", ".eia",   ".min", ".mpf", ".spf",
                                                      ".ptp", ".gcode", ".iso"};
    std::error_code ec;
    std::vector<std::filesystem::path> files;
    for (std::filesystem::directory_iterator it(dir.empty() ? "." : dir, ec), end; !ec && it != end;
         it.increment(ec)) {
      std::string ext = it->path().extension().string();
      for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      if (it->is_regular_file(ec) && kExtensions.count(ext)) files.push_back(it->path());
    }
    std::sort(files.begin(),
              files.end());  // the first in name order wins a number two files start with
    for (const auto& path : files) {
      std::ifstream in(path, std::ios::binary);
      std::string head(1024, '\0');
      in.read(head.data(), static_cast<std::streamsize>(head.size()));
      head.resize(static_cast<std::size_t>(in.gcount()));
      std::size_t i = 0;
      while (i < head.size()) {  // past %, blank lines and whole-line comments
        const char c = head[i];
        if (c == '%' || c == ' ' || c == '\t' || c == '\r' || c == '\n') {
          ++i;
        } else if (c == '(' || c == ';') {
          i = head.find('\n', i);
          if (i == std::string::npos) i = head.size();
        } else {
          break;
        }
      }
      if (i >= head.size() || (head[i] != 'O' && head[i] != 'o' && head[i] != ':')) continue;
      std::size_t digits = i + 1;
      while (digits < head.size() && digits - i <= 9 &&
             std::isdigit(static_cast<unsigned char>(head[digits])))
        ++digits;
      if (digits == i + 1 || digits - i > 9) continue;
      index->second.try_emplace(std::stoi(head.substr(i + 1, digits - i - 1)), path);
    }
  }
  auto it = index->second.find(number);
  if (it == index->second.end()) return std::nullopt;
  return it->second;
}

void ProgramFlow::skip_until(const std::function<bool(const Skim&)>& stop, const std::string& what,
                             int column) {
  int from = line_;
  std::string_view text;
  Skim skim;
  while (read(text)) {
    skim_line(text, skim);
    if (stop(skim)) {
      skipped_ = text;
      return;
    }
  }
  s_.context.line = from;
  error(column, "no " + what + " after this line");
}

// Where a called program's body starts: in this file (reading ahead for its label if need be),
// or in a subprogram file found by name, at its label (a LinuxCNC file must hold `o<name> sub`;
// a Fanuc file without its O number runs from its top).
template <class Key>
std::optional<Position> ProgramFlow::find_body(std::map<Key, Source::Label> Source::*table,
                                               const Key& key, const std::string& label,
                                               bool o_word, int column) {
  Source& src = source();
  if (scan_for([&] { return (src.*table).count(key) > 0; })) {
    Source::Label l = (src.*table).at(key);
    return Position{current_, l.body, l.line};
  }
  auto external = find_external(label, o_word);
  if (!external) return std::nullopt;
  std::size_t k = external->first;
  Source& file = *sources_[k];
  Position back = here();
  jump(Position{k, external->second.body, 0});
  std::optional<Source::Label> inner;
  if (scan_for([&] { return (file.*table).count(key) > 0; })) inner = (file.*table).at(key);
  jump(back);
  if (inner) return Position{k, inner->body, inner->line};
  if (o_word) error(column, "o<" + label + "> call: " + file.name + " has no o<" + label + "> sub");
  return Position{k, file.start, 0};
}

void ProgramFlow::call(CallKind kind, const std::string& label, long long repeats, int column) {
  if (repeats <= 0) return;
  if (static_cast<int>(calls_.size()) >= s_.options.max_call_depth)
    error(column,
          "subprogram calls nested deeper than " + std::to_string(s_.options.max_call_depth));
  Call c{kind, label, here(), {}, repeats, loops_.size(), branches_.size(), false};
  std::optional<Position> body =
      kind == CallKind::o_call ? find_body(&Source::subroutines, label, label, true, column)
      : kind == CallKind::m97
          ? find_sequence(std::stoll(label), "M97 P" + label, column)
          : find_body(&Source::programs, std::stoi(label), label, false, column);
  if (!body) {
    if (kind == CallKind::o_call)
      error(column, "o<" + label + "> call: no such subroutine in the program, and no " + label +
                        ".ngc in the subprogram folders");
    std::string message = std::string(kind == CallKind::m98 ? "M98 P" : "G65 P") + label +
                          ": no O" + label +
                          " in the program nor in the subprogram folders (--subprograms)";
    if (!s_.options.lenient) error(column, message);
    s_.warn(column, message + "; the call is skipped (lenient mode)");
    return;
  }
  c.body = *body;
  if (kind == CallKind::g65 || kind == CallKind::o_call) {  // M98 and M97 share the caller's locals
    s_.parameters.scopes.emplace_back();
    c.scope = true;
    auto& locals = s_.parameters.scopes.back().locals;
    if (kind == CallKind::g65) {
      locals = c.arguments = s_.call_request.arguments;
    } else {
      for (std::size_t k = 0; k < o_arguments_.size() && k + 1 < locals.size(); ++k)
        locals[k + 1] = o_arguments_[k];
    }
  }
  calls_.push_back(std::move(c));
  jump(calls_.back().body);
}

// M99, endsub, return: the next repeat of the call, or back to the caller.
void ProgramFlow::give_back(int column) {
  Call& c = calls_.back();
  loops_.resize(std::min(loops_.size(), c.loops));
  branches_.resize(std::min(branches_.size(), c.branches));
  (void)column;
  if (--c.remaining > 0) {
    if (c.kind == CallKind::g65) s_.parameters.scopes.back().locals = c.arguments;  // G65 L: afresh
    jump(c.body);
    return;
  }
  Position back = c.back;
  if (c.scope) s_.parameters.scopes.pop_back();
  calls_.pop_back();
  jump(back);
}

std::vector<Value> ProgramFlow::arguments(const Control& control) {
  std::vector<Value> values;
  if (!evaluate_arguments(control.arguments, control.arguments_column, s_, values, lex_error_))
    throw SyntaxError(Diagnostic{source().name, line_, lex_error_.column, lex_error_.message});
  return values;
}

bool ProgramFlow::condition(const Control& control) {
  std::vector<Value> values = arguments(control);
  if (values.size() != 1)
    error(control.arguments_column,
          std::string("o-word ") + to_string(control.keyword) + " needs one condition in [ ]");
  return values[0].number != 0;
}

void ProgramFlow::jump_to_sequence(long long number, int column) {
  jump(find_sequence(number, "GOTO " + std::to_string(number), column));
}

// Where block N`number` of the current file starts; `what` names the jump in the error.
Position ProgramFlow::find_sequence(long long number, const std::string& what, int column) {
  Source& src = source();
  auto it = src.sequences.find(number);
  if (it == src.sequences.end()) {
    // Fanuc searches forward from here, then from the start of the program.
    int from = line_;
    Position back = here();
    std::string_view text;
    Skim skim;
    std::optional<Position> found;
    for (int pass = 0; pass < 2 && !found; ++pass) {
      if (pass == 1) jump(Position{current_, src.start, 0});
      for (;;) {
        Position at = here();
        if (!read(text)) break;
        skim_line(text, skim);
        if (skim.sequence == number) {
          found = at;
          break;
        }
        if (pass == 1 && here().offset > back.offset) break;
      }
    }
    if (!found) {
      jump(back);
      s_.context.line = from;
      error(column, what + ": no block N" + std::to_string(number));
    }
    jump(back);
    s_.context.line = from;
    it = src.sequences.emplace(number, Source::Label{found->offset, found->line}).first;
  }
  return Position{current_, it->second.body, it->second.line};
}

void ProgramFlow::loop_control(const Control& control) {
  Position start{current_, 0, line_ - 1};
  // The statement's own line: its offset is where the reader was before reading it.
  start.offset = statement_offset_;
  if (control.kind == ControlKind::while_loop) {
    auto same = std::find_if(loops_.begin(), loops_.end(), [&](const Loop& l) {
      return l.kind == LoopKind::fanuc && l.start.source == start.source &&
             l.start.offset == start.offset;
    });
    if (control.condition) {
      if (same != loops_.end()) {
        loops_.erase(same + 1, loops_.end());
      } else {
        if (loops_.size() >= kMaxControlDepth) error(control.column, "loops nested too deeply");
        loops_.push_back(Loop{LoopKind::fanuc, control.number, {}, start, 0});
      }
      return;
    }
    if (same != loops_.end()) loops_.erase(same, loops_.end());
    long long id = control.number;
    int depth = 0;
    skip_until(
        [&](const Skim& k) {
          if (k.kind == ControlKind::while_loop && k.number == id) ++depth;
          if (k.kind == ControlKind::end_loop && k.number == id) return depth-- == 0;
          return false;
        },
        "END " + std::to_string(id), control.column);
    return;
  }
  // END m: back to the loop's WHILE (evaluated again) or DO.
  auto it = std::find_if(loops_.rbegin(), loops_.rend(), [&](const Loop& l) {
    return l.kind == LoopKind::fanuc && l.id == control.number;
  });
  if (it == loops_.rend())
    error(control.column, "END " + std::to_string(control.number) + " without a running DO " +
                              std::to_string(control.number));
  loops_.erase(it.base(), loops_.end());
  jump(it->start);
}

// LinuxCNC reads a bare O number met in the flow as a Fanuc-style program number and goes on into
// the blocks after it (LinuxCNC 2.9 interp_o_word.cc, convert_control_functions, case O_:
// "continue executing into Fanuc-style programs w/o skipping"), in the main program and in an M98
// subprogram alike: pcb2gcode's Mach3 output runs from its main program into "O200" and ends at
// that subprogram's M99, and rs274 cuts it so. Only inside an o-word call is it an error, as
// rs274 reports it.
// Whether the line just read is the first of a subprogram file being run from its top.
bool ProgramFlow::own_top() const {
  return !calls_.empty() && calls_.back().body.source == current_ && current_ != 0 &&
         calls_.back().body.offset == sources_[current_]->start;
}

// An O number or a program name (`name`, as written) on Fanuc and Haas: it opens the main
// program or a subprogram file; met later, a program ran into the next one. True when that ends
// the main program (lenient).
bool ProgramFlow::program_start(const std::string& name, int column) {
  if (own_top()) return false;  // a subprogram file's own O number, run from its top
  if (!calls_.empty())
    error(column, "subprogram " + calls_.back().label + " runs into " + name + " without M99");
  if (!started_) {
    started_ = true;
    return false;
  }
  std::string message = "the main program runs into " + name + " without M2/M30";
  if (!s_.options.lenient) error(column, message);
  s_.warn(column, message + "; treated as the end of the program");
  ended_ = true;
  return true;
}

void ProgramFlow::linuxcnc_program_number(const Word& label) {
  if (!calls_.empty() && calls_.back().kind == CallKind::o_call)
    error(label.column, "O" + format_number(label.value) +
                            " inside an o-word call: a Fanuc-style program must be called with M98 "
                            "(as LinuxCNC refuses it)");
  started_ = true;
}

// The innermost o-word loop labelled `label` (rend(): none).
std::vector<Loop>::reverse_iterator ProgramFlow::find_o_loop(const std::string& label) {
  return std::find_if(loops_.rbegin(), loops_.rend(),
                      [&](const Loop& l) { return l.kind != LoopKind::fanuc && l.label == label; });
}

// Skips to the next o-word of `control`'s label with one of `keywords`, and says which it met.
OKeyword ProgramFlow::skip_to(const Control& control, std::initializer_list<OKeyword> keywords,
                              const std::string& what) {
  const std::string& label = control.label;
  OKeyword hit = OKeyword::sub;
  skip_until(
      [&](const Skim& k) {
        if (k.kind != ControlKind::o_word || k.label != label) return false;
        for (OKeyword kw : keywords)
          if (k.keyword == kw) {
            hit = kw;
            return true;
          }
        return false;
      },
      what, control.column);
  return hit;
}

// LinuxCNC's o-words: a statement per keyword (subroutines, branches, loops).
void ProgramFlow::o_word(const Control& control) {
  const std::string& label = control.label;
  switch (control.keyword) {
    case OKeyword::sub:  // a definition met in the flow of the program: note it, skip it
      source().subroutines.emplace(label, Source::Label{here().offset, line_});
      skip_to(control, {OKeyword::endsub}, "o" + label + " endsub");
      return;
    case OKeyword::endsub:
    case OKeyword::return_:
      o_return(control);
      return;
    case OKeyword::call:
      o_arguments_ = arguments(control);
      call(CallKind::o_call, label, 1, control.column);
      return;
    case OKeyword::if_:
      o_if(control);
      return;
    case OKeyword::elseif:
    case OKeyword::else_:
      if (branches_.empty() || branches_.back().label != label)
        error(control.column,
              "o" + label + " " + to_string(control.keyword) + " without o" + label + " if");
      skip_to(control, {OKeyword::endif}, "o" + label + " endif");
      branches_.pop_back();
      return;
    case OKeyword::endif:
      if (branches_.empty() || branches_.back().label != label)
        error(control.column, "o" + label + " endif without o" + label + " if");
      branches_.pop_back();
      return;
    case OKeyword::while_:
      o_while(control);
      return;
    case OKeyword::do_:
      if (loops_.size() >= kMaxControlDepth) error(control.column, "loops nested too deeply");
      loops_.push_back(Loop{LoopKind::o_do, 0, label, here(), 0});
      return;
    case OKeyword::repeat:
      o_repeat(control);
      return;
    case OKeyword::endwhile:
    case OKeyword::endrepeat:
    case OKeyword::continue_:
      o_loop_end(control);
      return;
    case OKeyword::break_:
      o_break(control);
      return;
  }
}

// o endsub / o return [value]: back to the caller, the value in #<_value>.
void ProgramFlow::o_return(const Control& control) {
  const std::string& label = control.label;
  if (calls_.empty() || calls_.back().kind != CallKind::o_call)
    error(control.column, "o" + label + " " + to_string(control.keyword) + " outside a call");
  std::vector<Value> values = arguments(control);
  if (!values.empty()) {
    s_.parameters.named_globals["_value"] = values[0];
    s_.parameters.named_globals["_value_returned"] = Value{1, false};
  } else {
    s_.parameters.named_globals["_value_returned"] = Value{0, false};
  }
  give_back(control.column);
}

// o if: skips to the branch taken (an elseif's condition is evaluated when it is reached).
void ProgramFlow::o_if(const Control& control) {
  const std::string& label = control.label;
  bool taken = condition(control);
  if (branches_.size() >= kMaxControlDepth) error(control.column, "if nested too deeply");
  branches_.push_back(Branch{label, taken});
  while (!branches_.back().taken) {
    OKeyword hit = skip_to(control, {OKeyword::elseif, OKeyword::else_, OKeyword::endif},
                           "o" + label + " endif");
    if (hit == OKeyword::endif) {
      branches_.pop_back();
      return;
    }
    if (hit == OKeyword::else_) {
      branches_.back().taken = true;
    } else {  // elseif: skimmed, so its condition is evaluated now
      Block b;
      if (!lex_line(skipped_, b, lex_error_, &s_))
        throw SyntaxError(Diagnostic{source().name, line_, lex_error_.column, lex_error_.message});
      branches_.back().taken = condition(b.control);
    }
  }
}

// o while: the start of a while loop (its condition read at each turn), or the end of a do loop.
void ProgramFlow::o_while(const Control& control) {
  const std::string& label = control.label;
  Position start{current_, statement_offset_, line_ - 1};
  auto loop = find_o_loop(label);
  if (loop != loops_.rend() && loop->kind == LoopKind::o_do) {  // the end of a do … while
    if (condition(control)) {
      jump(loop->start);
    } else {
      loops_.erase(std::prev(loop.base()), loops_.end());
    }
    return;
  }
  bool running = loop != loops_.rend() && loop->start.offset == start.offset;
  if (condition(control)) {
    if (!running) {
      if (loops_.size() >= kMaxControlDepth) error(control.column, "loops nested too deeply");
      loops_.push_back(Loop{LoopKind::o_while, 0, label, start, 0});
    }
    return;
  }
  if (running) loops_.erase(std::prev(loop.base()), loops_.end());
  skip_to(control, {OKeyword::endwhile}, "o" + label + " endwhile");
}

void ProgramFlow::o_repeat(const Control& control) {
  const std::string& label = control.label;
  std::vector<Value> values = arguments(control);
  if (values.size() != 1)
    error(control.arguments_column, "o" + label + " repeat needs a count in [ ]");
  long long count = std::llround(values[0].number);
  if (count <= 0) {
    skip_to(control, {OKeyword::endrepeat}, "o" + label + " endrepeat");
    return;
  }
  if (loops_.size() >= kMaxControlDepth) error(control.column, "loops nested too deeply");
  loops_.push_back(Loop{LoopKind::o_repeat, 0, label, here(), count});
}

// o endwhile, o endrepeat, o continue: the loop's next turn, or its end.
void ProgramFlow::o_loop_end(const Control& control) {
  const std::string& label = control.label;
  auto loop = find_o_loop(label);
  if (loop == loops_.rend())
    error(control.column, "o" + label + " " + to_string(control.keyword) + " outside its loop");
  loops_.erase(loop.base(), loops_.end());  // loops opened inside it end here
  if (loop->kind == LoopKind::o_repeat) {
    if (--loop->remaining > 0) {
      jump(loop->start);
    } else {
      bool at_end = control.keyword == OKeyword::endrepeat;
      loops_.pop_back();
      if (!at_end) skip_to(control, {OKeyword::endrepeat}, "o" + label + " endrepeat");
    }
    return;
  }
  jump(loop->start);  // while: its condition again; do: its first line
}

void ProgramFlow::o_break(const Control& control) {
  const std::string& label = control.label;
  auto loop = find_o_loop(label);
  if (loop == loops_.rend()) error(control.column, "o" + label + " break outside its loop");
  LoopKind kind = loop->kind;
  loops_.erase(std::prev(loop.base()), loops_.end());
  if (kind == LoopKind::o_repeat)
    skip_to(control, {OKeyword::endrepeat}, "o" + label + " endrepeat");
  else if (kind == LoopKind::o_do)
    skip_to(control, {OKeyword::while_}, "o" + label + " while");
  else
    skip_to(control, {OKeyword::endwhile}, "o" + label + " endwhile");
}

void ProgramFlow::run() {
  std::string_view text;
  for (;;) {
    statement_offset_ = offset();
    if (!read(text)) {
      if (current_ != 0 && !calls_.empty() && calls_.back().body.source == current_ &&
          calls_.back().kind != CallKind::o_call) {
        give_back(0);  // a subprogram file that ends without M99
        continue;
      }
      break;
    }
    if (ahead_line_ && ahead_line_->lexed)
      read_ahead_->fill(*ahead_line_, block_);  // what lex_line makes of it (read_ahead.hpp)
    else if (!lex_line(text, block_, lex_error_, &s_))
      throw SyntaxError(Diagnostic{source().name, line_, lex_error_.column, lex_error_.message});
    if (block_.percent) {
      if (current_ != 0) continue;  // a subprogram file's own tape marks
      if (!started_ && !percent_seen_) {
        percent_seen_ = true;
        continue;
      }
      if (!calls_.empty()) error(1, "'%' (end of tape) inside subprogram " + calls_.back().label);
      ended_ = true;
      break;
    }
    if (block_.block_delete && s_.options.block_delete) continue;
    const Control& control = block_.control;
    if (control.kind != ControlKind::none) {
      count_block(control.column);
      started_ = true;
      for (const Assignment& a : block_.assignments) s_.assign(a);
      if (control.kind == ControlKind::o_word) {
        o_word(control);
      } else if (control.kind == ControlKind::jump) {
        jump_to_sequence(control.number, control.column);
      } else {
        loop_control(control);
      }
      continue;
    }
    if (!block_.program_name.empty()) {
      if (s_.machine.dialect == Dialect::linuxcnc)
        error(block_.program_name_column,
              "program name " + block_.program_name +
                  ": LinuxCNC has no program names; its O words are o-words, a number or <name> "
                  "and a keyword (o100 sub, o<name> call)");
      if (program_start(block_.program_name, block_.program_name_column)) break;
      continue;
    }
    if (block_.words.empty() && block_.assignments.empty()) continue;
    if (!block_.words.empty() && block_.words.front().letter == 'O') {
      const Word& label = block_.words.front();
      if (block_.words.size() > 1)
        error(block_.words[1].column, "an O number must be alone on its line");
      if (label.value < 0 || label.value != std::floor(label.value))
        error(label.column, "O number must be a non-negative integer");
      if (s_.machine.dialect == Dialect::linuxcnc && !own_top()) {
        linuxcnc_program_number(label);
        continue;
      }
      if (program_start("O" + format_number(label.value), label.column)) break;
      continue;
    }
    started_ = true;
    // The statement starts at its first word or assignment, whichever comes first on the line.
    int statement =
        block_.words.empty() ? block_.assignments.front().column : block_.words.front().column;
    if (!block_.assignments.empty())
      statement = std::min(statement, block_.assignments.front().column);
    count_block(statement);
    for (const Assignment& a : block_.assignments) s_.assign(a);
    if (block_.words.empty()) continue;
    Flow flow = s_.execute(block_);
    if (flow == Flow::end) {
      ended_ = true;
      break;
    }
    if (flow == Flow::call || flow == Flow::macro) {
      const int m97 = s_.w.find_m(kM97);
      int column = flow == Flow::macro ? s_.w.find_g(kG65) : m97 ? m97 : s_.w.find_m(kM98);
      call(flow == Flow::macro ? CallKind::g65
           : m97               ? CallKind::m97
                               : CallKind::m98,
           std::to_string(s_.call_request.label), s_.call_request.repeats, column);
      continue;
    }
    if (flow == Flow::ret) {
      if (calls_.empty()) {
        s_.warn(s_.w.find_m(kM99), "M99 in the main program: treated as the end of the program");
        ended_ = true;
        break;
      }
      if (calls_.back().kind == CallKind::o_call)
        error(s_.w.find_m(kM99),
              "M99 inside o" + calls_.back().label + " sub (use endsub or return)");
      give_back(s_.w.find_m(kM99));
    }
  }
  if (piece_) return;  // Interpreter::finish() checks the end
  if (!ended_) {
    if (!calls_.empty())
      error(0, "end of file inside subprogram " + calls_.back().label + " (missing M99/endsub)");
    s_.warn(0, "the program ends without M2, M30 or '%' (truncated?)");
  }
}

void ProgramFlow::run_piece() {
  Interpreter::State::Continuation& c = s_.continuation;
  piece_ = true;
  line_ = c.line;
  started_ = c.started;
  percent_seen_ = c.percent_seen;
  run();
  if (!ended_ && !calls_.empty())
    error(0, "the piece ends inside subprogram " + calls_.back().label +
                 ": feed a call and its body in one piece");
  if (!ended_ && !loops_.empty())
    error(0, "the piece ends inside a loop: feed a loop in one piece");
  c.line = line_;
  c.started = started_;
  c.percent_seen = percent_seen_;
  c.ended = ended_;
}

void run_program(Interpreter::State& state, std::istream& program, const std::string& file_name) {
  ProgramFlow flow(state, program, file_name);
  flow.start_read_ahead(program);
  flow.run();
}

void run_program_piece(Interpreter::State& state, std::istream& piece,
                       const std::string& file_name) {
  ProgramFlow(state, piece, file_name).run_piece();
}

}  // namespace tridex::gcode
