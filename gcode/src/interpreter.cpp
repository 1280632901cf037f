// tridex::gcode — the modal interpreter (see interpreter.hpp for the codes and conventions).
//
// Semantics follow RS274/NGC (Kramer, Proctor, Messina, NIST IR 6556, 2000) as LinuxCNC
// implements it — order of execution within a block, modal groups, arc and canned-cycle
// geometry — with Fanuc's tilted working plane (G68.2 / G53.1, Euler Z-X-Z) and Haas's G268 /
// G253 as ../shared/DESIGN.md fixes them, and DESIGN.md's "far along the tool axis" rule for
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

namespace tridex::gcode {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kAxisEps = 1e-9;        // a frame axis "has a component" along the tool axis
constexpr double kSameDirection = 1e-12;  // 1 − cos of the angle below which axes are equal
constexpr long long kMaxArcPieces = 10'000'000;

// ---- reading lines ------------------------------------------------------------------------
// A fixed buffer over the stream: constant memory, no per-line allocation, and byte offsets for
// M98 to jump back to.
class LineReader {
 public:
  static constexpr std::size_t kCapacity = 1 << 16;

  explicit LineReader(std::istream& in) : in_(in), buffer_(kCapacity) {
    std::streamoff start = in_.tellg();
    seekable_ = start >= 0;
    base_ = seekable_ ? static_cast<std::uint64_t>(start) : 0;
  }

  // The next line without its '\n'; false at the end of the input; `too_long` when a line
  // does not fit the buffer.
  bool next(std::string_view& line, bool& too_long) {
    too_long = false;
    for (;;) {
      const char* start = buffer_.data() + pos_;
      std::size_t available = end_ - pos_;
      const void* newline = available ? std::memchr(start, '\n', available) : nullptr;
      if (newline) {
        std::size_t length = static_cast<std::size_t>(static_cast<const char*>(newline) - start);
        line = std::string_view(start, length);
        pos_ += length + 1;
        return true;
      }
      if (eof_) {
        if (available == 0) return false;
        line = std::string_view(start, available);
        pos_ = end_;
        return true;
      }
      if (available == kCapacity) {
        too_long = true;
        return true;
      }
      std::memmove(buffer_.data(), start, available);
      base_ += pos_;
      pos_ = 0;
      end_ = available;
      in_.read(buffer_.data() + end_, static_cast<std::streamsize>(kCapacity - end_));
      std::streamsize got = in_.gcount();
      end_ += static_cast<std::size_t>(got);
      if (!in_) eof_ = true;
    }
  }

  std::uint64_t offset() const { return base_ + pos_; }  // where the next line starts
  bool seekable() const { return seekable_; }

  bool seek(std::uint64_t offset) {
    if (!seekable_) return false;
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(offset));
    if (!in_) return false;
    base_ = offset;
    pos_ = end_ = 0;
    eof_ = false;
    return true;
  }

 private:
  std::istream& in_;
  std::vector<char> buffer_;
  std::size_t pos_ = 0, end_ = 0;
  std::uint64_t base_ = 0;
  bool eof_ = false;
  bool seekable_ = false;
};

// `O1234` alone on its line (comments allowed): a program or subprogram label.
bool parse_label(std::string_view text, int& number) {
  std::size_t i = 0, n = text.size();
  while (i < n && (text[i] == ' ' || text[i] == '\t')) ++i;
  if (i == n || (text[i] != 'O' && text[i] != 'o')) return false;
  ++i;
  long long value = 0;
  std::size_t digits = 0;
  while (i < n && text[i] >= '0' && text[i] <= '9' && digits < 10) {
    value = value * 10 + (text[i] - '0');
    ++i;
    ++digits;
  }
  if (digits == 0 || value > 999'999'999) return false;
  number = static_cast<int>(value);
  return true;
}

// ---- words of one block ---------------------------------------------------------------------
int letter_index(char c) { return c - 'A'; }

struct Code {
  int code;    // G and M codes times ten: G53.1 -> 531, G1 -> 10
  int column;
};

struct Words {
  std::array<double, 26> value{};
  std::array<int, 26> column{};
  std::uint32_t present = 0;
  std::uint32_t used = 0;
  std::array<Code, 24> g{};
  int g_count = 0;
  std::array<Code, 8> m{};
  int m_count = 0;

  bool has(char c) const { return (present >> letter_index(c)) & 1u; }
  int col(char c) const { return column[static_cast<std::size_t>(letter_index(c))]; }
  double take(char c) {
    used |= 1u << letter_index(c);
    return value[static_cast<std::size_t>(letter_index(c))];
  }
  int find_g(int code) const {
    for (int i = 0; i < g_count; ++i)
      if (g[static_cast<std::size_t>(i)].code == code) return g[static_cast<std::size_t>(i)].column;
    return 0;
  }
  int find_m(int code) const {
    for (int i = 0; i < m_count; ++i)
      if (m[static_cast<std::size_t>(i)].code == code) return m[static_cast<std::size_t>(i)].column;
    return 0;
  }
};

// Modal groups (RS274/NGC table 4, plus the tilted-plane codes); -1: not supported.
enum Group {
  kNonModal, kMotion, kPlane, kDistance, kArcDistance, kFeedMode, kUnits, kCutterComp,
  kToolLength, kReturn, kWork, kSpindleMode, kPolar, kPath, kTilt, kOrient, kSmoothing,
  kGroupCount
};

