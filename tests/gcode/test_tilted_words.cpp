// The tilted-plane words as the interpreter reads them (tilted_plane_codes.cpp): each control's
// G68.2 form, G68.3, G68.4, G268's Q orders and LinuxCNC's G53.3, run as programs and compared with
// the frames of tilted_plane.hpp (tested against the manuals' definitions in test_tilted_forms.cpp)
// and with each other.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <tuple>

#include "helpers.hpp"
#include "tridex/gcode/tilted_plane.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace test_tilted_words {

// The tool direction and the moves of a program that defines a plane, orients the tool and cuts
// a small square in the plane.
Result square_in(const std::string& plane, const std::string& orient = "G53.1",
                 MachineConfig machine = at_origin()) {
  return run_program(cat("G21 G90 G54 T1 M6 S1000 M3\n", plane, "\n", orient, "\n",
                         "G0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\nG1 Y10\nG1 X0\nG1 Y0\nG0 Z5\nM30\n"),
                     {}, machine);
}

Vec3 tool_of(const Result& r) {
  REQUIRE(!r.moves.empty());
  return r.moves.back().axis;
}

bool same_moves(const Result& a, const Result& b, double eps = 1e-9) {
  if (a.moves.size() != b.moves.size()) return false;
  for (std::size_t i = 0; i < a.moves.size(); ++i)
    if (!near(a.moves[i].start, b.moves[i].start, eps) ||
        !near(a.moves[i].end, b.moves[i].end, eps) || !near(a.moves[i].axis, b.moves[i].axis, eps))
      return false;
  return true;
}

// Ten decimals: the written words must not cost the 1e-6 mm the forms are compared within.
std::string num(double v) {
  char text[48];
  std::snprintf(text, sizeof text, "%.10f", v);
  return text;
}
std::string xyz(const Vec3& p) { return cat("X", num(p.x), " Y", num(p.y), " Z", num(p.z)); }
std::string ijk(const Vec3& v) { return cat("I", num(v.x), " J", num(v.y), " K", num(v.z)); }

TEST_CASE("G68.2 forms: one plane written five ways gives the same moves") {
  // A 90-degree turn about Y with the origin at (3, -3, -6), as in Hurco's example.
  Result hurco = square_in("G68.2 X3 Y-3 Z-6 I0 J0 K-1 U0 V1 W0");
  CHECK(near(tool_of(hurco), Vec3(1, 0, 0), 1e-12));
  Frame f = hurco_vector_frame(Vec3(3, -3, -6), Vec3(0, 0, -1), Vec3(0, 1, 0));
  CHECK(near(hurco.moves.back().end, f.to_world(Vec3(0, 0, 5)), 1e-9));
  CHECK(same_moves(hurco, square_in("G68.2 X3 Y-3 Z-6 I90 J90 K-90")));          // Fanuc P0
  CHECK(same_moves(hurco, square_in("G68.2 X3 Y-3 Z-6 A90 B90 C-90")));          // Mazak A B C
  CHECK(same_moves(hurco, square_in("G68.2 P1 Q123 X3 Y-3 Z-6 J90")));           // Fanuc P1
  CHECK(same_moves(hurco, square_in("G268 X3 Y-3 Z-6 J90 Q123", "G253")));       // Haas
  CHECK(same_moves(hurco, square_in("G68.2 P0 Q313 X3 Y-3 Z-6 I90 J90 K-90")));  // LinuxCNC P0
}

TEST_CASE("G68.2 P1 and G268: the Q order decides") {
  CHECK(near(tool_of(square_in("G68.2 P1 I90 K90")), Vec3(1, 0, 0), 1e-12));  // Q123 default
  CHECK(near(tool_of(square_in("G68.2 P1 Q321 I90 K90")), Vec3(0, -1, 0), 1e-12));
  CHECK(near(tool_of(square_in("G268 I90 K90 Q321", "G253")), Vec3(0, -1, 0), 1e-12));
  CHECK(near(tool_of(square_in("G268 I90 J90 Q213", "G253")), Vec3(1, 0, 0), 1e-12));
  Diagnostic d = error_of("G68.2 P1 Q121 I10\n");
  CHECK(d.column == 10);
  CHECK_MESSAGE(d.message.find("Q121") != std::string::npos, d.message);
}

TEST_CASE("LinuxCNC G68.2 Q121: the issue's plane") {
  Vec3 t = tool_of(square_in("G68.2 X0 Y0 Z0 I30 J15 K0 Q121"));
  CHECK(near(t, Vec3(0.259, -0.483, 0.837), 1e-3));
  CHECK(near(t, linuxcnc_angles_frame(0, 121, Vec3(0), 30, 15, 0).rotation[2], 1e-12));
  // R turns about the work Z.
  Result r = square_in("G68.2 X0 Y0 Z0 I30 J15 K0 Q121 R90");
  CHECK(near(tool_of(r), linuxcnc_angles_frame(0, 121, Vec3(0), 30, 15, 0, 90).rotation[2], 1e-12));
}

