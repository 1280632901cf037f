// Differential test against LinuxCNC's interpreter (Debian package linuxcnc-uspace, `rs274`).
//
// rs274 prints the canonical machining calls of a program: STRAIGHT_TRAVERSE, STRAIGHT_FEED and
// ARC_FEED with end points in the active work coordinate system and program units, to 4
// decimals. Those are turned into machine millimetres (with the SET_G5X_OFFSET and
// USE_LENGTH_UNITS calls it also prints) and compared with tridex's moves: one end point per
// straight move, one per arc (the last of its chords), zero-length moves dropped on both sides.
// Agreement is to rs274's printed precision: 0.5e-4 program units plus 1e-6.
#include <doctest/doctest.h>

#include <cstdio>
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
  Vec3 offset(0.0);  // mm
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
    push(points, Point{p * scale + offset, 0.5e-4 * scale + 1e-6, record});
  }
  fs::remove(out);
  fs::remove(out.string() + ".log");
  return points;
}

std::vector<Point> run_tridex(const fs::path& program) {
  InterpreterOptions options;
  options.start_position = Vec3(0.0);   // rs274 starts at the origin
  options.tool_change_retracts = false; // and does not move on M6
  options.block_delete = false;         // its block-delete switch is off by default
  std::vector<Point> points;
  std::ifstream in(program, std::ios::binary);
  REQUIRE(in);
  Interpreter interpreter(options);
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
  for (const char* name : {"3dtest.ngc", "arcspiral.ngc", "cds.ngc", "tort.ngc"})
    files.push_back(fs::path("/usr/share/linuxcnc/ncfiles") / name);
  return files;
}

}  // namespace

TEST_CASE("differential: LinuxCNC rs274 and tridex agree on every move end point") {
  if (!rs274_available()) {
    MESSAGE("SKIPPED: rs274 not found (install the Debian package linuxcnc-uspace); the LinuxCNC "
            "differential test did not run");
    return;
  }
  for (const fs::path& program : corpus()) {
    CAPTURE(program.string());
    REQUIRE_MESSAGE(fs::exists(program), "corpus file missing");
    std::string log;
    std::vector<Point> theirs = run_rs274(program, log);
    std::vector<Point> ours = run_tridex(program);
    INFO("rs274 log: " << log.substr(0, 600));
    CHECK(ours.size() == theirs.size());
    std::size_t n = std::min(ours.size(), theirs.size());
    int reported = 0;
    for (std::size_t i = 0; i < n && reported < 5; ++i) {
      Vec3 d = glm::abs(ours[i].p - theirs[i].p);
      double worst = std::max(d.x, std::max(d.y, d.z));
      if (worst > theirs[i].tolerance) {
        ++reported;
        FAIL_CHECK("move " << i << ": tridex (line " << ours[i].record << ") " << ours[i].p.x << " "
                           << ours[i].p.y << " " << ours[i].p.z << " vs rs274 (record "
                           << theirs[i].record << ") " << theirs[i].p.x << " " << theirs[i].p.y
                           << " " << theirs[i].p.z);
      }
    }
    MESSAGE(program.filename().string() << ": " << n << " end points compared");
  }
}
