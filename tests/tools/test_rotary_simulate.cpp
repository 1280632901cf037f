// `tridex simulate` on rotary-indexed 3+2: the bundled example's rotary twin (Haas DWO on the
// bc-trunnion profile) gives the same solid as the G68.2 example, and one tilted pocket written
// in each way of writing a plane (Fanuc G68.2 I J K, G68.2 P1, Mazak A B C, G68.2 P2 and P3,
// rotary words with DWO, rotary words under TCP) machines the same volume; and on every bundled
// profile, by its --machine name, the issue's four ways (G68.2, DWO, TCP, raw rotary words) give
// the same moves within 1e-6 mm and the same volume. The interpreter's side is in tests/gcode
// (test_rotary.cpp, test_tilted_words.cpp); this is the end-to-end check through the command.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"
#include "tridex/gcode/kinematics.hpp"
#include "tridex/gcode/machine.hpp"
#include "tridex/gcode/tilted_plane.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

namespace {

std::string num(double v) {
  char text[48];
  std::snprintf(text, sizeof text, "%.10f", v);
  return text;
}

std::string xyz(const Vec3& p) { return "X" + num(p.x) + " Y" + num(p.y) + " Z" + num(p.z); }

json simulate_report(const fs::path& dir, const std::string& name,
                     const std::vector<std::string>& more) {
  fs::path report = dir / (name + ".json");
  std::vector<std::string> args{"simulate", "--report", report.string(), "--quiet"};
  args.insert(args.end(), more.begin(), more.end());
  CommandResult r = run_tridex(args, dir);
  INFO(name << ": " << r.err);
  REQUIRE(r.status == 0);
  return json::parse(slurp(report));
}

}  // namespace

TEST_CASE("simulate: the rotary-indexed twin of the bundled example gives the same solid") {
  fs::path dir = scratch("rotary-twin");
  const std::string examples = std::string(TRIDEX_SOURCE_DIR) + "/gcode/examples/";
  const std::vector<std::string> common{"--tools",     examples + "mold_3plus2.tools.json",
                                        "--stock",     "box:0,0,0,100,80,50",
                                        "--dexel-res", "160"};
  std::vector<std::string> g682{examples + "mold_3plus2.nc"},
      twin{examples + "mold_3plus2_bc.nc", "--machine", examples + "mold_3plus2_bc.machine.json"};
  g682.insert(g682.end(), common.begin(), common.end());
  twin.insert(twin.end(), common.begin(), common.end());
  json a = simulate_report(dir, "g682", g682), b = simulate_report(dir, "twin", twin);
  // The twin's arcs are lines within 0.0005 mm and its coordinates are rounded to 0.0001 mm.
  const double volume = a["result"]["volume_mm3"].get<double>();
  CHECK(b["result"]["volume_mm3"].get<double>() == doctest::Approx(volume).epsilon(1e-5));
  CHECK(b["result"]["watertight"] == true);
  CHECK(a["result"]["removed_mm3"].get<double>() > 1e5);  // the part is machined, not the stock
  REQUIRE(a["groups"].size() == 5);
  REQUIRE(b["groups"].size() == a["groups"].size());
  for (std::size_t g = 0; g < a["groups"].size(); ++g)
    for (int i = 0; i < 3; ++i)
      CHECK(b["groups"][g]["axis"][i].get<double>() ==
            doctest::Approx(a["groups"][g]["axis"][i].get<double>()).epsilon(1e-9));
  fs::remove_all(dir);
}