TEST_CASE("G68.2 P1 in LinuxCNC's dialect: I J K the first to third angle, intrinsic") {
  MachineConfig linuxcnc = at_origin();
  linuxcnc.dialect = Dialect::linuxcnc;
  Vec3 t = tool_of(square_in("G68.2 P1 Q123 I30 J20 K0", "G53.1", linuxcnc));
  CHECK(near(t, linuxcnc_angles_frame(1, 123, Vec3(0), 30, 20, 0).rotation[2], 1e-12));
  CHECK(near(t, rotation_x(30) * rotation_y(20) * Vec3(0, 0, 1), 1e-12));
  // Fanuc's reading of the same words differs: about the fixed X, then the fixed Y.
  CHECK(near(tool_of(square_in("G68.2 P1 Q123 I30 J20 K0")),
             rotation_y(20) * rotation_x(30) * Vec3(0, 0, 1), 1e-12));
  // G268 stays Haas's in either dialect.
  CHECK(near(tool_of(square_in("G268 I30 J20 Q123", "G253", linuxcnc)),
             rotation_y(20) * rotation_x(30) * Vec3(0, 0, 1), 1e-12));
}

TEST_CASE("G68.4 composes with the active plane; G68.3 takes the tool axis") {
  CHECK(same_moves(square_in("G68.2 X10 I0 J30 K0\nG68.4 Z2 J15"),
                   square_in(cat("G68.2 X10 Y", fmt(-2 * std::sin(glm::radians(30.0))), " Z",
                                 fmt(2 * std::cos(glm::radians(30.0))), " J45")),
                   1e-4));
  CHECK(error_of("G68.4 J15\n").message.find("without an active tilted plane") !=
        std::string::npos);
  // G68.3 after orienting to a plane, with the plane cancelled: Z along that tool axis (+X).
  Result r = square_in("G68.2 I90 J90 K0\nG53.1\nG69\nG68.3 X1 Y2 Z3 R30");
  Frame g = tool_axis_frame(Vec3(1, 2, 3), Vec3(1, 0, 0), 30);
  CHECK(near(tool_of(r), Vec3(1, 0, 0), 1e-12));
  CHECK(near(r.moves.back().end, g.to_world(Vec3(0, 0, 5)), 1e-9));
  CHECK(near(r.moves[r.moves.size() - 3].end, g.to_world(Vec3(0, 10, -1)), 1e-9));
  CHECK(error_of("G68.3 X1 Y2\n").message.find("all of X, Y and Z") != std::string::npos);
  CHECK(error_of("G68.3\n").message.find("retracted") != std::string::npos);
}

TEST_CASE("LinuxCNC G53.3 orients and rapids to X Y Z in the plane (its remap's form)") {
  Result r = run_program("G21 G90 T1 M6\nG68.2 X5 I0 J30 K0 Q313\nG53.3 P1 X1 Y2 Z3\nM30\n", {},
                         at_origin());
  REQUIRE(r.moves.size() == 1);
  Frame f = fanuc_euler(Vec3(5, 0, 0), 0, 30, 0);
  CHECK(near(r.moves[0].end, f.to_world(Vec3(1, 2, 3)), 1e-9));
  CHECK(r.moves[0].kind == MoveKind::rapid);
  CHECK(near(r.moves[0].axis, f.rotation[2], 1e-12));
  CHECK(error_of("G68.2 J30\nG53.3 X1 Y2\n").message.find("needs X, Y and Z") != std::string::npos);
  Diagnostic d = error_of("G68.2 J30\nG53.3 I1 J2 K3\n");
  CHECK(d.column == 7);
  CHECK(d.message.find("as X Y Z, not I J K") != std::string::npos);
}

TEST_CASE("tilted-plane words: bad combinations are errors with their column") {
  Diagnostic d = error_of("G68.2 X0 I10 A20\n");
  CHECK(d.line == 1);
  CHECK(d.column == 14);
  d = error_of("G68.2 X0 I1 J0 K0 U1 V0 W0\n");  // Hurco vectors not normal
  CHECK_MESSAGE(d.message.find("not normal") != std::string::npos, d.message);
  d = error_of("G68.2 P0 Q123 I10\n");  // LinuxCNC P0 takes proper Euler orders only
  CHECK_MESSAGE(d.message.find("Q123") != std::string::npos, d.message);
  d = error_of("G68.2 I10 R5\n");  // Fanuc P0 has no R
  CHECK_MESSAGE(d.message.find("R5") != std::string::npos, d.message);
}

