#include <doctest/doctest.h>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace {
std::vector<Vec3> ends(const Result& r, MoveKind kind) {
  std::vector<Vec3> out;
  for (const Move& m : r.moves)
    if (m.kind == kind) out.push_back(m.end);
  return out;
}
}  // namespace

TEST_CASE("G81 with G98 and G99: retract levels") {
  Result r = run_program("G90 F100\nG0 X0 Y0 Z10\nG99 G81 X1 Y1 Z-2 R1\nG98 X2\nG80\nM30\n", {},
                         at_origin());
  std::vector<Vec3> want = {Vec3(1, 1, 10), Vec3(1, 1, 1), Vec3(1, 1, -2), Vec3(1, 1, 1),
                            Vec3(2, 1, 1),  Vec3(2, 1, 1), Vec3(2, 1, -2), Vec3(2, 1, 10)};
  std::vector<Vec3> got = ends(r, MoveKind::cycle);
  REQUIRE(got.size() == want.size());
  for (std::size_t i = 0; i < want.size(); ++i) CHECK(near(got[i], want[i]));
  for (const Move& m : r.moves)
    if (m.feed > 0) CHECK(m.end.z < m.start.z);  // G81 feeds only go down
}

TEST_CASE("G83/G73 pecks: each step at most Q deeper, the last at the bottom, random depths") {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(0.1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    double r_level = std::stod(fmt(u(rng) * 3)), bottom = std::stod(fmt(-u(rng) * 20)),
           q = std::stod(fmt(u(rng) * 4));
    bool g83 = rng() % 2;
    std::string program = cat("G90 F100\nG0 X0 Y0 Z10\n", g83 ? "G83" : "G73", " X3 Y4 Z",
                              fmt(bottom), " R", fmt(r_level), " Q", fmt(q), "\nG80\nM30\n");
    Result r = run_program(program, {}, at_origin());
    double deepest = r_level;
    int feeds = 0;
    for (const Move& m : r.moves) {
      if (m.kind != MoveKind::cycle) continue;
      CHECK(m.end.x == 3);
      if (m.feed > 0) {
        ++feeds;
        CHECK(m.end.z < m.start.z);
        CHECK(m.end.z >= deepest - q - 1e-9);
        CHECK(m.end.z >= bottom - 1e-12);
        // G73 backs off by the clearance; G83 comes back down to it above the last depth.
        CHECK(m.start.z <= deepest + 0.254 + 1e-9);
        deepest = std::min(deepest, m.end.z);
      } else {
        CHECK(m.end.z <= 10 + 1e-12);
      }
    }
    CHECK(deepest == doctest::Approx(bottom));
    CHECK(feeds == static_cast<int>(std::ceil((r_level - bottom) / q - 1e-9)));
    CHECK(r.moves.back().end.z == doctest::Approx(10));  // G98 default: back to the start level
  }
}

TEST_CASE("G85/G89 feed out, G86 rapids out; L repeats step under G91") {
  Result r = run_program(
      "G90 F100\nG0 X0 Y0 Z5\nG85 X1 Y0 Z-3 R1\nG80\n"
      "G91 G99 G81 X2 Y1 Z-4 R-3 L3\nG90 G80\nM30\n",
      {}, at_origin());
  std::vector<Move> cycle;
  for (const Move& m : r.moves)
    if (m.kind == MoveKind::cycle) cycle.push_back(m);
  // G85: XY, R, down (feed), up to R (feed), back to 5.
  REQUIRE(cycle.size() >= 5);
  CHECK(cycle[3].feed > 0);
  CHECK(near(cycle[3].end, Vec3(1, 0, 1)));
  CHECK(near(cycle[4].end, Vec3(1, 0, 5)));
  // G91 repeats: R = 5 - 3 = 2, bottom = R - 4 = -2, holes at x = 3, 5, 7; y = 1, 2, 3.
  std::vector<Vec3> bottoms;
  for (std::size_t i = 5; i < cycle.size(); ++i)
    if (cycle[i].feed > 0) bottoms.push_back(cycle[i].end);
  REQUIRE(bottoms.size() == 3);
  for (int k = 0; k < 3; ++k)
    CHECK(near(bottoms[static_cast<std::size_t>(k)], Vec3(3 + 2 * k, 1 + k, -2)));
  // K is the Fanuc spelling of the repeat count.
  Result k =
      run_program("G90 F100\nG0 X0 Y0 Z5\nG91 G81 X1 Z-1 R-1 K2\nG90 G80\nM30\n", {}, at_origin());
  CHECK(near(k.moves.back().end, Vec3(2, 0, 5)));
}