int g_group(int code) {
  switch (code) {
    case 40: case 100: case 280: case 300: case 530: return kNonModal;
    case 0: case 10: case 20: case 30: case 730: case 800: case 810: case 820: case 830:
    case 850: case 860: case 890: return kMotion;
    case 170: case 180: case 190: return kPlane;
    case 900: case 910: return kDistance;
    case 901: case 911: return kArcDistance;
    case 940: return kFeedMode;
    case 200: case 210: return kUnits;
    case 400: return kCutterComp;
    case 430: case 440: case 490: return kToolLength;
    case 980: case 990: return kReturn;
    case 540: case 550: case 560: case 570: case 580: case 590: case 541: return kWork;
    case 970: return kSpindleMode;
    case 150: return kPolar;
    case 610: case 640: return kPath;
    case 682: case 690: case 2680: case 2690: return kTilt;
    case 531: case 536: case 2530: return kOrient;
    case 51: case 80: case 1870: return kSmoothing;  // Fanuc G5.1 Q / G8 P, Haas G187 P E
    default: return -1;
  }
}

enum MGroup { kStop, kToolChange, kSpindle, kCoolant, kMGroupCount };

int m_group(int code) {
  switch (code) {
    case 0: case 1: case 2: case 30: case 98: case 99: return kStop;
    case 6: return kToolChange;
    case 3: case 4: case 5: return kSpindle;
    case 7: case 8: case 9: return kCoolant;
    default: return -1;
  }
}

std::string code_name(char letter, int code10) {
  char text[32];
  if (code10 % 10)
    std::snprintf(text, sizeof text, "%c%d.%d", letter, code10 / 10, code10 % 10);
  else
    std::snprintf(text, sizeof text, "%c%d", letter, code10 / 10);
  return text;
}

std::string format_number(double v) {
  char text[48];
  std::snprintf(text, sizeof text, "%.10g", v);
  return text;
}

bool is_cycle(int motion) {
  return motion == 730 || motion == 810 || motion == 820 || motion == 830 || motion == 850 ||
         motion == 860 || motion == 890;
}

// Plane axes (u, v) and normal w as coordinate indices: G17 XY, G18 ZX, G19 YZ.
std::array<int, 3> plane_axes(int plane) {
  if (plane == 180) return {2, 0, 1};
  if (plane == 190) return {1, 2, 0};
  return {0, 1, 2};
}

constexpr char kAxisLetter[3] = {'X', 'Y', 'Z'};
constexpr char kCenterLetter[3] = {'I', 'J', 'K'};

enum class Flow { next, end, call, ret };

}  // namespace

// ---- the interpreter's state ----------------------------------------------------------------
struct Interpreter::State {
  InterpreterOptions options;
  MachineConfig machine;

  std::vector<Diagnostic> warnings;
  std::set<int> tools_used;
  std::map<int, int> tool_first_line;
  long long blocks = 0;

  // Context of the block being executed.
  const std::string* file = nullptr;
  const std::function<void(const Move&)>* sink = nullptr;
  int line = 0;
  int motion_column = 1;

  // Modal state.
  double unit = 1.0;  // mm per program unit
  bool incremental = false;
  bool arc_absolute = false;
  int plane = 170;
  int motion = -1;  // -1: none yet
  bool retract_to_r = false;
  int work_key = 1;
  Vec3 work_offset{0.0};
  std::map<int, Vec3> offsets;
  double feed = 0;
  double speed = 0;
  int spindle_direction = 0;
  int tool_selected = 0;
  int tool = 0;

  // Tilted working plane and the active program frame (program point p -> machine
  // origin + rotation·p).
  bool tilted = false;
  Mat3 tilt_rotation{1.0};
  Vec3 tilt_origin{0.0};
  int tilt_line = 0;
  Mat3 rotation{1.0};
  Vec3 origin{0.0};

  // Tool: spindle direction, tip position (machine coordinates) and the far flag.
  Vec3 axis{0.0, 0.0, 1.0};
  Vec3 pos{0.0};
  bool far = true;
  bool ambiguous = false;
  bool warned_ambiguous = false;
  bool warned_home = false;
  bool warned_reference2 = false;
  Vec3 world_origin{0.0};

  // Canned cycle state (sticky values, program units converted to mm, as written).
  bool cycle_active = false;
  bool cycle_initial_far = false;
  double cycle_initial = 0;
  double cycle_r = 0, cycle_z = 0, cycle_q = 0;
  bool has_cycle_r = false, has_cycle_z = false, has_cycle_q = false;

  // Subprograms.
  struct Label {
    std::uint64_t body = 0;  // offset of the line after the label
    int line = 0;            // line number of the label
  };
  struct Call {
    int label = 0;
    std::uint64_t return_offset = 0;
    int return_line = 0;
    long long remaining = 0;
    Label body;
  };
  std::map<int, Label> labels;
  std::vector<Call> calls;
  std::uint64_t scanned_to = 0;
  int scanned_line = 0;
  int call_label = 0;
  long long call_repeats = 0;

  Words w;