TEST_CASE("G68.2 P2 and P3 over several blocks agree with the P0 plane they describe") {
  // Random planes written as Fanuc's P0 and as the several-block forms built from that plane's
  // axes (tilted_plane.hpp's fanuc_euler is checked against the manual in test_tilted_forms.cpp).
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> angle(-180, 180), tilt(5, 85), coord(-30, 30),
      scale(0.5, 40);
  for (int n = 0; n < 40; ++n) {
    double i = angle(rng), j = tilt(rng), k = angle(rng), r = angle(rng);
    Vec3 o(coord(rng), coord(rng), coord(rng)), shift(coord(rng), coord(rng), coord(rng));
    Frame f = fanuc_euler(o, i, j, k);
    Vec3 x = f.rotation[0], y = f.rotation[1], z = f.rotation[2];
    Vec3 p2 = o + scale(rng) * x, p3 = o + coord(rng) * x + scale(rng) * y;
    std::string points =
        cat("G68.2 P2 Q1 ", xyz(o), "\nG68.2 P2 Q2 ", xyz(p2), "\nG68.2 P2 Q3 ", xyz(p3));
    Result p0 = square_in(cat("G68.2 ", xyz(o), " I", num(i), " J", num(j), " K", num(k)));
    CHECK(same_moves(square_in(points), p0, 1e-6));
    // Fanuc P2 Q0: the shift from point 1 in the feature frame, then R about the feature Z —
    // the P0 plane at o + R·shift with K + R.
    Result shifted = square_in(
        cat("G68.2 ", xyz(f.to_world(shift)), " I", num(i), " J", num(j), " K", num(k + r)));
    CHECK(same_moves(square_in(cat("G68.2 P2 Q0 ", xyz(shift), " R", num(r), "\n", points)),
                     shifted, 1e-6));
    CHECK(same_moves(square_in(cat("G68.2 P2 Q2 ", xyz(p2), "\nG68.2 P2 Q0 ", xyz(shift), " R",
                                   num(r), "\nG68.2 P2 Q1 ", xyz(o), "\nG68.2 P2 Q3 ", xyz(p3))),
                     shifted, 1e-6));
    // Fanuc P3: Q1 the origin and the X direction, Q2 the Z direction.
    CHECK(same_moves(square_in(cat("G68.2 P3 Q1 ", xyz(o), " ", ijk(scale(rng) * x),
                                   "\nG68.2 P3 Q2 ", ijk(scale(rng) * z))),
                     p0, 1e-6));
    // LinuxCNC's dialect: P2 Q0 the origin itself, P3 Q0 I J K a point on X; R about the work Z,
    // as its P0 Q313 R.
    MachineConfig linuxcnc = at_origin();
    linuxcnc.dialect = Dialect::linuxcnc;
    Vec3 at(coord(rng), coord(rng), coord(rng));
    Result lc0 = square_in(
        cat("G68.2 P0 Q313 ", xyz(at), " I", num(i), " J", num(j), " K", num(k), " R", num(r)),
        "G53.1", linuxcnc);
    CHECK(same_moves(
        square_in(cat("G68.2 P2 Q0 ", xyz(at), " R", num(r), "\n", points), "G53.1", linuxcnc), lc0,
        1e-6));
    CHECK(same_moves(square_in(cat("G68.2 P3 Q1 ", ijk(z), "\nG68.2 P3 Q0 ", xyz(at), " ",
                                   ijk(at + scale(rng) * x), " R", num(r)),
                               "G53.1", linuxcnc),
                     lc0, 1e-6));
  }
  // G68.4 takes them too, composed with the active plane.
  CHECK(same_moves(square_in("G68.2 X10 I0 J30 K0\nG68.4 P3 Q1 Z2 I1\nG68.4 P3 Q2 K1\nG68.4 J15"),
                   square_in(cat("G68.2 X10 Y", fmt(-2 * std::sin(glm::radians(30.0))), " Z",
                                 fmt(2 * std::cos(glm::radians(30.0))), " J45")),
                   1e-4));
}