TEST_CASE(
    "G84/G74 tapping back out at feed: to R on Fanuc, to the clear level on LinuxCNC; P kept on "
    "any Fanuc cycle") {
  const std::string program =
      "G90 F100 S500 M3\nG0 X0 Y0 Z10\nG98 G84 X1 Y1 Z-3 R2 P200\nG80\nM30\n";
  for (const Dialect dialect : {Dialect::fanuc, Dialect::haas, Dialect::linuxcnc}) {
    CAPTURE(static_cast<int>(dialect));
    MachineConfig machine = at_origin();
    machine.dialect = dialect;
    Result r = run_program(program, {}, machine);
    std::vector<Move> cycle;
    for (const Move& m : r.moves)
      if (m.kind == MoveKind::cycle) cycle.push_back(m);
    // XY at the initial level, down to R, down at feed, up at feed, then (Fanuc) a rapid to 10.
    const bool linuxcnc = dialect == Dialect::linuxcnc;
    REQUIRE(cycle.size() == (linuxcnc ? 4u : 5u));
    CHECK(cycle[2].feed > 0);
    CHECK(near(cycle[2].end, Vec3(1, 1, -3)));
    CHECK(cycle[3].feed > 0);
    CHECK(near(cycle[3].end, Vec3(1, 1, linuxcnc ? 10 : 2)));
    if (!linuxcnc) {
      CHECK(cycle[4].feed == 0);
      CHECK(near(cycle[4].end, Vec3(1, 1, 10)));
    }
  }
  // G74 (left hand) goes the same way; LinuxCNC's rs274 takes no L on either.
  auto same_ends = [](const Result& a, const Result& b) {
    REQUIRE(a.moves.size() == b.moves.size());
    for (std::size_t i = 0; i < a.moves.size(); ++i) CHECK(near(a.moves[i].end, b.moves[i].end));
  };
  same_ends(run_program("G90 F100 S500 M4\nG0 X0 Y0 Z10\nG99 G74 X1 Y1 Z-3 R2\nX2\nG80\nM30\n", {},
                        at_origin()),
            run_program("G90 F100 S500 M4\nG0 X0 Y0 Z10\nG99 G85 X1 Y1 Z-3 R2\nX2\nG80\nM30\n", {},
                        at_origin()));
  CHECK(error_of("G90 F100\nG0 X0 Y0 Z10\nG84 X1 Z-3 R2 L2\n", {}, linuxcnc_at_origin())
            .message.find("no repeats") != std::string::npos);
  // A P written on G81 (a post's habit): modal cycle data on Fanuc, an unused word on LinuxCNC.
  same_ends(run_program("G90 F100\nG0 X0 Y0 Z10\nG81 X1 Z-3 R2 P500\nG80\nM30\n", {}, at_origin()),
            run_program("G90 F100\nG0 X0 Y0 Z10\nG81 X1 Z-3 R2\nG80\nM30\n", {}, at_origin()));
  CHECK(error_of("G90 F100\nG0 X0 Y0 Z10\nG81 X1 Z-3 R2 P500\n", {}, linuxcnc_at_origin())
            .message.find("P500") != std::string::npos);
}