  // ---- diagnostics ----
  [[noreturn]] void error(int column, std::string message) const {
    throw GcodeError(Diagnostic{*file, line, column, std::move(message)});
  }
  void warn(int column, std::string message) {
    // Bounded: a warning per block of a long program would grow memory with its length.
    if (warnings.size() < 1000) warnings.push_back(Diagnostic{*file, line, column, std::move(message)});
  }
  void unsupported(int column, const std::string& message) {
    if (!options.lenient) error(column, message);
    warn(column, message + " (skipped: lenient mode)");
  }

  // ---- words ----
  void gather(const Block& block) {
    w.present = w.used = 0;
    w.g_count = w.m_count = 0;
    std::array<int, kGroupCount> g_seen{};
    std::array<int, kMGroupCount> m_seen{};
    for (const Word& word : block.words) {
      if (word.letter == 'G' || word.letter == 'M') {
        // Codes are small; anything else is unsupported before it reaches an int (fuzz finding).
        double scaled = word.value * 10;
        double rounded = std::round(scaled);
        bool integral = std::abs(scaled - rounded) < 1e-6 && word.value >= 0 && word.value < 10000;
        int code = integral ? static_cast<int>(rounded) : -1;
        if (word.letter == 'M' && code % 10) integral = false;
        int group = !integral ? -1 : word.letter == 'G' ? g_group(code) : m_group(code / 10);
        if (group < 0) {
          unsupported(word.column, std::string("unsupported code ") + word.letter +
                                       format_number(word.value));
          continue;
        }
        if (word.letter == 'G') {
          int& seen = g_seen[static_cast<std::size_t>(group)];
          if (seen)
            error(word.column, code_name('G', code) + " conflicts with " +
                                   code_name('G', w.g[static_cast<std::size_t>(seen - 1)].code) +
                                   " in the same block (same modal group)");
          if (w.g_count == static_cast<int>(w.g.size())) error(word.column, "too many G codes");
          w.g[static_cast<std::size_t>(w.g_count++)] = Code{code, word.column};
          seen = w.g_count;
        } else {
          int& seen = m_seen[static_cast<std::size_t>(group)];
          if (seen)
            error(word.column, code_name('M', code) + " conflicts with " +
                                   code_name('M', w.m[static_cast<std::size_t>(seen - 1)].code) +
                                   " in the same block (same modal group)");
          w.m[static_cast<std::size_t>(w.m_count++)] = Code{code / 10, word.column};
          seen = w.m_count;
        }
        continue;
      }
      if (word.letter == 'N') continue;  // sequence numbers carry no meaning here
      std::size_t i = static_cast<std::size_t>(letter_index(word.letter));
      if (w.has(word.letter))
        error(word.column, std::string("repeated word ") + word.letter + " (first at column " +
                               std::to_string(w.column[i]) + ")");
      w.present |= 1u << i;
      w.value[i] = word.value;
      w.column[i] = word.column;
    }
  }

  double length(char c) { return w.take(c) * unit; }

  long long integer(char c, const char* what, long long low, long long high) {
    double v = w.take(c);
    if (std::abs(v - std::round(v)) > 1e-9 || v < static_cast<double>(low) ||
        v > static_cast<double>(high))
      error(w.col(c), std::string(what) + ": " + c + format_number(v) + " must be an integer in [" +
                          std::to_string(low) + ", " + std::to_string(high) + "]");
    return static_cast<long long>(std::llround(v));
  }

  bool has_axis_words() const { return w.has('X') || w.has('Y') || w.has('Z'); }

  // ---- frames ----
  Vec3 to_machine(const Vec3& p) const { return origin + rotation * p; }
  Vec3 to_program(const Vec3& m) const { return glm::transpose(rotation) * (m - origin); }

  void update_frame() {
    if (tilted) {
      rotation = tilt_rotation;
      origin = tilt_origin;
    } else {
      rotation = Mat3(1.0);
      origin = work_offset;
    }
    ambiguous = tilted && glm::dot(tilt_rotation[2], axis) < 1 - kSameDirection;
  }

  // ---- emitting ----
  void emit(MoveKind kind, const Vec3& a, const Vec3& b, double move_feed) {
    if (ambiguous) {
      std::string message = "spindle direction is ambiguous: the plane tilted at line " +
                            std::to_string(tilt_line) +
                            " is not normal to the tool and no G53.1/G53.6/G253 has oriented it";
      if (!options.lenient) error(motion_column, message);
      if (!warned_ambiguous) warn(motion_column, message + "; keeping the current direction");
      warned_ambiguous = true;
    }
    Move move;
    move.line = line;
    move.kind = kind;
    move.tool = tool;
    move.start = a - world_origin;
    move.end = b - world_origin;
    move.axis = axis;
    move.feed = move_feed;
    move.spindle = speed * spindle_direction;
    if (tools_used.insert(tool).second) tool_first_line.emplace(tool, line);
    (*sink)(move);
  }

