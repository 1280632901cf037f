// Differential test against LinuxCNC's interpreter (Debian package linuxcnc-uspace, `rs274`).
//
// rs274 prints the canonical machining calls of a program: STRAIGHT_TRAVERSE, STRAIGHT_FEED and
// ARC_FEED with end points in the active work coordinate system and program units, to 4
// decimals. Those are turned into machine millimetres (with the SET_G5X_OFFSET and
// USE_LENGTH_UNITS calls it also prints) and compared with tridex's moves: one end point per
// straight move, one per arc (the last of its chords), zero-length moves dropped on both sides.
// Agreement is to rs274's printed precision: 0.5e-4 program units plus 1e-6.
// A G5/G5.1 spline is printed as NURBS_FEED without its points (the pieces are made by the
// controller, not the interpreter): it stands for the moves tridex makes of that block, and the
// corpus programs reveal where each spline ended with the move that follows it.
#include <doctest/doctest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <random>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <unistd.h>
#include <vector>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
namespace fs = std::filesystem;

namespace {

struct Point {
  Vec3 p;
  double tolerance;     // mm
  int record;           // rs274 output line, or source line for tridex
  bool chord = false;   // tridex: a chord end inside an arc (see compare_paths)
  bool spline = false;  // rs274: a NURBS_FEED, which prints no point
};

bool rs274_available() { return std::system("command -v rs274 > /dev/null 2>&1") == 0; }

std::vector<double> arguments(const std::string& line, std::size_t open) {
  std::vector<double> values;
  const char* p = line.c_str() + open + 1;
  while (*p && *p != ')') {
    char* end = nullptr;
    double v = std::strtod(p, &end);
    if (end == p) break;
    values.push_back(v);
    p = end;
    while (*p == ',' || *p == ' ') ++p;
  }
  return values;
}

void push(std::vector<Point>& points, const Point& point) {
  auto last =
      std::find_if(points.rbegin(), points.rend(), [](const Point& q) { return !q.spline; });
  Vec3 previous = last == points.rend() ? Vec3(0.0) : last->p;
  if (glm::length(point.p - previous) > 1e-9) points.push_back(point);
}

// rs274 run standalone without -t loads its own tool table (the same as LinuxCNC's sample
// sim.tbl): T1 0.511 in long, T2 0.1 in, T3 1.273 in, T98876 0.1 in. In mm:
const std::map<int, double> kRs274ToolLengths{
    {1, 0.511 * 25.4}, {2, 0.1 * 25.4}, {3, 1.273 * 25.4}, {98876, 0.1 * 25.4}};

// rs274 keeps its tool table in $HOME/.tool.mmap (LinuxCNC 2.9 tooldata_mmap.cc): two runs at
// once under one HOME (ctest runs test processes side by side) read each other's tools or die of
// a bus error and print nothing, so each test process gives it a HOME of its own.
fs::path rs274_home() {
  fs::path home = fs::temp_directory_path() / ("tridex_rs274_home_" + std::to_string(::getpid()));
  fs::create_directories(home);
  return home;
}

// `tool_table`: a LinuxCNC tool table for -t (standalone rs274 reads its diameters in inches);
// `tool_lengths` (mm) the lengths it holds. rs274 prints the controlled point: the tip of a tool
// as long as the active offset (USE_TOOL_LENGTH_OFFSET, program units). tridex follows the tip of
// the tool in the spindle (CHANGE_TOOL), which lies (offset − its length) from that point.
std::vector<Point> run_rs274(const fs::path& program, std::string& log,
                             const fs::path& tool_table = {},
                             const std::map<int, double>& tool_lengths = kRs274ToolLengths) {
  fs::path out = fs::temp_directory_path() /
                 ("tridex_rs274_" + std::to_string(::getpid()) + "_" + program.filename().string());
  std::string tools = tool_table.empty() ? "" : "-t '" + tool_table.string() + "' ";
  const fs::path home = rs274_home();
  std::string command = "HOME='" + home.string() + "' rs274 " + tools + "-g '" + program.string() +
                        "' '" + out.string() + "' < /dev/null > '" + out.string() + ".log' 2>&1";
  int status = std::system(command.c_str());
  (void)status;  // rs274 exits 0 even on interpreter errors; its log is checked instead
  std::ifstream log_in(out.string() + ".log");
  log.assign(std::istreambuf_iterator<char>(log_in), {});
  std::ifstream in(out);
  std::vector<Point> points;
  double scale = 1;
  Vec3 offset(0.0);                             // mm, G5x
  Vec3 local(0.0);                              // mm, G92 / G52
  double length_offset = 0, loaded_length = 0;  // mm
  Vec3 last_controlled(0.0);
  double last_length_offset = 0;  // at the last point printed
  char plane = 'Z';               // XY: Z, XZ: Y, YZ: X (the arc's axis)
  std::string line;
  int record = 0;
  while (std::getline(in, line)) {
    ++record;
    std::size_t at;
    if (line.find("USE_LENGTH_UNITS(CANON_UNITS_INCHES") != std::string::npos) scale = 25.4;
    if (line.find("USE_LENGTH_UNITS(CANON_UNITS_MM") != std::string::npos) scale = 1;
    if (line.find("SELECT_PLANE(CANON_PLANE_XY") != std::string::npos) plane = 'Z';
    if (line.find("SELECT_PLANE(CANON_PLANE_XZ") != std::string::npos) plane = 'Y';
    if (line.find("SELECT_PLANE(CANON_PLANE_YZ") != std::string::npos) plane = 'X';
    if ((at = line.find("SET_G5X_OFFSET(")) != std::string::npos) {
      auto v = arguments(line, line.find('(', at));
      REQUIRE(v.size() >= 4);
      offset = Vec3(v[1], v[2], v[3]) * scale;
    }
    if ((at = line.find("SET_G92_OFFSET(")) != std::string::npos) {
      auto v = arguments(line, line.find('(', at));
      REQUIRE(v.size() >= 3);
      local = Vec3(v[0], v[1], v[2]) * scale;
    }
    if ((at = line.find("USE_TOOL_LENGTH_OFFSET(")) != std::string::npos) {
      auto v = arguments(line, line.find('(', at));
      REQUIRE(v.size() >= 3);
      length_offset = v[2] * scale;
    }
    // M6 prints CHANGE_TOOL, M61 Q CHANGE_TOOL_NUMBER: either way that tool is in the spindle.
    if ((at = line.find("CHANGE_TOOL(")) != std::string::npos ||
        (at = line.find("CHANGE_TOOL_NUMBER(")) != std::string::npos) {
      auto v = arguments(line, line.find('(', at));
      REQUIRE(v.size() >= 1);
      auto it = tool_lengths.find(static_cast<int>(v[0]));
      loaded_length = it == tool_lengths.end() ? 0.0 : it->second;
    }
    if (line.find("NURBS_FEED(") != std::string::npos) {
      points.push_back(Point{Vec3(0.0), 0, record, false, true});
      continue;
    }
    // rs274 standalone's probe reaches its point and stops 0.254 mm (0.01 in) back towards its
    // start (saicanon.cc STRAIGHT_PROBE): two points.
    bool probe = false;
    Vec3 p;
    if ((at = line.find("STRAIGHT_TRAVERSE(")) != std::string::npos ||
        (at = line.find("STRAIGHT_FEED(")) != std::string::npos ||
        (probe = (at = line.find("STRAIGHT_PROBE(")) != std::string::npos)) {
      auto v = arguments(line, line.find('(', at));
      REQUIRE(v.size() >= 3);
      p = Vec3(v[0], v[1], v[2]);
    } else if ((at = line.find("ARC_FEED(")) != std::string::npos) {
      auto v = arguments(line, line.find('(', at));
      REQUIRE(v.size() >= 6);
      // (first_end, second_end, first_centre, second_centre, turns, axis_end): XY: X Y Z;
      // XZ: Z X Y; YZ: Y Z X.
      if (plane == 'Z') p = Vec3(v[0], v[1], v[5]);
      if (plane == 'Y') p = Vec3(v[1], v[5], v[0]);
      if (plane == 'X') p = Vec3(v[5], v[0], v[1]);
    } else {
      continue;
    }
    // rs274 prints a block with no axis words under G0 as a move to where it is: dropped here
    // by the printed point, which (unlike the tip) starts at the origin as tridex's first point.
    Vec3 controlled = p * scale + offset + local;
    Vec3 from = last_controlled;  // in mm, as saicanon keeps it across offset and unit changes
    for (int piece = 0; piece < (probe ? 2 : 1); ++piece) {
      if (piece == 1) {
        double distance = glm::length(from - controlled);
        if (distance == 0) break;
        controlled += 0.254 * (from - controlled) / distance;  // 0.01 in = 0.254 mm
      }
      // A move to where the controlled point is moves the axes when the tool length offset
      // changed since (cone.ngc's `g43.1 z#1` then `g0 z0`); a tool change alone moves nothing.
      bool offset_changed = length_offset != last_length_offset;
      last_length_offset = length_offset;
      if (glm::length(controlled - last_controlled) <= 1e-9 && !offset_changed) continue;
      last_controlled = controlled;
      push(points, Point{controlled + Vec3(0, 0, length_offset - loaded_length),
                         0.5e-4 * scale + 1e-6, record});
    }
  }
  fs::remove(out);
  fs::remove(out.string() + ".log");
  fs::remove_all(home);
  return points;
}

// `tool_diameters`: the tool table for G41/G42 D (mm). With `chords`, every chord of an arc is a
// point (marked `chord`, its last one not); without, only the end of each arc.
std::vector<Point> run_tridex(const fs::path& program,
                              const std::map<int, double>& tool_diameters = {}, bool chords = false,
                              const std::map<int, double>& tool_lengths = kRs274ToolLengths) {
  InterpreterOptions options;
  options.block_delete = false;  // rs274's block-delete switch is off by default
  std::vector<Point> points;
  std::ifstream in(program, std::ios::binary);
  REQUIRE(in);
  MachineConfig machine = *MachineConfig::bundled("rs274");
  machine.tool_diameters = tool_diameters;
  machine.tool_lengths = tool_lengths;
  Interpreter interpreter(options, machine);
  Move last_arc;
  bool in_arc = false;
  auto flush = [&] {
    if (in_arc) push(points, Point{last_arc.end, 0, last_arc.line});
    in_arc = false;
  };
  interpreter.run(in, program.string(), [&](const Move& m) {
    // A move that leaves the tip where it is (`G0 Z#1` back to where it is, after a tool change
    // that moved the tip to the new tool's length) is dropped, as rs274's to where it is: the
    // tip's last point before it belongs to the previous tool (tcdemo.ngc's `T3 M6`).
    if (m.start == m.end) return;
    if (chords) {
      push(points, Point{m.end, 0, m.line, m.kind == MoveKind::arc});
      return;
    }
    if (m.kind == MoveKind::arc) {
      if (in_arc && m.line != last_arc.line) flush();
      last_arc = m;
      in_arc = true;
      return;
    }
    flush();
    push(points, Point{m.end, 0, m.line});
  });
  flush();
  return points;
}

std::vector<fs::path> corpus() {
  std::vector<fs::path> files;
  for (const auto& entry :
       fs::directory_iterator(fs::path(TRIDEX_TEST_DATA) / "gcode" / "linuxcnc"))
    if (entry.path().extension() == ".ngc") files.push_back(entry.path());
  // Programs written by others (tests/data/gcode/public: a hobby mill's Fusion 360 output).
  for (const auto& entry :
       fs::recursive_directory_iterator(fs::path(TRIDEX_TEST_DATA) / "gcode" / "public"))
    if (entry.path().extension() == ".nc") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  // LinuxCNC's own sample programs that use only codes both interpreters support.
  if (const char* only = std::getenv("TRIDEX_DIFF_ONLY")) {  // ad-hoc: one program
    files.assign(1, fs::path(only));
    return files;
  }
  // b-index and daisy turn B and A, plain axes on LinuxCNC without kinematics: X/Y/Z agree
  // (daisy under G93 inverse time). cone.ngc has a test of its own (its W words).
  for (const char* name : {"3D_Chips.ngc", "3dtest.ngc", "arcspiral.ngc", "b-index.ngc", "cds.ngc",
                           "daisy.ngc", "flowsnake.ngc", "hole-circle.ngc", "lathe_pawn.ngc",
                           "plasmatest.ngc", "polar.ngc", "spiral.ngc", "tort.ngc"})
    files.push_back(fs::path("/usr/share/linuxcnc/ncfiles") / name);
  // Text engraved with G5.1 splines, two tools of different lengths changed between rapids. It
  // is one of linuxcnc-uspace's documentation examples, which an image that leaves out
  // /usr/share/doc does not have.
  const fs::path tcdemo =
      "/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/remap/"
      "manual-toolchange-with-tool-length-switch/nc_files/tcdemo.ngc";
  if (fs::exists(tcdemo)) files.push_back(tcdemo);
  return files;
}

// A random 3-axis program: rapids, feeds, arcs (I/J/K and R, all planes, helical), units,
// distance modes and drilling cycles, all with exact 4-decimal coordinates.
std::string random_program(std::mt19937_64& rng) {
  using tridex::gcode::test::cat;
  using tridex::gcode::test::fmt;
  std::uniform_real_distribution<double> u01(0, 1);
  auto coord = [&](double span) { return std::round((u01(rng) * 2 - 1) * span * 1e4) / 1e4; };
  std::string text = "G21 G90 G17 F300 S1000 M3\nG0 X0 Y0 Z10\n";
  Vec3 p(0, 0, 10);
  for (int i = 0; i < 60; ++i) {
    int kind = static_cast<int>(rng() % 10);
    if (kind < 4) {
      Vec3 q(coord(50), coord(50), coord(10));
      text += cat(kind == 0 ? "G0" : "G1", " X", fmt(q.x), " Y", fmt(q.y), " Z", fmt(q.z), "\n");
      p = q;
    } else if (kind < 6) {
      // Incremental feed.
      Vec3 d(coord(5), coord(5), coord(1));
      text += cat("G91 G1 X", fmt(d.x), " Y", fmt(d.y), " Z", fmt(d.z), "\nG90\n");
      p += Vec3(std::stod(fmt(d.x)), std::stod(fmt(d.y)), std::stod(fmt(d.z)));
    } else if (kind < 9) {
      // An arc in a random plane: the centre offset and the end on the same circle (as printed
      // to 4 decimals the radii differ by < 1e-4, within both interpreters' tolerance).
      int plane = static_cast<int>(rng() % 3);
      int a = plane == 0 ? 0 : plane == 1 ? 2 : 1, b = plane == 0 ? 1 : plane == 1 ? 0 : 2;
      int n = 3 - a - b;
      const char* letters = "IJK";
      const char* axes = "XYZ";
      double r = 1 + u01(rng) * 20, start_angle = u01(rng) * 6.283, sweep = 0.2 + u01(rng) * 5.8;
      bool ccw = rng() % 2;
      Vec2 centre(p[a] - r * std::cos(start_angle), p[b] - r * std::sin(start_angle));
      double end_angle = start_angle + (ccw ? sweep : -sweep);
      Vec3 e = p;
      e[a] = std::stod(fmt(centre.x + r * std::cos(end_angle)));
      e[b] = std::stod(fmt(centre.y + r * std::sin(end_angle)));
      if (rng() % 3 == 0) e[n] = std::stod(fmt(p[n] - u01(rng) * 3));
      std::string words = cat(plane == 0 ? "G17" : plane == 1 ? "G18" : "G19", ccw ? " G3" : " G2");
      for (int k = 0; k < 3; ++k) words += cat(" ", axes[k], fmt(e[k]));
      if (rng() % 2 || sweep > 6.0) {
        words += cat(" ", letters[a], fmt(centre.x - p[a]), " ", letters[b], fmt(centre.y - p[b]));
      } else {
        double chord_r = glm::length(Vec2(e[a], e[b]) - Vec2(p[a], p[b])) / 2;
        double radius = std::max(std::stod(fmt(r)), chord_r);  // printable, never too short
        words += cat(" R", fmt(sweep > 3.14159265 ? -radius : radius));
      }
      text += words + "\nG17\n";
      p = e;
      if (words.find(" R") != std::string::npos) {  // R arcs: refetch where it really ended
        text += cat("G0 X", fmt(p.x), " Y", fmt(p.y), " Z", fmt(p.z), "\n");
      }
    } else {
      double r_level = std::round(u01(rng) * 30) / 10, bottom = -std::round(u01(rng) * 80) / 10;
      const char* cycles[] = {"G81", "G82 P0.1", "G83 Q1.5", "G73 Q0.7", "G85", "G86 P0", "G89 P0"};
      text += cat(rng() % 2 ? "G98 " : "G99 ", cycles[rng() % 7], " X", fmt(coord(40)), " Y",
                  fmt(coord(40)), " Z", fmt(bottom), " R", fmt(r_level), "\nG80\n");
      text += cat("G0 X", fmt(p.x), " Y", fmt(p.y), " Z", fmt(p.z), "\n");
    }
  }
  return text + "M2\n";
}

// rs274 reports an interpreter error as "<line>: <message>" (or the message and the block) and
// stops: a corpus program must run to its end there, or the comparison would only cover a prefix.
bool rs274_stopped(const std::string& log) {
  for (std::size_t at = 0; at < log.size();) {
    std::size_t end = log.find('\n', at);
    std::string row = log.substr(at, end == std::string::npos ? std::string::npos : end - at);
    std::size_t digits = row.find_first_not_of("0123456789");
    if (digits > 0 && digits != std::string::npos && row.compare(digits, 2, ": ") == 0) return true;
    at = end == std::string::npos ? log.size() : end + 1;
  }
  return false;
}

// Runs rs274 and tridex on `program` and checks that every move end point agrees within rs274's
// printed precision, reporting at most `max_reports` disagreements; returns how many were compared
// and whether all agreed.
struct Comparison {
  std::size_t compared = 0;
  bool agreed = true;
};

// `ours`: the program tridex reads, when it is not the same (an rs274 refuses words of it).
Comparison compare_with_rs274(const fs::path& program, int max_reports,
                              const fs::path& ours_program = {}) {
  std::string log;
  std::vector<Point> theirs = run_rs274(program, log);
  std::vector<Point> ours = run_tridex(ours_program.empty() ? program : ours_program);
  INFO("rs274 log: " << log.substr(0, 600));
  CHECK_MESSAGE(!rs274_stopped(log), "rs274 stopped on an error");
  int reported = 0;
  std::size_t i = 0, j = 0, compared = 0;
  for (; i < theirs.size() && j < ours.size() && reported < max_reports; ++i) {
    if (theirs[i].spline) {  // every tridex move of the spline's block
      int spline_line = ours[j].record;
      while (j < ours.size() && ours[j].record == spline_line) ++j;
      continue;
    }
    Vec3 d = glm::abs(ours[j].p - theirs[i].p);
    if (std::max(d.x, std::max(d.y, d.z)) > theirs[i].tolerance) {
      ++reported;
      FAIL_CHECK("move " << compared << ": tridex (line " << ours[j].record << ") " << ours[j].p.x
                         << " " << ours[j].p.y << " " << ours[j].p.z << " vs rs274 (record "
                         << theirs[i].record << ") " << theirs[i].p.x << " " << theirs[i].p.y << " "
                         << theirs[i].p.z);
    }
    ++j;
    ++compared;
  }
  bool both_ended = reported > 0 || (i == theirs.size() && j == ours.size());
  CHECK_MESSAGE(both_ended, "tridex made " << ours.size() - j << " moves more, rs274 "
                                           << theirs.size() - i << " more");
  return {compared, reported == 0 && both_ended};
}

// Cutter compensation splits one block into a corner arc and its own arc, which rs274 prints as
// two ARC_FEEDs: so here every rs274 end point must be met, in order, by a tridex chord end, and
// the tridex points between them may only be chords inside arcs (never a straight move's end).
void compare_paths(const fs::path& program, const fs::path& tool_table,
                   const std::map<int, double>& tool_diameters) {
  std::string log;
  std::vector<Point> theirs = run_rs274(program, log, tool_table, {});  // tools.tbl: every Z is 0
  std::vector<Point> ours = run_tridex(program, tool_diameters, true, {});
  INFO("rs274 log: " << log.substr(0, 600));
  CHECK_MESSAGE(!rs274_stopped(log), "rs274 stopped on an error");
  std::size_t j = 0;
  bool ok = true;
  for (std::size_t i = 0; i < theirs.size() && ok; ++i) {
    auto near = [&](const Point& q) {
      Vec3 d = glm::abs(q.p - theirs[i].p);
      return std::max(d.x, std::max(d.y, d.z)) <= theirs[i].tolerance;
    };
    while (j < ours.size() && !near(ours[j])) {
      if (!ours[j].chord) {
        FAIL_CHECK("rs274 end point "
                   << i << " (record " << theirs[i].record << ") " << theirs[i].p.x << " "
                   << theirs[i].p.y << " " << theirs[i].p.z << ": tridex ends a move (line "
                   << ours[j].record << ") at " << ours[j].p.x << " " << ours[j].p.y << " "
                   << ours[j].p.z);
        ok = false;
        break;
      }
      ++j;
    }
    if (ok && j == ours.size()) {
      FAIL_CHECK("rs274 end point " << i << " (record " << theirs[i].record << ") never reached");
      ok = false;
    }
    ++j;
  }
  if (ok) CHECK_MESSAGE(j == ours.size(), "tridex moves on after rs274's last end point");
  MESSAGE(program.filename().string() << ": " << theirs.size() << " rs274 end points met");
}

// The diameters of a LinuxCNC tool table (`T<n> ... D<d>` a line, inches as rs274 standalone
// reads it), in mm: what tridex's --tools reads from the same file.
std::map<int, double> tbl_diameters(const fs::path& table) {
  std::map<int, double> diameters;
  std::ifstream in(table);
  REQUIRE(in);
  std::string line;
  while (std::getline(in, line)) {
    line = line.substr(0, line.find(';'));
    std::size_t t = line.find('T'), d = line.find(" D");
    if (t == std::string::npos || d == std::string::npos) continue;
    diameters[std::stoi(line.substr(t + 1))] = std::stod(line.substr(d + 2)) * 25.4;
  }
  return diameters;
}

}  // namespace