TEST_CASE("cycle errors: missing words, bottom above R, wrong axis, retracted incremental") {
  CHECK(error_of("G0 X0 Y0 Z5\nG81 X1 Z-1 F10\n").message.find("needs R") != std::string::npos);
  CHECK(error_of("G0 X0 Y0 Z5\nG83 X1 Z-1 R1 F10\n").message.find("Q") != std::string::npos);
  CHECK(error_of("G0 X0 Y0 Z5\nG81 X1 Z2 R1 F10\n").message.find("above") != std::string::npos);
  CHECK(error_of("G0 X0 Y0 Z5\nG18 G81 X1 Y-1 R1 F10\n").message.find("spindle") !=
        std::string::npos);
  CHECK(error_of("G91 G81 X1 Z-1 R1 F10\n").message.find("retracted") != std::string::npos);
  CHECK(error_of("G0 X0 Y0 Z5\nG81 X1 Z-1 R1 F10 L2 K2\n").column == 22);
  // From far (program start) a cycle comes straight down onto its R plane.
  Result r = run_program("G90 F100\nG81 X4 Y5 Z-1 R2\nM30\n");
  REQUIRE(r.moves.size() == 3);
  CHECK(near(r.moves[0].start, Vec3(4, 5, 2 + MachineConfig::kDefaultFar)));
  CHECK(near(r.moves[0].end, Vec3(4, 5, 2)));
}

TEST_CASE("subprograms: M98 P L / M99 give the moves of the inline expansion (random programs)") {
  std::mt19937_64 rng(23);
  for (int trial = 0; trial < 100; ++trial) {
    int subs = 1 + static_cast<int>(rng() % 3);
    std::vector<std::string> bodies;
    for (int s = 0; s < subs; ++s) {
      std::string body = "G91\n";
      int n = 1 + static_cast<int>(rng() % 4);
      for (int i = 0; i < n; ++i)
        body += cat("G1 X", static_cast<int>(rng() % 9) - 4, " Y", static_cast<int>(rng() % 9) - 4,
                    "\n");
      // A nested call from the last subprogram to the first.
      if (s == subs - 1 && s > 0 && rng() % 2) body += "M98 P1001\nG91\n";
      body += "G90\n";
      bodies.push_back(body);
    }
    auto expand = [&](int s) {
      std::string text = bodies[static_cast<std::size_t>(s)];
      std::size_t at = text.find("M98 P1001\n");
      if (at != std::string::npos) text.replace(at, 10, bodies[0]);
      return text;
    };
    std::string main = "%\nO1\nG90 G21 F100\nG0 X0 Y0 Z1\n", inline_text = main;
    int calls = 1 + static_cast<int>(rng() % 4);
    for (int c = 0; c < calls; ++c) {
      int s = static_cast<int>(rng() % static_cast<unsigned>(subs));
      int l = static_cast<int>(rng() % 3) + 1;
      main += cat("M98 P", 1001 + s, " L", l, "\n");
      for (int i = 0; i < l; ++i) inline_text += expand(s);
      main += "G1 X0 Y0\n";
      inline_text += "G1 X0 Y0\n";
    }
    main += "M30\n";
    inline_text += "M30\n";
    for (int s = 0; s < subs; ++s)
      main += cat("O", 1001 + s, " (sub)\n", bodies[static_cast<std::size_t>(s)], "M99\n");
    main += "%\n";
    Result a = run_program(main), b = run_program(inline_text);
    REQUIRE(a.moves.size() == b.moves.size());
    for (std::size_t i = 0; i < a.moves.size(); ++i) {
      CHECK(near(a.moves[i].start, b.moves[i].start));
      CHECK(near(a.moves[i].end, b.moves[i].end));
    }
  }
}

