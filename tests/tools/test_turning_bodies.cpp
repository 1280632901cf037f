// `tridex check`: the holder of a simultaneous 5-axis move (issue 34; checks/turning_bodies.hpp)
// against the stock, on the bundled ac-trunnion's kinematics (A tilts the table about X through
// (0, 0, −75), C turns it about Z through the origin).
//
// The tool stands at A60, its tip 2 mm below the top of the stock −30..30 × −30..30 × −10..0,
// 68 mm from the C axis and leaning towards it; a 6 mm flat end with 10 mm of flutes, a Ø6 shank
// and a Ø30 holder 20 mm out. Its holder's lowest generatrix (the rim's lowest point, 43.18 mm from
// the axis and 4.99 mm down, rising towards the axis at 30°) crosses the stock's top 34.54 mm from
// the axis: beyond the box's sides (30 mm), inside its corners (42.43 mm). While C turns 0 → 90
// (raw: the table turns under the standing machine; TCP: the tip runs straight from
// (0, −96.17) to (−96.17, 0), 68 mm out at C45) the holder dips into the corner at C45 only: at
// both ends it clears the stock by 2.26 mm, beyond the 1 mm clearance, so a check of the move's
// ends alone finds nothing. With 40 mm out the holder clears the stock everywhere.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"
#include "tridex/collide.hpp"
#include "tridex/gcode/kinematics.hpp"
#include "tridex/gcode/machine.hpp"
#include "tridex/stl.hpp"

namespace test_turning_bodies {

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

const std::string kStock = "box:-30,-30,-10,30,30,0";
constexpr double kCell = 1.0;  // coarse: each check well under a second

std::string tools_json(double stick_out) {
  return R"({"1": {"shape": "cylindrical", "diameter": 6, "flute-length": 10,
     "shank-diameter": 6, "stick-out": )" +
         std::to_string(stick_out) +
         R"(, "holder": [{"bottom-diameter": 30, "top-diameter": 30, "length": 20}]}})";
}

std::string xyz(const Vec3& p) {
  char text[96];
  std::snprintf(text, sizeof text, "X%.4f Y%.4f Z%.4f", p.x, p.y, p.z);
  return text;
}

// Raw rotary words: X Y Z are the machine's linear axes. The tip 68 mm out on −Y at A60 C0; the
// approach and the retract along the part's Z (40 mm above), then C turns 90° alone (line 6).
std::string raw_program() {
  const gcode::Kinematics kin = *gcode::MachineConfig::bundled("ac-trunnion")->kinematics;
  const gcode::RotaryPositions a60{60, 0, 0};
  const Vec3 low = gcode::machine_from_part(kin, Vec3(0, -68, -2), a60);
  const Vec3 high = gcode::machine_from_part(kin, Vec3(0, -68, 38), a60);
  return "G21 G90 G17 G40 G49 G80\nT1 M6\nS8000 M3\nG0 " + xyz(high) + " A60 C0\nG0 " + xyz(low) +
         "\nG1 C90 F500\nG0 " + xyz(high) + "\nM2\n";
}

// Under TCP (G43.4): X Y Z are the tip on the part; the turning cut on line 8.
std::string tcp_program() {
  return "G21 G90 G17 G40 G49 G80\nT1 M6\nS8000 M3\nG0 A60 C0\nG43.4\nG0 X0 Y-96.167 Z40\n"
         "G0 Z-2\nG1 X-96.167 Y0 C90 F500\nG0 Z40\nG49\nM2\n";
}

// The holder's deepest point at C45 (a material point's distance to the holder's surface, as
// check measures it): on the box's top along the diagonal, where its distance up the axis from
// the holder's face equals its distance to the side's lowest generatrix.
double deepest_at_c45() {
  const double s = std::sin(M_PI / 3), c = std::cos(M_PI / 3);
  const double rim_out = 68 - 20 * s - 15 * c, rim_z = -2 + 20 * c - 15 * s;  // 43.18, −4.99
  // A point d inward of the rim on the top (z = 0): up the axis .866 d + .5 (−rim_z), across the
  // generatrix .866 (−rim_z) − .5 d.
  const double d = (s * -rim_z - c * -rim_z) / (s + c);
  CHECK(rim_out - d < 30 * std::sqrt(2.0));  // inside the corner
  return s * d + c * -rim_z;
}

struct Checked {
  CommandResult result;
  json report;
};

Checked check(const std::string& name, const std::string& program, double stick_out,
              const std::vector<std::string>& more = {}) {
  fs::path dir = scratch(name);
  write_text(dir / "bare.json", R"({"base": "ac-trunnion", "components": []})");
  write_text(dir / "tools.json", tools_json(stick_out));
  write_text(dir / "p.ngc", program);
  // The turning cuts of the holders' cases cut nothing (the flutes stay outside the box): the
  // design is the stock.
  {
    std::ofstream design(dir / "design.stl", std::ios::binary);
    write_stl(design, make_box_mesh(Vec3(-30, -30, -10), Vec3(30, 30, 0)));
  }
  std::vector<std::string> args{"check",
                                (dir / "p.ngc").string(),
                                "--design",
                                (dir / "design.stl").string(),
                                "--machine",
                                (dir / "bare.json").string(),
                                "--tools",
                                (dir / "tools.json").string(),
                                "--stock",
                                kStock,
                                "--dexel-cell",
                                std::to_string(kCell),
                                "--lattice-only",
                                "--tolerance",
                                "0.1",
                                "--report",
                                (dir / "report.json").string()};
  args.insert(args.end(), more.begin(), more.end());
  Checked out{run_tridex(args, dir), json()};
  if (fs::exists(dir / "report.json")) out.report = json::parse(slurp(dir / "report.json"));
  fs::remove_all(dir);
  return out;
}