// LinuxCNC's sample programs with G41/G42, read in place (GPL: not copied), with a tool table of
// ours (sweep_tools.tbl) that both interpreters read: rs274 through -t, tridex as --tools would.
// TRIDEX_DIFF_COMP_ONLY=FILE runs one program this way (ad hoc).
TEST_CASE("differential: LinuxCNC's G41/G42 samples agree with rs274 given a tool table") {
  if (!rs274_available()) {
    MESSAGE(
        "SKIPPED: rs274 not found (install the Debian package linuxcnc-uspace); the LinuxCNC "
        "differential test did not run");
    return;
  }
  const fs::path table = fs::path(TRIDEX_TEST_DATA) / "gcode" / "linuxcnc" / "sweep_tools.tbl";
  std::vector<fs::path> programs;
  if (const char* only = std::getenv("TRIDEX_DIFF_COMP_ONLY")) {
    programs.assign(1, fs::path(only));
  } else {
    // lathecomp.ngc is a lathe's program, but its codes are a mill's (G18, G41/G42): with this
    // table's mill tools both interpreters offset the path in XZ alike.
    for (const char* name : {"comp.ngc", "comp-g1.ngc", "comp311.ngc", "comp311_2.ngc",
                             "gmoccapy_2_tools_with_cutter_radius_compensation.ngc",
                             "lathecomp.ngc", "useful-subroutines.ngc"})
      programs.push_back(fs::path("/usr/share/linuxcnc/ncfiles") / name);
  }
  const std::map<int, double> diameters = tbl_diameters(table);
  REQUIRE(diameters.at(4) == doctest::Approx(0.2 * 25.4));
  for (const fs::path& program : programs) {
    CAPTURE(program.string());
    REQUIRE_MESSAGE(fs::exists(program), "corpus file missing");
    compare_paths(program, table, diameters);
  }
}

