// Feed modes (RS274/NGC group 5): G94 units per minute, G93 inverse time (every feed block takes
// 1/F minutes: its moves run at the block's programmed length × F), G95 units per revolution
// (F × S). The path is the same in every mode; each move's feed (mm/min) is checked against
// hand-computed rates and the block times Σ length / feed against 1/F; LinuxCNC's errors.
#include <doctest/doctest.h>

#include <map>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace {

// Minutes each source line takes at its moves' feeds (feed moves only).
std::map<int, double> minutes_by_line(const std::vector<Move>& moves) {
  std::map<int, double> minutes;
  for (const Move& m : moves)
    if (m.feed > 0) minutes[m.line] += glm::length(m.end - m.start) / m.feed;
  return minutes;
}

// The feed of the first move made by source line `line`.
double feed_on(const std::vector<Move>& moves, int line) {
  for (const Move& m : moves)
    if (m.line == line) return m.feed;
  FAIL("no move on line " << line);
  return 0;
}

}  // namespace

TEST_CASE("feed modes: G93 inverse time takes 1/F minutes per block, lines and arcs; G94 back") {
  for (const MachineConfig& machine : {at_origin(), linuxcnc_at_origin()}) {
    Result r = run_program(
        "G21 G0 X0 Y0 Z0\n"
        "G93 G1 X30 Y40 F2\n"          // 50 mm in 1/2 min: 100 mm/min
        "G1 X0 Y40 F0.25\n"            // 30 mm in 4 min
        "G3 X-10 Y30 I0 J-10 F3\n"     // a quarter circle of radius 10
        "G2 X-10 Y30 I10 J0 Z-6 F1\n"  // a full helix: hypot(20π, 6)
        "G20 G1 X0 F10\n"              // 10 mm in 1/10 min, whatever the units
        "G21 G94 G1 Y0 F300\n",        // 30 mm at 300 mm/min
        {}, machine);
    std::map<int, double> minutes = minutes_by_line(r.moves);
    REQUIRE(minutes.size() == 6);
    CHECK(minutes[2] == doctest::Approx(0.5));
    CHECK(minutes[3] == doctest::Approx(4.0));
    // Chords are a little shorter than their arc: within the arc tolerance.
    CHECK(minutes[4] == doctest::Approx(1.0 / 3).epsilon(1e-4));
    CHECK(minutes[5] == doctest::Approx(1.0).epsilon(1e-4));
    CHECK(minutes[6] == doctest::Approx(0.1));
    CHECK(minutes[7] == doctest::Approx(0.1));
    CHECK(feed_on(r.moves, 2) == doctest::Approx(100));
    double quarter = 10 * std::acos(-1.0) / 2;
    CHECK(feed_on(r.moves, 4) == doctest::Approx(3 * quarter));
    CHECK(feed_on(r.moves, 7) == doctest::Approx(300));
  }
}

TEST_CASE("feed modes: the path does not depend on the feed mode") {
  const std::string path = "X30 Y40\nG1 X0 Y40\nG3 X-10 Y30 R10\nG1 Z-2\n";
  auto with = [&](const std::string& mode, const std::string& f) {
    std::string text = "G0 X0 Y0 Z0 S500\n" + mode + "\n";
    for (std::size_t at = 0, next; at < path.size(); at = next + 1) {
      next = path.find('\n', at);
      text += (at == 0 ? "G1 " : "") + path.substr(at, next - at) + " F" + f + "\n";
    }
    return run_program(text, {}, linuxcnc_at_origin()).moves;
  };
  std::vector<Move> per_minute = with("G94", "200"), inverse = with("G93", "3"),
                    per_rev = with("G95", "0.2");
  REQUIRE(per_minute.size() == inverse.size());
  REQUIRE(per_minute.size() == per_rev.size());
  for (std::size_t i = 0; i < per_minute.size(); ++i) {
    CHECK(near(per_minute[i].end, inverse[i].end));
    CHECK(near(per_minute[i].end, per_rev[i].end));
    if (per_rev[i].kind != MoveKind::rapid) CHECK(per_rev[i].feed == doctest::Approx(0.2 * 500));
  }
}

