// Every Fusion 360 milling tool type (issue 31): each tool of a library, plunged 4 mm into a block,
// removes the volume of the solid of revolution its profile sweeps, ∫ π ρ(h)² dh, with ρ(h)
// written here from the type's published geometry (DC, SIG, TA, RE, tip-diameter), not from the
// cutter tridex builds. A type tridex cannot mill is an error naming the tool and its type.
#include <doctest/doctest.h>

#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>

#include "command_harness.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

namespace test_fusion_tools {

constexpr double kDepth = 4;  // mm below the block's top

double degrees(double a) { return a * M_PI / 180; }

// ∫0^depth π ρ(h)² dh by Simpson's rule on 4000 pieces.
double revolved_volume(const std::function<double(double)>& rho) {
  const int n = 4000;
  const double step = kDepth / n;
  double sum = 0;
  for (int k = 0; k <= n; ++k) {
    const double r = rho(k * step);
    sum += (k == 0 || k == n ? 1 : (k % 2 ? 4 : 2)) * M_PI * r * r;
  }
  return sum * step / 3;
}

json tool_entry(const std::string& type, int number, json geometry) {
  geometry["LCF"] = 10;
  geometry["LB"] = 30;
  geometry["OAL"] = 60;
  geometry["SFDM"] = 8;
  return {{"type", type},
          {"unit", "millimeters"},
          {"description", type},
          {"geometry", geometry},
          {"post-process", {{"number", number}}}};
}

struct Case {
  std::string type;
  json geometry;
  std::function<double(double)> rho;  // the radius at height h above the tip
};

std::vector<Case> cases() {
  const double t59 = std::tan(degrees(59)), t45 = 1, t10 = std::tan(degrees(10));
  const double ball = 1;  // the tapered ball's tip radius
  const double tangent_h = ball * (1 - std::sin(degrees(10)));
  return {
      {"drill", {{"DC", 6}, {"SIG", 118}}, [=](double h) { return std::min(3.0, h * t59); }},
      {"spot drill", {{"DC", 6}, {"SIG", 90}}, [=](double h) { return std::min(3.0, h * t45); }},
      {"center drill", {{"DC", 5}, {"SIG", 90}}, [=](double h) { return std::min(2.5, h); }},
      {"chamfer mill",
       {{"DC", 8}, {"tip-diameter", 2}, {"TA", 45}},
       [=](double h) { return std::min(4.0, 1 + h * t45); }},
      {"counter sink", {{"DC", 8}, {"SIG", 90}}, [=](double h) { return std::min(4.0, h); }},
      {"tapered mill",
       {{"DC", 2}, {"TA", 10}, {"RE", 0}},
       [=](double h) { return std::min(1 + 10 * t10, 1 + h * t10); }},
      {"tapered mill",
       {{"DC", 2}, {"TA", 10}, {"RE", 1}},
       [=](double h) {
         if (h <= tangent_h) return std::sqrt(ball * ball - (ball - h) * (ball - h));
         return std::min(1 + 10 * t10, ball * std::cos(degrees(10)) + (h - tangent_h) * t10);
       }},
      {"lollipop mill",
       {{"DC", 6}},
       [](double h) { return h < 3 ? std::sqrt(9 - (3 - h) * (3 - h)) : 3.0; }},
      {"thread mill", {{"DC", 6}}, [](double) { return 3.0; }},
      {"tap right hand", {{"DC", 6}, {"thread-pitch", 1}}, [](double) { return 3.0; }},
      {"tap left hand", {{"DC", 6}}, [](double) { return 3.0; }},
      {"reamer", {{"DC", 6}}, [](double) { return 3.0; }},
      {"slot mill", {{"DC", 6}}, [](double) { return 3.0; }},
  };
}

TEST_CASE("Fusion tool types: a plunge removes the volume of the solid the tool sweeps") {
  fs::path dir = scratch("fusion-types");
  write_text(dir / "plunge.nc",
             "G21 G90 G17\nT7 M6\nS5000 M3\nG0 X0 Y0 Z5\nG1 Z-4 F100\n"
             "G0 Z5\nM30\n");
  for (const Case& c : cases()) {
    CAPTURE(c.type);
    CAPTURE(c.geometry.dump());
    write_text(dir / "lib.json", json{{"data", {tool_entry(c.type, 7, c.geometry)}}}.dump());
    CommandResult r =
        run_tridex({"simulate", (dir / "plunge.nc").string(), "--tools",
                    (dir / "lib.json").string(), "--stock", "box:-6,-6,-6,6,6,0", "--dexel-cell",
                    "0.04", "--report", (dir / "report.json").string()},
                   dir);
    REQUIRE(r.status == 0);
    const json report = json::parse(slurp(dir / "report.json"));
    const double removed = report["result"]["removed_mm3"].get<double>();
    // The dexel surface cuts the hole's round wall on chords 0.04 mm apart: within 1 %.
    CHECK(removed == doctest::Approx(revolved_volume(c.rho)).epsilon(0.01));
    CHECK(r.out.find("tools: T7 ") != std::string::npos);
  }
  fs::remove_all(dir);
}

TEST_CASE("Fusion tool types: a tool tridex cannot mill is named with its type, never missing") {
  fs::path dir = scratch("fusion-unusable");
  write_text(dir / "plunge.nc", "G21 G90 G17\nT7 M6\nG0 X0 Y0 Z5\nG1 Z-4 F100\nM30\n");
  for (const std::string type : {"radius mill", "form mill", "probe"}) {
    CAPTURE(type);
    write_text(dir / "lib.json", json{{"data", {tool_entry(type, 7, {{"DC", 6}})}}}.dump());
    CommandResult r = run_tridex({"simulate", (dir / "plunge.nc").string(), "--tools",
                                  (dir / "lib.json").string(), "--stock", "box:-6,-6,-6,6,6,0"},
                                 dir);
    CHECK(r.status == 2);
    CHECK(r.err.find("plunge.nc:2: tool 7 is used, but") != std::string::npos);
    CHECK(r.err.find("is a Fusion \"" + type + "\"") != std::string::npos);
    CHECK(r.err.find("missing") == std::string::npos);
  }
  fs::remove_all(dir);
}

}  // namespace test_fusion_tools