TEST_CASE("differential: cutter compensation (G41/G42) agrees with rs274") {
  if (!rs274_available()) {
    MESSAGE(
        "SKIPPED: rs274 not found (install the Debian package linuxcnc-uspace); the LinuxCNC "
        "differential test did not run");
    return;
  }
  fs::path folder = fs::path(TRIDEX_TEST_DATA) / "gcode" / "linuxcnc" / "comp";
  // tools.tbl in mm: T1 0.25 in, T2 0.5 in, T3 0.
  const std::map<int, double> diameters{{1, 6.35}, {2, 12.7}, {3, 0.0}};
  std::vector<fs::path> programs;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.path().extension() == ".ngc") programs.push_back(entry.path());
  std::sort(programs.begin(), programs.end());
  REQUIRE(programs.size() >= 4);
  for (const fs::path& program : programs) {
    CAPTURE(program.string());
    compare_paths(program, folder / "tools.tbl", diameters);
  }
}

TEST_CASE("differential: random programs agree with rs274") {
  if (!rs274_available()) {
    MESSAGE(
        "SKIPPED: rs274 not found (install the Debian package linuxcnc-uspace); the LinuxCNC "
        "differential test did not run");
    return;
  }
  std::mt19937_64 rng(31);
  std::size_t compared = 0;
  for (int trial = 0; trial < 30; ++trial) {
    fs::path program = fs::temp_directory_path() / ("tridex_random_" + std::to_string(::getpid()) +
                                                    "_" + std::to_string(trial) + ".ngc");
    {
      std::ofstream out(program);
      out << random_program(rng);
    }
    CAPTURE(trial);
    Comparison c = compare_with_rs274(program, 3);
    compared += c.compared;
    if (c.agreed) fs::remove(program);
  }
  MESSAGE("random programs: " << compared << " end points compared");
}

