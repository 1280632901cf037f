// Differential test against LinuxCNC's interpreter (Debian package linuxcnc-uspace, `rs274`).
//
// rs274 prints the canonical machining calls of a program: STRAIGHT_TRAVERSE, STRAIGHT_FEED and
// ARC_FEED with end points in the active work coordinate system and program units, to 4
// decimals. Those are turned into machine millimetres (with the SET_G5X_OFFSET and
// USE_LENGTH_UNITS calls it also prints) and compared with tridex's moves: one end point per
// straight move, one per arc (the last of its chords), zero-length moves dropped on both sides.
// Agreement is to rs274's printed precision: 0.5e-4 program units plus 1e-6.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <cstdlib>
#include <filesystem>
#include <fstream>
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
  double tolerance;  // mm
  int record;        // rs274 output line, or source line for tridex
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
  Vec3 previous = points.empty() ? Vec3(0.0) : points.back().p;
  if (glm::length(point.p - previous) > 1e-9) points.push_back(point);
}

std::vector<Point> run_rs274(const fs::path& program, std::string& log) {
  fs::path out = fs::temp_directory_path() /
                 ("tridex_rs274_" + std::to_string(::getpid()) + "_" + program.filename().string());
  std::string command = "rs274 -g '" + program.string() + "' '" + out.string() +
                        "' < /dev/null > '" + out.string() + ".log' 2>&1";
  int status = std::system(command.c_str());
  (void)status;  // rs274 exits 0 even on interpreter errors; its log is checked instead
  std::ifstream log_in(out.string() + ".log");
  log.assign(std::istreambuf_iterator<char>(log_in), {});
  std::ifstream in(out);
  std::vector<Point> points;
  double scale = 1;
  Vec3 offset(0.0);  // mm, G5x
  Vec3 local(0.0);   // mm, G92 / G52
  char plane = 'Z';  // XY: Z, XZ: Y, YZ: X (the arc's axis)
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
    Vec3 p;
    if ((at = line.find("STRAIGHT_TRAVERSE(")) != std::string::npos ||
        (at = line.find("STRAIGHT_FEED(")) != std::string::npos) {
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
    push(points, Point{p * scale + offset + local, 0.5e-4 * scale + 1e-6, record});
  }
  fs::remove(out);
  fs::remove(out.string() + ".log");
  return points;
}

std::vector<Point> run_tridex(const fs::path& program) {
  InterpreterOptions options;
  options.block_delete = false;  // rs274's block-delete switch is off by default
  std::vector<Point> points;
  std::ifstream in(program, std::ios::binary);
  REQUIRE(in);
  Interpreter interpreter(options, *MachineConfig::bundled("linuxcnc"));
  Move last_arc;
  bool in_arc = false;
  auto flush = [&] {
    if (in_arc) push(points, Point{last_arc.end, 0, last_arc.line});
    in_arc = false;
  };
  interpreter.run(in, program.string(), [&](const Move& m) {
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
  for (const auto& entry : fs::directory_iterator(fs::path(TRIDEX_TEST_DATA) / "gcode" / "linuxcnc"))
    if (entry.path().extension() == ".ngc") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  // LinuxCNC's own sample programs that use only codes both interpreters support.
  if (const char* only = std::getenv("TRIDEX_DIFF_ONLY")) {  // ad-hoc: one program
    files.assign(1, fs::path(only));
    return files;
  }
  for (const char* name : {"3dtest.ngc", "arcspiral.ngc", "cds.ngc", "tort.ngc"})
    files.push_back(fs::path("/usr/share/linuxcnc/ncfiles") / name);
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

// Runs rs274 and tridex on `program` and checks that every move end point agrees within rs274's
// printed precision, reporting at most `max_reports` disagreements; returns how many were compared
// and whether all agreed.
struct Comparison {
  std::size_t compared = 0;
  bool agreed = true;
};

Comparison compare_with_rs274(const fs::path& program, int max_reports) {
  std::string log;
  std::vector<Point> theirs = run_rs274(program, log);
  std::vector<Point> ours = run_tridex(program);
  INFO("rs274 log: " << log.substr(0, 600));
  CHECK(ours.size() == theirs.size());
  std::size_t n = std::min(ours.size(), theirs.size());
  int reported = 0;
  for (std::size_t i = 0; i < n && reported < max_reports; ++i) {
    Vec3 d = glm::abs(ours[i].p - theirs[i].p);
    if (std::max(d.x, std::max(d.y, d.z)) > theirs[i].tolerance) {
      ++reported;
      FAIL_CHECK("move " << i << ": tridex (line " << ours[i].record << ") " << ours[i].p.x << " "
                         << ours[i].p.y << " " << ours[i].p.z << " vs rs274 (record "
                         << theirs[i].record << ") " << theirs[i].p.x << " " << theirs[i].p.y
                         << " " << theirs[i].p.z);
    }
  }
  return {n, reported == 0 && ours.size() == theirs.size()};
}

}  // namespace

TEST_CASE("differential: random programs agree with rs274") {
  if (!rs274_available()) {
    MESSAGE("SKIPPED: rs274 not found (install the Debian package linuxcnc-uspace); the LinuxCNC "
            "differential test did not run");
    return;
  }
  std::mt19937_64 rng(31);
  std::size_t compared = 0;
  for (int trial = 0; trial < 30; ++trial) {
    fs::path program = fs::temp_directory_path() /
                       ("tridex_random_" + std::to_string(::getpid()) + "_" + std::to_string(trial) + ".ngc");
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
    MESSAGE("SKIPPED: rs274 not found (install the Debian package linuxcnc-uspace); the LinuxCNC "
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