TEST_CASE("feed modes: G95 feeds F per revolution at the spindle speed S, in program units") {
  Result r = run_program("G0 X0 Y0 Z0\nG95 G1 X10 F0.1 S1200\nS600 X20\nG20 X1 F0.01\n", {},
                         linuxcnc_at_origin());
  CHECK(feed_on(r.moves, 2) == doctest::Approx(120));
  CHECK(feed_on(r.moves, 3) == doctest::Approx(60));
  CHECK(feed_on(r.moves, 4) == doctest::Approx(0.01 * 25.4 * 600));
}

TEST_CASE(
    "feed modes: G94 and G95 clear the feed rate under LinuxCNC; elsewhere a change of mode does") {
  // rs274: G94 sets the feed rate to 0 (interp_convert.cc convert_feed_mode), even when already in
  // G94.
  Diagnostic d = error_of("F100\nG94\nG1 X1\n", {}, linuxcnc_at_origin());
  CHECK(d.line == 3);
  CHECK(d.message.find("no feed rate") != std::string::npos);
  CHECK_NOTHROW(run_program("F100\nG94\nG0 X0 Y0 Z0\nG1 X1\n", {}, at_origin()));
  d = error_of("G0 X0 Y0 Z0\nF100\nG93 G1 X1 F1\nG94\nG1 X2\n", {}, at_origin());
  CHECK(d.line == 5);
  // F on the G94 block itself counts (the mode is set first).
  CHECK_NOTHROW(run_program("G0 X0 Y0 Z0\nG94 F100\nG1 X1\n", {}, linuxcnc_at_origin()));
}

TEST_CASE("feed modes: LinuxCNC's errors, with line and column") {
  // Every G1/G2/G3 block in G93 needs its own F (NCE_F_WORD_MISSING_WITH_INVERSE_TIME_*).
  Diagnostic d = error_of("G0 X0 Y0 Z0\nG93 G1 X1 F2\nG1 X2\n", {}, linuxcnc_at_origin());
  CHECK(d.line == 3);
  CHECK(d.column == 1);
  CHECK(d.message.find("F word missing with inverse time") != std::string::npos);
  d = error_of("G0 X0 Y0 Z0\nG93 G1 X1 F2\n  G2 X3 I1 J0\n", {}, linuxcnc_at_origin());
  CHECK(d.line == 3);
  CHECK(d.column == 3);
  CHECK(d.message.find("F word missing with inverse time") != std::string::npos);
  d = error_of("G0 X0 Y0 Z0\nG93 G1 X1 F0\n", {}, linuxcnc_at_origin());
  CHECK(d.column == 11);
  CHECK(d.message.find("F0") != std::string::npos);
  d = error_of("G0 X0 Y0 Z5\nG93 G81 X1 Z-1 R1 F2\n", {}, linuxcnc_at_origin());
  CHECK(d.message.find("canned cycles cannot run in inverse time") != std::string::npos);
  d = error_of("G0 X0 Y0 Z0\nG95 G1 X1 F0.1\n", {}, linuxcnc_at_origin());
  CHECK(d.message.find("zero spindle speed") != std::string::npos);
  d = error_of("G0 X0 Y0 Z0\nS100 G95 F0.1\nG38.2 X1\n", {}, linuxcnc_at_origin());
  CHECK(d.message.find("feed per revolution") != std::string::npos);
  // A G0 in G93 needs no F; G93 alone is no move.
  CHECK_NOTHROW(run_program("G93\nG0 X0 Y0 Z0\nG0 X5\n", {}, linuxcnc_at_origin()));
}

TEST_CASE("feed modes: Fanuc's #4005 and #4109 read the mode and F of the block before") {
  // Each X is read before its block's codes apply: the mode (and F) the previous block left.
  Result r =
      run_program("G0 X0 Y0 Z0\nG93 G1 X1 F2\nG1 X#4005 F1\nG95 S10 G1 X#4005 F0.5\nG1 X#4109\n",
                  {}, at_origin());
  REQUIRE(r.moves.size() >= 4);
  CHECK(r.moves[r.moves.size() - 3].end.x == doctest::Approx(93));
  CHECK(r.moves[r.moves.size() - 2].end.x == doctest::Approx(93));
  CHECK(r.moves.back().end.x == doctest::Approx(0.5));
}