TEST_CASE("differential: LinuxCNC rs274 and tridex agree on every move end point") {
  if (!rs274_available()) {
    MESSAGE(
        "SKIPPED: rs274 not found (install the Debian package linuxcnc-uspace); the LinuxCNC "
        "differential test did not run");
    return;
  }
  for (const fs::path& program : corpus()) {
    CAPTURE(program.string());
    REQUIRE_MESSAGE(fs::exists(program), "corpus file missing");
    std::size_t n = compare_with_rs274(program, 5).compared;
    MESSAGE(program.filename().string() << ": " << n << " end points compared");
  }
}

// LinuxCNC's skeleton.ngc loads tool 1 and takes its length (0.511 in in rs274's own table) with
// `T1 M06 G43 H1`. Run standalone, rs274 re-reads its position after a tool change from the last
// point it printed, which drops the G43 of the same block from the position of the axes the next
// move leaves out (a real control re-reads it from the machine, offset applied): with G43 in a
// block of its own, rs274 shifts the position as tridex does. The installed program is read (GPL:
// not copied here) and run with that one block split.
TEST_CASE("differential: skeleton.ngc's tool length offset agrees with rs274") {
  if (!rs274_available()) {
    MESSAGE(
        "SKIPPED: rs274 not found (install the Debian package linuxcnc-uspace); the LinuxCNC "
        "differential test did not run");
    return;
  }
  const fs::path installed = "/usr/share/linuxcnc/ncfiles/skeleton.ngc";
  REQUIRE_MESSAGE(fs::exists(installed), "corpus file missing");
  std::ifstream in(installed);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  const std::string block = "T1 M06 G43 H1";
  std::size_t at = text.find(block);
  REQUIRE(at != std::string::npos);
  text.replace(at, block.size(), "T1 M06\nG43 H1");
  fs::path program =
      fs::temp_directory_path() / ("tridex_skeleton_" + std::to_string(::getpid()) + ".ngc");
  {
    std::ofstream out(program);
    out << text;
  }
  Comparison c = compare_with_rs274(program, 5);
  CHECK(c.agreed);
  CHECK(c.compared >= 4);
  // The tip stands the tool's length below the gauge point G53 Z0 put at the machine's zero.
  std::vector<Point> ours = run_tridex(program);
  REQUIRE(!ours.empty());
  CHECK(ours.front().p.z == doctest::Approx(-0.511 * 25.4));
  fs::remove(program);
}