  // Moves the tip to program point `target` of the frame (rot, org); coordinate i was set
  // absolutely when set_absolute[i]. Handles the far state (see interpreter.hpp).
  void move_to(Vec3 target, const std::array<bool, 3>& set_absolute, const Mat3& rot,
               const Vec3& org, MoveKind kind, double move_feed) {
    auto to_frame_machine = [&](const Vec3& p) { return org + rot * p; };
    if (!far) {
      Vec3 end = to_frame_machine(target);
      emit(kind, pos, end, move_feed);
      pos = end;
      return;
    }
    Vec3 current = glm::transpose(rot) * (pos - org);
    Vec3 along = glm::transpose(rot) * axis;
    bool any = false, all = true;
    for (int i = 0; i < 3; ++i) {
      if (std::abs(along[i]) <= kAxisEps) continue;
      if (set_absolute[static_cast<std::size_t>(i)]) {
        any = true;
      } else {
        all = false;
        target[i] = current[i];
      }
    }
    if (!any) {  // still far: only the lateral position changes
      pos = to_frame_machine(target);
      return;
    }
    if (!all)
      error(motion_column,
            "the tool is retracted far along its axis and this move sets only some of the "
            "coordinates along the tool axis; set all of X, Y and Z to bring it back");
    Vec3 end = to_frame_machine(target);
    emit(kind, end + machine.far_distance * axis, end, move_feed);
    pos = end;
    far = false;
  }

  void linear(MoveKind kind, double move_feed) {
    Vec3 current = to_program(pos);
    Vec3 target = current;
    std::array<bool, 3> set{};
    for (int i = 0; i < 3; ++i) {
      char c = kAxisLetter[i];
      if (!w.has(c)) continue;
      double v = length(c);
      target[i] = incremental ? current[i] + v : v;
      set[static_cast<std::size_t>(i)] = !incremental;
    }
    move_to(target, set, rotation, origin, kind, move_feed);
  }

  void require_feed() {
    if (!(feed > 0)) error(motion_column, "feed move with no feed rate (F) set");
  }

  // ---- arcs ----
  void arc(bool ccw) {
    if (far)
      error(motion_column,
            "arc from a retracted position: the tool is far along its axis; position it first");
    require_feed();
    const std::array<int, 3> axes = plane_axes(plane);
    const int u = axes[0], v = axes[1], n = axes[2];
    Vec3 start = to_program(pos);
    Vec3 end = start;
    for (int i = 0; i < 3; ++i) {
      char c = kAxisLetter[i];
      if (w.has(c)) end[i] = incremental ? start[i] + length(c) : length(c);
    }
    char cu = kCenterLetter[u], cv = kCenterLetter[v];
    bool has_center = w.has(cu) || w.has(cv);
    bool has_radius = w.has('R');
    if (has_center && has_radius)
      error(w.col('R'), "arc with both R and " + std::string(1, cu) + "/" + cv + " words");
    if (!has_center && !has_radius)
      error(motion_column, std::string("arc needs ") + cu + "/" + cv + " (in " +
                               code_name('G', plane) + ") or R");
    Vec2 s(start[u], start[v]), e(end[u], end[v]), c;
    double r0, r1;
    if (has_center) {
      if (arc_absolute) {
        if (!w.has(cu) || !w.has(cv))
          error(motion_column, std::string("arc centre under G90.1 needs both ") + cu + " and " + cv);
        c = Vec2(length(cu), length(cv));
      } else {
        c = s + Vec2(w.has(cu) ? length(cu) : 0.0, w.has(cv) ? length(cv) : 0.0);
      }
      r0 = glm::length(s - c);
      r1 = glm::length(e - c);
      if (!(r0 > 1e-9)) error(motion_column, "zero-radius arc: the centre is the start point");
      if (!(r1 > 1e-9)) error(motion_column, "zero-radius arc: the centre is the end point");
      if (std::abs(r1 - r0) > options.arc_radius_tolerance)
        error(motion_column, "arc end radius " + format_number(r1) + " differs from start radius " +
                                 format_number(r0) + " by more than " +
                                 format_number(options.arc_radius_tolerance) + " mm");
    } else {
      double r = length('R');
      double d = glm::length(e - s);
      if (!(std::abs(r) > 1e-9)) error(w.col('R'), "zero-radius arc (R0)");
      if (!(d > 1e-9))
        error(w.col('R'), "R-form arc with the same start and end point (a full circle needs I/J/K)");
      if (d > 2 * std::abs(r) + options.arc_radius_tolerance)
        error(w.col('R'), "arc radius " + format_number(std::abs(r)) +
                              " is too small for its chord of " + format_number(d));
      double h = std::sqrt(std::max(0.0, r * r - d * d / 4));
      Vec2 dir = (e - s) / d;
      Vec2 left(-dir.y, dir.x);
      // The shorter arc (R > 0) turns around a centre on its inner side: left of the chord for
      // counter-clockwise motion.
      bool centre_left = ccw == (r > 0);
      c = 0.5 * (s + e) + (centre_left ? h : -h) * left;
      r0 = glm::length(s - c);
      r1 = glm::length(e - c);
    }
    double a0 = std::atan2(s.y - c.y, s.x - c.x);
    double a1 = std::atan2(e.y - c.y, e.x - c.x);
    double sweep = ccw ? a1 - a0 : a0 - a1;
    if (glm::length(e - s) <= 1e-9) {
      sweep = 2 * kPi;  // start == end: a full circle
    } else {
      while (sweep <= 0) sweep += 2 * kPi;
      while (sweep > 2 * kPi) sweep -= 2 * kPi;
    }
    double r = std::max(r0, r1);
    long long pieces = 1;
    if (r > options.arc_tolerance) {
      double step = 2 * std::acos(1 - options.arc_tolerance / r);
      double count = std::ceil(sweep / step);
      if (!(count <= static_cast<double>(kMaxArcPieces)))
        error(motion_column, "arc of radius " + format_number(r) + " needs more than " +
                                 std::to_string(kMaxArcPieces) + " pieces at this tolerance");
      pieces = std::max(1LL, static_cast<long long>(count));
    }
    double sign = ccw ? 1.0 : -1.0;
    Vec3 previous = pos;
    for (long long k = 1; k <= pieces; ++k) {
      Vec3 p = end;
      if (k < pieces) {
        double t = static_cast<double>(k) / static_cast<double>(pieces);
        double angle = a0 + sign * sweep * t;
        double radius = r0 + (r1 - r0) * t;
        p[u] = c.x + radius * std::cos(angle);
        p[v] = c.y + radius * std::sin(angle);
        p[n] = start[n] + (end[n] - start[n]) * t;
      }
      Vec3 m = to_machine(p);
      emit(MoveKind::arc, previous, m, feed);
      previous = m;
    }
    pos = to_machine(end);
  }