TEST_CASE("subprogram errors and flow") {
  Diagnostic d = error_of("G0 X0 Y0 Z1\nM98 P77\nM30\n");
  CHECK(d.line == 2);
  CHECK(d.message.find("O77") != std::string::npos);
  d = error_of("O1\nM98 P2\nM30\nO2\nM98 P2\nM99\n");
  CHECK(d.message.find("nested") != std::string::npos);
  d = error_of("O1\nM98 P2\nM30\nO2\nG0 X1\n");
  CHECK(d.message.find("M99") != std::string::npos);
  d = error_of("O1\nG0 X1 Y1 Z1\nO2\nG0 X2\n");
  CHECK(d.line == 3);
  CHECK(d.message.find("M30") != std::string::npos);
  Result r = run_program("G0 X0 Y0 Z1\nM99\nG0 X5\n");
  CHECK(r.moves.size() == 1);
  CHECK(r.warnings.size() == 1);
  // A subprogram before the main program's end, reached by a call, and M98 L0 (no call).
  r = run_program("O1\nG0 X0 Y0 Z1\nM98 P5 L0\nM98 P5\nM30\nO5\nG0 X3\nM99\n");
  REQUIRE(r.moves.size() == 2);
  CHECK(r.moves[1].line == 7);
  // M98 on a stream that cannot seek: a jump within the read buffer (64 KiB) works, one further
  // back is an error.
  struct OneWay : std::streambuf {
    std::string text = "G0 X0 Y0 Z1\nM98 P5\nM30\n" + std::string(70000, ' ') + "\nO5\nM99\n";
    OneWay() { setg(text.data(), text.data(), text.data() + text.size()); }
    pos_type seekoff(off_type, std::ios_base::seekdir, std::ios_base::openmode) override {
      return pos_type(off_type(-1));
    }
  } one_way;
  std::istream in(&one_way);
  Interpreter interpreter;
  CHECK_THROWS_AS(interpreter.run(in, "pipe", [](const Move&) {}), GcodeError);
}

// LinuxCNC goes on through a bare O number met in the flow (interp_o_word.cc, case O_), in the
// main program and in an M98 subprogram; each case as rs274 prints it. pcb2gcode's Mach3 output
// (main program, then "O200" ... M99, then M2) was refused as running into O200.
TEST_CASE("LinuxCNC: the flow goes on through a bare O number, as rs274 does") {
  const MachineConfig linuxcnc = linuxcnc_at_origin();
  auto ends = [](const Result& r) {
    std::vector<double> x;
    for (const Move& m : r.moves) x.push_back(m.end.x);
    return x;
  };
  // rs274: X1, X2, then M99 in the main program ends it (X3 never runs).
  Result r = run_program("G21 G90\nG0 X1\nO100\nG0 X2\nM99\nG0 X3\nM2\n", {}, linuxcnc);
  CHECK(ends(r) == std::vector<double>{1, 2});
  // rs274: a first O number after other blocks is passed over too.
  r = run_program("G21 G90\nO1\nG0 X1\nO2\nG0 X2\nM30\n", {}, linuxcnc);
  CHECK(ends(r) == std::vector<double>{1, 2});
  // rs274: X1, the subprogram's X2 and, through O200, X3 before its M99, then X5.
  r = run_program("G21 G90\nG0 X1\nM98 P100\nG0 X5\nM30\nO100\nG0 X2\nO200\nG0 X3\nM99\nM2\n", {},
                  linuxcnc);
  CHECK(ends(r) == std::vector<double>{1, 2, 3, 5});
  // Inside an o-word call it is an error (rs274: "Fanuc 'O....' subroutine must be called with
  // 'M98'").
  Diagnostic d =
      error_of("G21 G90\no100 call\nM2\no100 sub\nO5\nG0 X2\no100 endsub\n", {}, linuxcnc);
  CHECK(d.line == 5);
  CHECK(d.message.find("M98") != std::string::npos);
  // Fanuc and Haas keep refusing a main program that runs into the next O number.
  CHECK(error_of("G21 G90\nG0 X1 Y0 Z0\nO100\nG0 X2\nM99\n", {}, at_origin())
            .message.find("M2/M30") != std::string::npos);
}