// rs274 prints the rate of every feed move (SET_FEED_RATE, program units per minute, or per
// revolution after SET_FEED_MODE(0, 1), times the SET_SPINDLE_SPEED); under G93 it is the rate
// it works out for the block, its length × F. tridex's moves carry theirs in mm/min: the rates
// of the feed blocks of feed_modes.ngc (one STRAIGHT_FEED or ARC_FEED each) are compared in order.
TEST_CASE("differential: feed rates in G93, G94 and G95 agree with rs274") {
  if (!rs274_available()) {
    MESSAGE(
        "SKIPPED: rs274 not found (install the Debian package linuxcnc-uspace); the LinuxCNC "
        "differential test did not run");
    return;
  }
  const fs::path program = fs::path(TRIDEX_TEST_DATA) / "gcode" / "linuxcnc" / "feed_modes.ngc";
  const fs::path out =
      fs::temp_directory_path() / ("tridex_rs274_feeds_" + std::to_string(::getpid()));
  const fs::path home = rs274_home();
  std::string command = "HOME='" + home.string() + "' rs274 -g '" + program.string() + "' '" +
                        out.string() + "' < /dev/null > /dev/null 2>&1";
  (void)std::system(command.c_str());
  fs::remove_all(home);
  std::vector<std::pair<double, double>> theirs;  // mm/min, tolerance
  {
    std::ifstream in(out);
    double scale = 1, rate = 0, speed = 0;
    bool per_rev = false;
    for (std::string line; std::getline(in, line);) {
      std::size_t at;
      if (line.find("USE_LENGTH_UNITS(CANON_UNITS_INCHES") != std::string::npos) scale = 25.4;
      if (line.find("USE_LENGTH_UNITS(CANON_UNITS_MM") != std::string::npos) scale = 1;
      if ((at = line.find("SET_FEED_MODE(")) != std::string::npos)
        per_rev = arguments(line, line.find('(', at)).at(1) == 1;
      if ((at = line.find("SET_FEED_RATE(")) != std::string::npos)
        rate = arguments(line, line.find('(', at)).at(0);
      if ((at = line.find("SET_SPINDLE_SPEED(")) != std::string::npos)
        speed = arguments(line, line.find('(', at)).at(1);
      if (line.find("STRAIGHT_FEED(") != std::string::npos ||
          line.find("ARC_FEED(") != std::string::npos)
        theirs.emplace_back(rate * scale * (per_rev ? speed : 1),
                            0.5e-4 * scale * (per_rev ? speed : 1) + 1e-6);
    }
  }
  fs::remove(out);
  std::vector<double> ours;
  {
    std::ifstream in(program);
    Interpreter interpreter({}, *MachineConfig::bundled("rs274"));
    int last_line = 0;
    interpreter.run(in, program.string(), [&](const Move& m) {
      if (m.kind == MoveKind::rapid || m.line == last_line) return;
      last_line = m.line;
      ours.push_back(m.feed);
    });
  }
  REQUIRE(theirs.size() >= 10);
  REQUIRE(ours.size() == theirs.size());
  for (std::size_t i = 0; i < ours.size(); ++i) {
    CAPTURE(i);
    CHECK(std::abs(ours[i] - theirs[i].first) <= theirs[i].second);
  }
}