  // ---- canned cycles ----
  void cycle(int code) {
    const std::array<int, 3> axes = plane_axes(plane);
    const int u = axes[0], v = axes[1], n = axes[2];
    Vec3 drill = rotation[n];  // cycle axis in machine coordinates
    if (glm::dot(drill, axis) < 1 - 1e-9)
      error(motion_column, code_name('G', code) + " drills along the " + code_name('G', plane) +
                               " plane normal, which is not the spindle direction");
    char depth_letter = kAxisLetter[n];
    if (w.has('R')) {
      cycle_r = length('R');
      has_cycle_r = true;
    }
    if (w.has(depth_letter)) {
      cycle_z = length(depth_letter);
      has_cycle_z = true;
    }
    if (code == 730 || code == 830) {
      if (w.has('Q')) {
        cycle_q = length('Q');
        has_cycle_q = true;
      }
      if (!has_cycle_q || !(cycle_q > 0))
        error(motion_column, code_name('G', code) + " needs a positive peck depth Q");
    }
    if ((code == 820 || code == 860 || code == 890) && w.has('P')) {
      if (w.take('P') < 0) error(w.col('P'), "dwell P must not be negative");
    }
    if (!has_cycle_r) error(motion_column, code_name('G', code) + " needs R (retract plane)");
    if (!has_cycle_z)
      error(motion_column, code_name('G', code) + " needs " + depth_letter + " (hole bottom)");
    require_feed();
    if (w.has('L') && w.has('K')) error(w.col('K'), "repeat count given twice (L and K)");
    long long repeats = 1;
    if (w.has('L')) repeats = integer('L', "repeat count", 0, 9999);
    if (w.has('K')) repeats = integer('K', "repeat count", 0, 9999);

    Vec3 current = to_program(pos);
    if (!cycle_active) {
      cycle_active = true;
      cycle_initial_far = far;
      cycle_initial = current[n];
    }
    if (far && incremental)
      error(motion_column, "incremental canned cycle from a retracted (far) position");
    double r_level = incremental ? current[n] + cycle_r : cycle_r;
    double bottom = incremental ? r_level + cycle_z : cycle_z;
    if (bottom > r_level)
      error(motion_column, "hole bottom " + format_number(bottom) + " is above the R plane " +
                               format_number(r_level));
    if (code == 730 || code == 830) {
      // A real control pecks a hole a few hundred times at most; a tiny Q against a deep hole
      // (or a far R plane) would emit moves without end, and below one ulp would never finish.
      constexpr double kMaxPecks = 100000;
      double pecks = (r_level - bottom) / cycle_q;
      if (!(pecks <= kMaxPecks))
        error(motion_column, code_name('G', code) + " would peck " + format_number(pecks) +
                                 " times (R " + format_number(r_level) + " to " + format_number(bottom) +
                                 " by Q " + format_number(cycle_q) + "); at most 100000 per hole");
    }
    bool clear_far = !retract_to_r && cycle_initial_far;
    double clear = retract_to_r ? r_level : std::max(cycle_initial, r_level);
    if (clear_far) clear = r_level;

    // Lateral target of the first hole; increments repeat under G91.
    double du = w.has(kAxisLetter[u]) ? length(kAxisLetter[u]) : 0.0;
    double dv = w.has(kAxisLetter[v]) ? length(kAxisLetter[v]) : 0.0;
    double hole_u = incremental ? current[u] : (w.has(kAxisLetter[u]) ? du : current[u]);
    double hole_v = incremental ? current[v] : (w.has(kAxisLetter[v]) ? dv : current[v]);

    auto at = [&](double uu, double vv, double depth) {
      Vec3 p;
      p[u] = uu;
      p[v] = vv;
      p[n] = depth;
      return to_machine(p);
    };
    auto rapid = [&](const Vec3& to) {
      emit(MoveKind::cycle, pos, to, 0.0);
      pos = to;
    };
    auto cut = [&](const Vec3& to) {
      emit(MoveKind::cycle, pos, to, feed);
      pos = to;
    };
    if (!far && current[n] < r_level - 1e-9) rapid(at(current[u], current[v], r_level));
    for (long long k = 0; k < repeats; ++k) {
      if (incremental) {
        hole_u += du;
        hole_v += dv;
      }
      if (far) {
        // Come back from far straight down the axis onto the R plane of the hole.
        Vec3 r_point = at(hole_u, hole_v, r_level);
        emit(MoveKind::cycle, r_point + machine.far_distance * axis, r_point, 0.0);
        pos = r_point;
        far = false;
      } else {
        Vec3 level = to_program(pos);
        rapid(at(hole_u, hole_v, level[n]));
        rapid(at(hole_u, hole_v, r_level));
      }
      double d = options.peck_clearance;
      switch (code) {
        case 730:
          for (double depth = r_level - cycle_q; depth > bottom; depth -= cycle_q) {
            cut(at(hole_u, hole_v, depth));
            rapid(at(hole_u, hole_v, depth + d));
          }
          cut(at(hole_u, hole_v, bottom));
          break;
        case 830:
          for (double depth = r_level - cycle_q; depth > bottom; depth -= cycle_q) {
            cut(at(hole_u, hole_v, depth));
            rapid(at(hole_u, hole_v, r_level));
            rapid(at(hole_u, hole_v, depth + d));
          }
          cut(at(hole_u, hole_v, bottom));
          break;
        case 850:  // out at feed to R (then rapid to the clear level)
          cut(at(hole_u, hole_v, bottom));
          cut(at(hole_u, hole_v, r_level));
          break;
        case 890:  // out at feed all the way to the clear level, as LinuxCNC does
          cut(at(hole_u, hole_v, bottom));
          cut(at(hole_u, hole_v, clear_far ? r_level : clear));
          break;
        default:  // 810, 820, 860: down at feed, out at rapid
          cut(at(hole_u, hole_v, bottom));
          break;
      }
      Vec3 out = at(hole_u, hole_v, clear);
      if (out != pos) rapid(out);
      if (clear_far) far = true;
    }
  }