TEST_CASE("simulate: one tilted pocket written every way gives the same volume") {
  fs::path dir = scratch("rotary-ways");
  write_text(dir / "tools.json",
             R"({"1": {"units": "mm", "shape": "ballnose", "diameter": 6, "length": 30}})");
  write_text(dir / "bc.json", R"({"kinematics": "bc-trunnion"})");
  // The plane: origin on the top face, Euler Z-X-Z (90, 30, 0): the tool leans 30° towards +X.
  const Vec3 o(20, 15, 20);
  const Frame f = gcode::fanuc_euler(o, 90, 30, 0);
  const Vec3 path[] = {{0, 0, 5},  {0, 0, -2}, {10, 0, -2}, {10, 8, -2},
                       {0, 8, -2}, {0, 0, -2}, {0, 0, 5}};
  // The feature-frame toolpath after a plane and its orienting code.
  auto in_plane = [&](const std::string& plane) {
    std::string p = "G21 G90 G54 T1 M6 S9000 M3\n" + plane +
                    "\nG0 X0 Y0 Z5\nG1 Z-2 F300\nG1 X10\nG1 Y8\nG1 X0\n"
                    "G1 Y0\nG0 Z5\nM30\n";
    return p;
  };
  // The same toolpath in the part's work coordinates, after rotary words (DWO or TCP).
  gcode::RotaryPositions bc =
      gcode::orient_tool(*gcode::kinematics_profile("bc-trunnion"), f.rotation[2], {});
  auto in_work = [&](const std::string& mode) {
    std::string p =
        "G21 G90 G54 T1 M6 S9000 M3\nG0 B" + num(bc[1]) + " C" + num(bc[2]) + "\n" + mode + "\n";
    for (std::size_t k = 0; k < std::size(path); ++k)
      p += std::string(k == 0 || k + 1 == std::size(path) ? "G0 " : "G1 ") +
           xyz(f.to_world(path[k])) + (k == 1 ? " F300" : "") + "\n";
    return p + "M30\n";
  };
  const Vec3 x = f.rotation[0], z = f.rotation[2];
  const std::pair<const char*, std::string> ways[] = {
      {"g682-ijk", in_plane("G68.2 " + xyz(o) + " I90 J30 K0\nG53.1")},
      {"g682-p1", in_plane("G68.2 P1 Q123 " + xyz(o) + " I30 J0 K90\nG53.1")},
      {"mazak-abc", in_plane("G68.2 " + xyz(o) + " A90 B30 C0\nG53.1")},
      {"g682-p2", in_plane("G68.2 P2 Q1 " + xyz(o) + "\nG68.2 P2 Q2 " + xyz(o + 5.0 * x) +
                           "\nG68.2 P2 Q3 " + xyz(f.to_world(Vec3(2, 7, 0))) + "\nG53.1")},
      {"g682-p3",
       in_plane("G68.2 P3 Q1 " + xyz(o) + " I" + num(x.x) + " J" + num(x.y) + " K" + num(x.z) +
                "\nG68.2 P3 Q2 I" + num(z.x) + " J" + num(z.y) + " K" + num(z.z) + "\nG53.1")},
      {"dwo", in_work("G254")},
      {"tcp", in_work("G43.4 H1")},
  };
  double reference = 0;
  for (const auto& [name, text] : ways) {
    write_text(dir / (std::string(name) + ".nc"), text);
    json r =
        simulate_report(dir, name,
                        {(dir / (std::string(name) + ".nc")).string(), "--tools",
                         (dir / "tools.json").string(), "--machine", (dir / "bc.json").string(),
                         "--stock", "box:0,0,0,40,30,20", "--dexel-cell", "0.25"});
    INFO(name);
    REQUIRE(r["groups"].size() == 1);
    for (int i = 0; i < 3; ++i)
      CHECK(r["groups"][0]["axis"][i].get<double>() == doctest::Approx(z[i]).epsilon(1e-9));
    double removed = r["result"]["removed_mm3"].get<double>();
    if (reference == 0) reference = removed;
    CHECK(removed > 100);  // the pocket cuts: 10 x 8 mm, 2 mm deep, with a 6 mm ball
    CHECK(removed == doctest::Approx(reference).epsilon(1e-6));
  }
  fs::remove_all(dir);
}