TEST_CASE("G68.2 P2 by hand: Q1 the origin, Q1 -> Q2 the X axis, Q3 on the +Y side") {
  // Fanuc's three-point form as its 30i-series posts describe it: the first point is the feature
  // origin, the second gives +X from it, the third lies in the plane on the +Y side; Z = X x Y.
  // Q0 X Y Z shifts the origin in the feature frame, R then turns the frame about its Z.
  auto end_of = [](const std::string& plane, const Vec3& feature_point) {
    Result r =
        run_program(cat("G21 G90\nG0 X0 Y0 Z50\n", plane, "\nG53.1\nG0 ", "X", num(feature_point.x),
                        " Y", num(feature_point.y), " Z", num(feature_point.z), "\nM30\n"),
                    {}, at_origin());
    REQUIRE(r.moves.size() >= 1);
    return std::pair<Vec3, Vec3>{r.moves.back().end, r.moves.back().axis};
  };
  // The plane level, X along work +Y: feature (1, 2, 3) is (10, 20, 5) + 1·(0,1,0) + 2·(-1,0,0) +
  // 3·Z.
  const std::string level = "G68.2 P2 Q1 X10 Y20 Z5\nG68.2 P2 Q2 X10 Y30 Z5\nG68.2 P2 Q3 X0 Y25 Z5";
  auto [end, axis] = end_of(level, Vec3(1, 2, 3));
  CHECK(near(end, Vec3(8, 21, 8), 1e-12));
  CHECK(near(axis, Vec3(0, 0, 1), 1e-12));
  // Q0 X1 R90: origin (11 on feature X) = (10, 21, 5); then X' = old Y = (-1, 0, 0), Y' = -old X.
  std::tie(end, axis) = end_of("G68.2 P2 Q0 X1 R90\n" + level, Vec3(1, 2, 3));
  CHECK(near(end, Vec3(9, 19, 8), 1e-12));
  // Tilted 45° about X: Z = (1,0,0) x (0,10,10) normalised = (0, -s, s), Y = (0, s, s).
  const double s = std::sqrt(0.5);
  std::tie(end, axis) =
      end_of("G68.2 P2 Q1 X0 Y0 Z0\nG68.2 P2 Q2 X10 Y0 Z0\nG68.2 P2 Q3 X0 Y10 Z10", Vec3(0, 2, 1));
  CHECK(near(axis, Vec3(0, -s, s), 1e-12));
  CHECK(near(end, Vec3(0, 2 * s - s, 2 * s + s), 1e-12));
}

TEST_CASE("G68.2 P2 / P3: incomplete, repeated or misplaced blocks are errors") {
  Diagnostic d = error_of("G68.2 P2 Q1 X0 Y0 Z0\nG68.2 P2 Q2 X1\nG0 X1\n");
  CHECK(d.line == 3);
  CHECK(d.column == 1);
  CHECK_MESSAGE(d.message.find("begun at line 1 is incomplete (Q3 missing)") != std::string::npos,
                d.message);
  d = error_of("G68.2 P3 Q1 X0 Y0 Z0 I1\n");  // the program ends inside the plane
  CHECK(d.line == 1);
  CHECK_MESSAGE(d.message.find("Q2 missing") != std::string::npos, d.message);
  d = error_of("G68.2 P2 Q1 X0\nG68.2 P2 Q1 X1\n");
  CHECK(d.line == 2);
  CHECK(d.column == 10);
  CHECK_MESSAGE(d.message.find("given twice") != std::string::npos, d.message);
  d = error_of("G68.2 P2 Q1 X0\nG68.2 P3 Q1 I1\n");
  CHECK(d.line == 2);
  CHECK_MESSAGE(d.message.find("P2 begun at line 1") != std::string::npos, d.message);
  d = error_of("G68.2 P3 Q0 I1\n");  // Fanuc's P3 blocks are Q1 and Q2 (LinuxCNC's Q0 and Q1)
  CHECK_MESSAGE(d.message.find("Q1, Q2") != std::string::npos, d.message);
  d = error_of("G68.2 P3 Q1 X0 I1\nG68.2 P3 Q2 X5 K1\n");  // a direction has no point
  CHECK(d.line == 2);
  CHECK(d.column == 13);
  d = error_of("G68.2 P2 X0 Y0 Z0\n");
  CHECK_MESSAGE(d.message.find("needs Q") != std::string::npos, d.message);
  d = error_of("G68.2 P2 Q1 X0\nG68.2 P2 Q2 X1\nG68.2 P2 Q3 X5\n");  // three points on one line
  CHECK(d.line == 3);
  CHECK(d.column == 10);
  CHECK_MESSAGE(d.message.find("one line") != std::string::npos, d.message);
  d = error_of("G68.2 P3 Q1 I1\nG68.2 P3 Q2 I1 K0.5\n");  // 63° apart, outside 85°–95°
  CHECK_MESSAGE(d.message.find("85 to 95") != std::string::npos, d.message);
  d = error_of("G68.2 P2 Q1 X0 R5\n");  // R belongs to Q0
  CHECK_MESSAGE(d.message.find("R5") != std::string::npos, d.message);
}

}  // namespace test_tilted_words