  // ---- returns and machine-coordinate moves ----
  // The machine's Z is the spindle's own axis (on a table-tilting machine it stays along the tool
  // in the work frame; on a head-tilting one it retracts the head), so a machine-coordinate move
  // of Z is a retract: the tip goes far along the tool axis. X/Y alone move the tip in machine
  // coordinates, which is only unambiguous with the tool along +Z.
  void machine_move(const Vec3& target, unsigned mask, MoveKind kind, double move_feed) {
    Vec3 end = pos;
    for (int i = 0; i < 3; ++i)
      if ((mask >> i) & 1u) end[i] = target[i];
    if ((mask & 4u) || far) {
      pos = end;
      far = true;
      return;
    }
    if (glm::dot(axis, Vec3(0, 0, 1)) < 1 - kSameDirection)
      error(motion_column, "G53 X/Y with a tilted tool depends on the machine's kinematics; "
                           "retract with G53 Z (or G28) first");
    emit(kind, pos, end, move_feed);
    pos = end;
  }

  void home_return(bool second) {
    int column = w.find_g(second ? 300 : 280);
    if (second && w.has('P')) {
      if (integer('P', "G30 reference number", 2, 2) != 2) error(w.col('P'), "only G30 P2");
    }
    unsigned mask = 0;
    for (int i = 0; i < 3; ++i)
      if (w.has(kAxisLetter[i])) mask |= 1u << i;
    bool rotary = w.has('A') || w.has('B') || w.has('C');
    if (mask) linear(MoveKind::rapid, 0.0);  // the intermediate point
    if (!mask && !rotary) mask = 7;
    const Vec3& target = second ? machine.reference2 : machine.home;
    bool is_default = second ? machine.reference2_is_default : machine.home_is_default;
    bool& warned = second ? warned_reference2 : warned_home;
    if (is_default && !warned) {
      warn(column, std::string(second ? "G30" : "G28") +
                       " uses the default reference position (far above the work along +Z); "
                       "set it in the machine configuration if the machine differs");
      warned = true;
    }
    // With the tool along +Z, returning X/Y only is a plain rapid at the current height (on any
    // machine). Anything else is a retract: the tip goes far along the tool axis, the homed
    // axes' coordinates kept for the lateral position.
    if (mask && !(mask & 4u) && !rotary && !far &&
        glm::dot(axis, Vec3(0, 0, 1)) >= 1 - kSameDirection) {
      machine_move(target, mask, MoveKind::rapid, 0.0);
      return;
    }
    for (int i = 0; i < 3; ++i)
      if ((mask >> i) & 1u) pos[i] = target[i];
    far = true;
    if (rotary) {
      // Rotary axes home: the spindle returns to the machine's +Z, and the tip goes far.
      for (char c : {'A', 'B', 'C'})
        if (w.has(c)) w.take(c);
      axis = Vec3(0, 0, 1);
      far = true;
      update_frame();
    }
  }

  void go_far() { far = true; }

  // ---- one block ----
  Flow execute(const Block& block);
};