// The holder's collision at `line`, alone, as deep as the geometry says within the lattice's
// reach (the Z rays lie a spacing apart: the deepest point may fall between them) and half a
// sampling step.
void expect_holder_collision(const Checked& run, int line) {
  INFO(run.result.out, run.result.err);
  CHECK(run.result.status == 3);
  CHECK(run.report["verdict"] == "fail");
  const json& c = run.report["collisions"];
  REQUIRE(c.size() == 1);
  CHECK(c[0]["line"] == line);
  CHECK(c[0]["tool"] == 1);
  CHECK(c[0]["part"] == "holder section 1");
  const double depth = c[0]["depth_mm"].get<double>(), expected = deepest_at_c45();
  CHECK(depth <= expected + 0.01);
  CHECK(depth >= expected - kCell * std::sqrt(2.0) - kCell / 4);
  // In the corner's quarter, where the holder leans at C45.
  CHECK(c[0]["point"][0].get<double>() < -20);
  CHECK(c[0]["point"][1].get<double>() < -20);
  CHECK(run.report["collisions_count"] == 1);
  // The ends are clear by more than the clearance: no near miss either.
  CHECK(run.report["near_misses"]["moves"].empty());
  CHECK(!run.report.contains("not_checked"));
  CHECK(run.result.out.find("p.ngc:" + std::to_string(line) + ": tool 1's holder section 1 is") !=
        std::string::npos);
}

TEST_CASE("check: a holder that dips into the stock only mid-way through a raw C turn") {
  expect_holder_collision(check("turning-raw", raw_program(), 20), 6);
  // The same turn as a rapid (G0 C90: an indexing turn, no move of its own) is tested at the line
  // of the move after it, the retract.
  std::string rapid = raw_program();
  rapid.replace(rapid.find("G1 C90 F500"), 11, "G0 C90");
  expect_holder_collision(check("turning-raw-rapid", rapid, 20), 7);
}

TEST_CASE("check: a holder that dips into the stock only mid-way through a turn under TCP") {
  expect_holder_collision(check("turning-tcp", tcp_program(), 20), 8);
}

TEST_CASE("check: the same turns with the holder 40 mm out pass") {
  for (const std::string& program : {raw_program(), tcp_program()}) {
    Checked run = check("turning-long", program, 40);
    INFO(program, run.result.out, run.result.err);
    CHECK(run.result.status == 0);
    CHECK(run.report["verdict"] == "pass");
    CHECK(run.report["collisions"].empty());
    CHECK(run.report["near_misses"]["moves"].empty());
  }
}

// Under LinuxCNC's TCP kinematics (M428) a G0 that turns the rotaries moves the tip straight on
// the part (a simultaneous rapid). A vertical flat end cuts a groove 2 mm deep from X-20 to X20
// while C turns 90° (line 7), then rapids back (line 8) with C: along its own groove it cuts
// nothing; 1 mm lower at its end it cuts the groove's floor, by 1 mm where it ends (less the
// sweep's band, ≤ a tenth of the spacing, by which the groove may be deeper). It leaves by a
// feed: a 3+2 rapid after a simultaneous cut is checked against the Z-maps, which do not hold
// that cut (docs/design.md, "Simultaneous moves").
std::string groove_and_rapid(const std::string& back) {
  return "G21 G90 G17 G40 G49 G80\nT1 M6\nS8000 M3\nM428\nG0 X-20 Y0 Z10 A0 C0\nG1 Z-2 F300\n"
         "G1 X20 C90 F500\n" +
         back + "\nG1 Z40\nM429\nM2\n";
}

TEST_CASE("check: a simultaneous rapid is a rapid cut where it meets stock its cuts left") {
  Checked run = check("turning-rapid", groove_and_rapid("G0 X-20 Z-2 C0"), 40);
  INFO(run.result.out, run.result.err);
  CHECK(run.report["rapid_cuts"].empty());
  CHECK(run.report["collisions"].empty());
  CHECK(!run.report.contains("not_checked"));
  run = check("turning-rapid", groove_and_rapid("G0 X-20 Z-3 C0"), 40);
  CHECK(run.result.status == 3);
  REQUIRE(run.report["rapid_cuts"].size() == 1);
  CHECK(run.report["rapid_cuts"][0]["line"] == 8);
  CHECK(run.report["rapid_cuts"][0]["depth_mm"].get<double>() >= 1 - kCell / 10 - 0.01);
  CHECK(run.report["rapid_cuts"][0]["depth_mm"].get<double>() <= 1 + 0.01);
  CHECK(run.result.out.find("p.ngc:8: rapid cuts") != std::string::npos);
}

}  // namespace test_turning_bodies