// LinuxCNC's cone.ngc, for its simulated 5-axis machine, drills with a W axis (`g1 w100`), which
// rs274 run standalone refuses ("Bad character 'w' used": it has no U/V/W without an INI), while
// a LinuxCNC machine with W reads it as a plain axis, as tridex does under --machine linuxcnc.
// rs274 reads the installed program (GPL: not copied here) with its W words taken out; tridex
// reads it whole, and its X/Y/Z must not move for them.
TEST_CASE("differential: cone.ngc's W axis moves no X/Y/Z, as rs274 without its W words") {
  if (!rs274_available()) {
    MESSAGE(
        "SKIPPED: rs274 not found (install the Debian package linuxcnc-uspace); the LinuxCNC "
        "differential test did not run");
    return;
  }
  const fs::path installed = "/usr/share/linuxcnc/ncfiles/cone.ngc";
  REQUIRE_MESSAGE(fs::exists(installed), "corpus file missing");
  std::ifstream in(installed);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  std::size_t removed = 0;
  for (std::size_t at = 0; (at = text.find_first_of("wW", at)) != std::string::npos;) {
    std::size_t end = at + 1;
    while (end < text.size() && (std::isdigit(static_cast<unsigned char>(text[end])) ||
                                 text[end] == '.' || text[end] == '-'))
      ++end;
    bool word =
        end > at + 1 && (at == 0 || !std::isalpha(static_cast<unsigned char>(text[at - 1])));
    if (!word) {
      at = end;
      continue;
    }
    text.erase(at, end - at);
    ++removed;
  }
  REQUIRE(removed == 2);
  fs::path stripped =
      fs::temp_directory_path() / ("tridex_cone_" + std::to_string(::getpid()) + ".ngc");
  {
    std::ofstream out(stripped);
    out << text;
  }
  Comparison c = compare_with_rs274(stripped, 5, installed);
  CHECK(c.agreed);
  CHECK(c.compared >= 80);
  fs::remove(stripped);
}