TEST_CASE("moves and simulate: one toolpath written four ways agrees on every bundled profile") {
  // The issue's equivalence, end to end through the command (`--machine NAME`): for a random
  // feature frame per profile, the same pocket written as G68.2 I J K + G53.1, as rotary words +
  // G254 (DWO), as rotary words under G43.4 (TCP) and as raw rotary words with the machine X Y Z
  // computed here from the kinematics, gives the same work-frame moves (1e-6 mm) and the same
  // machined volume. tests/gcode/test_rotary.cpp checks more frames at the interpreter's level.
  fs::path dir = scratch("rotary-four-ways");
  write_text(dir / "tools.json",
             R"({"1": {"units": "mm", "shape": "ballnose", "diameter": 6, "length": 30}})");
  std::mt19937 rng(1212);
  std::uniform_real_distribution<double> angle(-180, 180), tilt(5, 30);
  const Vec3 path[] = {{-5, -4, 5}, {-5, -4, -2}, {5, -4, -2}, {5, 4, -2},
                       {-5, 4, -2}, {-5, -4, -2}, {-5, -4, 5}};
  auto moves_of = [](const std::string& out) {
    std::vector<json> moves;
    std::istringstream in(out);
    for (std::string line; std::getline(in, line);)
      if (!line.empty()) moves.push_back(json::parse(line));
    return moves;
  };
  for (const std::string& profile : gcode::kinematics_profile_names()) {
    const gcode::Kinematics kin = *gcode::kinematics_profile(profile);
    const double drawn = angle(rng), j = tilt(rng), k = angle(rng);
    // One B axis (hmc-b-table) reaches the planes tilted about Y.
    const double i = kin.axes.size() == 1 ? 90 : drawn;
    const Vec3 o(20, 15, 20);  // the feature origin on the stock's top face
    const Frame f = gcode::fanuc_euler(o, i, j, k);
    const gcode::RotaryPositions r = gcode::orient_tool(kin, f.rotation[2], {});
    std::string index = "G0";
    for (const gcode::RotaryAxis& a : kin.axes)
      index += std::string(" ") + a.letter +
               num(r[static_cast<std::size_t>(gcode::rotary_index(a.letter))]);
    auto program = [&](const std::string& head, auto point, const std::string& tail) {
      std::string p = "G21 G90 G54 T1 M6 S9000 M3\n" + head + "\n";
      for (std::size_t n = 0; n < std::size(path); ++n)
        p += std::string(n == 0 || n + 1 == std::size(path) ? "G0 " : "G1 ") + xyz(point(path[n])) +
             (n == 1 ? " F300" : "") + "\n";
      return p + tail + "M30\n";
    };
    auto in_feature = [](const Vec3& p) { return p; };
    auto in_work = [&](const Vec3& p) { return f.to_world(p); };
    // Raw: X Y Z are the linear axes' machine position (the default machine's G54 is zero).
    auto in_machine = [&](const Vec3& p) {
      return gcode::machine_from_part(kin, f.to_world(p), r);
    };
    const std::pair<const char*, std::string> ways[] = {
        {"g682",
         program("G68.2 " + xyz(o) + " I" + num(i) + " J" + num(j) + " K" + num(k) + "\nG53.1",
                 in_feature, "G69\n")},
        {"dwo", program(index + "\nG254", in_work, "G255\n")},
        {"tcp", program("G43.4 H1\n" + index, in_work, "G49\n")},
        {"raw", program(index, in_machine, "")},
    };
    std::vector<json> reference_moves;
    double reference_volume = 0;
    for (const auto& [name, text] : ways) {
      INFO(profile << " " << name << " (I" << i << " J" << j << " K" << k << ")");
      const std::string file = (dir / (std::string(name) + ".nc")).string();
      write_text(file, text);
      CommandResult listed = run_tridex({"moves", file, "--machine", profile}, dir);
      INFO(listed.err);
      REQUIRE(listed.status == 0);
      std::vector<json> moves = moves_of(listed.out);
      REQUIRE(moves.size() == std::size(path));
      for (std::size_t c = 0; c < 3; ++c)
        CHECK(std::abs(moves[2]["end"][c].get<double>() -
                       f.to_world(path[2])[static_cast<int>(c)]) <= 1e-6);
      if (reference_moves.empty()) reference_moves = moves;
      for (std::size_t n = 0; n < moves.size(); ++n)
        for (const char* key : {"start", "end", "axis", "machine"})
          for (std::size_t c = 0; c < 3; ++c)
            CHECK(std::abs(moves[n][key][c].get<double>() -
                           reference_moves[n][key][c].get<double>()) <= 1e-6);
      json report =
          simulate_report(dir, std::string(name) + "-" + profile,
                          {file, "--tools", (dir / "tools.json").string(), "--machine", profile,
                           "--stock", "box:0,0,0,40,30,20", "--dexel-cell", "0.5"});
      const double removed = report["result"]["removed_mm3"].get<double>();
      CHECK(removed > 100);  // the 10 x 8 mm pocket, 2 mm deep, cuts
      if (reference_volume == 0) reference_volume = removed;
      CHECK(removed == doctest::Approx(reference_volume).epsilon(1e-6));
    }
  }
  fs::remove_all(dir);
}