Flow Interpreter::State::execute(const Block& block) {
  gather(block);
  motion_column = 0;
  int motion_code = -1, nonmodal = -1, tilt = -1, orient = -1;
  for (int i = 0; i < w.g_count; ++i) {
    const Code& g = w.g[static_cast<std::size_t>(i)];
    int group = g_group(g.code);
    if (group == kMotion) {
      motion_code = g.code;
      motion_column = g.column;
    } else if (group == kNonModal) {
      nonmodal = g.code;
      if (g.code != 40) motion_column = g.column;
    } else if (group == kTilt) {
      tilt = g.code;
    } else if (group == kOrient) {
      orient = g.code;
    }
  }
  if (motion_column == 0) {
    motion_column = 1;
    for (char c : {'X', 'Y', 'Z'})
      if (w.has(c)) {
        motion_column = w.col(c);
        break;
      }
  }

  // Units first, so that every length in this block is read in them.
  if (w.find_g(200)) unit = 25.4;
  if (w.find_g(210)) unit = 1.0;

  if (w.has('F')) {
    double f = length('F');
    if (f < 0) error(w.col('F'), "feed rate F must not be negative");
    feed = f;
  }
  if (w.has('S')) {
    double s = w.take('S');
    if (s < 0) error(w.col('S'), "spindle speed S must not be negative");
    speed = s;
  }
  if (w.has('T')) tool_selected = static_cast<int>(integer('T', "tool number", 0, 99'999'999));

  if (w.find_m(6)) {
    tool = tool_selected;
    tool_first_line.emplace(tool, line);
    if (options.tool_change_retracts) go_far();
  }
  if (w.find_m(3)) spindle_direction = 1;
  if (w.find_m(4)) spindle_direction = -1;
  if (w.find_m(5)) spindle_direction = 0;

  if (nonmodal == 40) {  // dwell: P (seconds or ms) or, on Fanuc, X
    if (w.has('P') && w.has('X')) error(w.col('X'), "G4 with both P and X");
    char c = w.has('P') ? 'P' : w.has('X') ? 'X' : 0;
    if (!c) error(w.find_g(40), "G4 needs a dwell time P");
    if (w.take(c) < 0) error(w.col(c), "dwell time must not be negative");
    if (c == 'X') w.present &= ~(1u << letter_index('X'));  // a time here, not a coordinate
  }

  for (int code : {170, 180, 190})
    if (w.find_g(code)) plane = code;
  if (w.find_g(900)) incremental = false;
  if (w.find_g(910)) incremental = true;
  if (w.find_g(901)) arc_absolute = true;
  if (w.find_g(911)) arc_absolute = false;
  if (w.find_g(430) || w.find_g(440)) {
    if (w.has('H')) integer('H', "tool length offset number", 0, 99'999'999);
  }
  // Look-ahead and smoothing modes change how the control follows the path, not the path.
  if (w.find_g(51)) {
    for (char c : {'Q', 'R'})
      if (w.has(c)) w.take(c);
  }
  if (w.find_g(80) && w.has('P')) w.take('P');
  if (w.find_g(1870)) {
    for (char c : {'P', 'E'})
      if (w.has(c)) w.take(c);
  }
  if (w.find_g(640)) {  // path blending tolerances (LinuxCNC G64 P Q): no effect on the path
    if (w.has('P')) w.take('P');
    if (w.has('Q')) w.take('Q');
  }
  if (w.find_g(980)) retract_to_r = false;
  if (w.find_g(990)) retract_to_r = true;

  // Work coordinate system.
  for (int code : {540, 550, 560, 570, 580, 590, 541}) {
    int column = w.find_g(code);
    if (!column) continue;
    int key = code == 541 ? 0 : (code - 540) / 10 + 1;
    if (code == 541) {
      if (!w.has('P')) error(column, "G54.1 needs P (1-300)");
      key = MachineConfig::g54_1_key(static_cast<int>(integer('P', "G54.1 number", 1, 300)));
    }
    if (tilted && key != work_key)
      error(column, "work coordinates change while a tilted plane is active (cancel it first)");
    work_key = key;
    auto it = offsets.find(key);
    work_offset = it == offsets.end() ? Vec3(0.0) : it->second;
    update_frame();
  }

  bool axis_consumer = false;  // a code other than motion that takes X/Y/Z
  if (nonmodal == 100) {
    axis_consumer = true;
    int column = w.find_g(100);
    if (!w.has('L')) error(column, "G10 needs L2 or L20");
    long long l = integer('L', "G10 L", 0, 99);
    if (l != 2 && l != 20) {
      unsupported(column, "G10 L" + std::to_string(l) + " is not supported (only L2 and L20)");
    } else {
      if (!w.has('P')) error(column, "G10 L" + std::to_string(l) + " needs P");
      int key = l == 2 ? static_cast<int>(integer('P', "G10 L2 P", 1, 6))
                       : MachineConfig::g54_1_key(static_cast<int>(integer('P', "G10 L20 P", 1, 300)));
      if (incremental)
        error(column, "G10 under G91 is read differently by different controls; use G90");
      Vec3 value = offsets.count(key) ? offsets[key] : Vec3(0.0);
      for (int i = 0; i < 3; ++i)
        if (w.has(kAxisLetter[i])) value[i] = length(kAxisLetter[i]);
      offsets[key] = value;
      if (key == work_key) {
        if (tilted) error(column, "G10 changes the active work offset under a tilted plane");
        work_offset = value;
        update_frame();
      }
    }
  }

  // Tilted working plane.
  if (tilt == 690 || tilt == 2690) {
    tilted = false;
    update_frame();
  } else if (tilt == 682 || tilt == 2680) {
    axis_consumer = true;
    int column = w.find_g(tilt);
    if (incremental) error(column, code_name('G', tilt) + " under G91 is not supported; use G90");
    if (tilt == 682 && w.has('P') && integer('P', "G68.2 P", 0, 3) != 0)
      unsupported(w.col('P'), "G68.2 P1/P2/P3 (other angle conventions) are not supported");
    if (tilt == 2680 && w.has('Q') && integer('Q', "G268 Q", 0, 999) != 123)
      unsupported(w.col('Q'), "G268 rotation order other than Q123 is not supported");
    Vec3 o(0.0);
    for (int i = 0; i < 3; ++i)
      if (w.has(kAxisLetter[i])) o[i] = length(kAxisLetter[i]);
    double a = w.has('I') ? w.take('I') : 0.0;
    double b = w.has('J') ? w.take('J') : 0.0;
    double c = w.has('K') ? w.take('K') : 0.0;
    // The feature frame sits on the active work coordinate system.
    tilt_rotation = tilt == 682 ? rotation_z(a) * rotation_x(b) * rotation_z(c)
                                : rotation_z(c) * rotation_y(b) * rotation_x(a);
    tilt_origin = work_offset + o;
    tilted = true;
    tilt_line = line;
    update_frame();
  }
  if (orient >= 0) {
    int column = w.find_g(orient);
    if (!tilted)
      error(column, code_name('G', orient) + " without an active G68.2/G268 tilted plane");
    Vec3 direction = glm::normalize(tilt_rotation[2]);
    if (glm::dot(direction, axis) < 1 - kSameDirection) {
      axis = direction;
      go_far();  // the machine turns the tool: where the tip ends is the kinematics' business
    }
    update_frame();
  }

  // Motion.
  if (motion_code >= 0) {
    if (axis_consumer && motion_code != 800)
      error(motion_column, code_name('G', motion_code) +
                               " in a block whose X/Y/Z belong to another code");
    if (motion_code == 800 || !is_cycle(motion_code)) cycle_active = false;
    if (is_cycle(motion_code) && motion != motion_code) cycle_active = false;
    motion = motion_code;
  }
  if (nonmodal == 280 || nonmodal == 300) {
    if (motion_code >= 0 && motion_code != 800)
      error(motion_column, "G28/G30 with a motion code in the same block");
    home_return(nonmodal == 300);
  } else if (nonmodal == 530) {
    if (motion != 0 && motion != 10)
      error(motion_column, "G53 needs G0 or G1 modal");
    if (motion == 10) require_feed();
    Vec3 target(0.0);
    unsigned mask = 0;
    for (int i = 0; i < 3; ++i)
      if (w.has(kAxisLetter[i])) {
        target[i] = length(kAxisLetter[i]);
        mask |= 1u << i;
      }
    if (mask)
      machine_move(target, mask, motion == 0 ? MoveKind::rapid : MoveKind::feed,
                   motion == 0 ? 0.0 : feed);
  } else if (!axis_consumer) {
    bool axes = has_axis_words();
    if (motion == 0 || motion == 10) {
      if (axes) {
        if (motion == 10) require_feed();
        linear(motion == 0 ? MoveKind::rapid : MoveKind::feed, motion == 0 ? 0.0 : feed);
      }
    } else if (motion == 20 || motion == 30) {
      char cu = kCenterLetter[plane_axes(plane)[0]], cv = kCenterLetter[plane_axes(plane)[1]];
      if (axes || motion_code >= 0 || w.has(cu) || w.has(cv) || w.has('R')) arc(motion == 30);
    } else if (is_cycle(motion)) {
      if (axes || motion_code >= 0 || w.has('R')) cycle(motion);
    } else if (axes) {
      error(motion_column, "X/Y/Z without an active motion mode (G0, G1, G2, G3 or a cycle)");
    }
  }

  // Program flow last.
  Flow flow = Flow::next;
  if (w.find_m(2) || w.find_m(30)) flow = Flow::end;
  if (int column = w.find_m(98)) {
    if (!w.has('P')) error(column, "M98 needs P (the O number to call)");
    call_label = static_cast<int>(integer('P', "M98 P", 0, 999'999'999));
    if (w.has('L') && w.has('K')) error(w.col('K'), "repeat count given twice (L and K)");
    call_repeats = 1;
    if (w.has('L')) call_repeats = integer('L', "M98 repeat count", 0, 9999);
    if (w.has('K')) call_repeats = integer('K', "M98 repeat count", 0, 9999);
    flow = Flow::call;
  }
  if (w.find_m(99)) flow = Flow::ret;

  // Every word must have been used by some code of the block: never a silent misreading.
  std::uint32_t free_words = w.present & ~w.used;
  for (char c : {'F', 'S', 'T', 'O'}) free_words &= ~(1u << letter_index(c));
  if (free_words) {
    for (int i = 0; i < 26; ++i) {
      if (!((free_words >> i) & 1u)) continue;
      char c = static_cast<char>('A' + i);
      std::size_t k = static_cast<std::size_t>(i);
      bool axis_letter = c == 'X' || c == 'Y' || c == 'Z';
      if (axis_letter) continue;  // axis words are consumed by construction or rejected above
      unsupported(w.column[k], std::string("word ") + c + format_number(w.value[k]) +
                                   " is not used by any code in this block");
    }
  }
  return flow;
}

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
