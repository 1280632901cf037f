// Rotary kinematics (kinematics.hpp): each bundled profile (machine.hpp) against poses worked out
// by hand and against the chain composed independently; random round trips (rotary positions → tool
// direction → inverse → the same direction; machine ↔ part maps invert each other; TCP/DWO
// positions agree with the raw machine-coordinate map); reachability, limits and the machine
// file's "kinematics" object with its errors.
#include <doctest/doctest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "helpers.hpp"
#include "tridex/error.hpp"
#include "tridex/gcode/kinematics.hpp"
#include "tridex/gcode/machine.hpp"
#include "tridex/gcode/tilted_plane.hpp"

using namespace tridex;
using namespace tridex::gcode;
using nlohmann::json;
using tridex::gcode::test::about;
using tridex::gcode::test::message_of;
using tridex::gcode::test::near;

namespace {

const Vec3 kX(1, 0, 0), kY(0, 1, 0), kZ(0, 0, 1);

Kinematics profile(const char* name) {
  std::optional<Kinematics> k = kinematics_profile(name);
  REQUIRE(k);
  return *k;
}

// Random positions inside each axis's limits (±400° for endless axes).
RotaryPositions random_pose(const Kinematics& kin, std::mt19937& rng) {
  RotaryPositions p{0, 0, 0};
  for (const RotaryAxis& axis : kin.axes) {
    double lo = axis.limits ? (*axis.limits)[0] : -400, hi = axis.limits ? (*axis.limits)[1] : 400;
    p[std::size_t(rotary_index(axis.letter))] = std::uniform_real_distribution<double>(lo, hi)(rng);
  }
  return p;
}

// The tip in the part frame composed by hand, axis by axis, for the bundled layouts: the table
// turned back (outer axis last), the head turned forward.
Vec3 tip_by_hand(const char* name, const Vec3& x, const RotaryPositions& r) {
  std::string n = name;
  double a = r[0], b = r[1], c = r[2];
  if (n == "ac-trunnion") {
    Vec3 pa(0, 0, -75);
    Vec3 on_a = about(kX, -a) * (x - pa) + pa;  // undo the tilt about the A line
    return about(kZ, -c) * on_a;                // then the platter's turn (C through the origin)
  }
  if (n == "bc-trunnion") {
    Vec3 pb(0, 0, -50);
    return about(kZ, -c) * (about(kY, -b) * (x - pb) + pb);
  }
  if (n == "b-head-c-table") {
    Vec3 pb(0, 0, 150);
    Vec3 tip = x + pb + about(kY, b) * (-pb);  // the tip swung about the head's pivot
    return about(kZ, -c) * tip;
  }
  if (n == "hmc-b-table") return about(kY, -b) * x;  // the B table about Y through the origin
  // LinuxCNC's sample configurations, from their kinematics' forward maps (trtfuncs.c,
  // xyzab_tdr_kins.comp): world = Rz(−C)·Rx(−A) / Rz(−C)·Ry(−B) / Rx(A)·Ry(B) about the pivots.
  if (n == "xyzac-trt") {
    Vec3 pa(0, 20, 10);
    return about(kZ, -c) * (about(kX, -a) * (x - pa) + pa);
  }
  if (n == "xyzbc-trt") {
    Vec3 pb(-20, 0, -15);
    return about(kZ, -c) * (about(kY, -b) * (x - pb) + pb);
  }
  if (n == "xyzab-tdr") {
    Vec3 pa(-20, 0, -10);
    return about(kX, a) * (about(kY, b) * x - pa) + pa;
  }
  // head-head: A's pivot turns with C about the spindle line.
  Vec3 pa(0, 0, 150);
  return x + about(kZ, c) * (pa + about(kX, a) * (-pa));
}

}  // namespace

TEST_CASE("bundled profiles: valid, vertical tool at zero, names listed") {
  for (const std::string& name : kinematics_profile_names()) {
    Kinematics kin = profile(name.c_str());
    CHECK_NOTHROW(kin.validate());
    CHECK(near(tool_direction(kin, {0, 0, 0}), kZ));
    CHECK(near(tip_in_part(kin, Vec3(1, 2, 3), {0, 0, 0}), Vec3(1, 2, 3)));
  }
  CHECK_FALSE(kinematics_profile("xyz"));
  CHECK(profile("ac-trunnion").type == MachineType::table_table);
  CHECK(profile("b-head-c-table").type == MachineType::head_table);
  CHECK(profile("head-head").type == MachineType::head_head);
}

TEST_CASE("ac-trunnion by hand") {
  Kinematics kin = profile("ac-trunnion");
  // A90 tilts the table's +Z to machine −Y, so the part's +Y now faces the spindle; C90 on top
  // of it turns the platter so that it is the part's +X.
  CHECK(near(tool_direction(kin, {90, 0, 0}), kY, 1e-12));
  CHECK(near(tool_direction(kin, {90, 0, 90}), kX, 1e-12));
  // The part origin (the C face centre) swings about the A line 75 mm below it.
  CHECK(near(machine_from_part(kin, Vec3(0), {90, 0, 0}), Vec3(0, -75, -75), 1e-12));
  CHECK(near(tip_in_part(kin, Vec3(0, -75, -75), {90, 0, 0}), Vec3(0), 1e-12));
}

TEST_CASE("head-head and b-head-c-table by hand") {
  Kinematics hh = profile("head-head");
  // C90 then A90: the spindle tilts to −Y about X, the C turn carries that to +X.
  CHECK(near(tool_direction(hh, {90, 0, 90}), kX, 1e-12));
  // The tip swings about A's pivot 150 mm up, (0, 150, 150) from the linear position, then
  // turns with C to (−150, 0, 150).
  CHECK(near(tip_in_part(hh, Vec3(0), {90, 0, 90}), Vec3(-150, 0, 150), 1e-12));
  CHECK(near(machine_from_part(hh, Vec3(10, 20, 30), {90, 0, 90}), Vec3(160, 20, -120), 1e-12));
  Kinematics bc = profile("b-head-c-table");
  // B90 turns the spindle to +X (right-handed about Y); C90 turns the table, so on the part the
  // tool points along −Y.
  CHECK(near(tool_direction(bc, {0, 90, 0}), kX, 1e-12));
  CHECK(near(tool_direction(bc, {0, 90, 90}), -kY, 1e-12));
}

TEST_CASE("every profile: the forward maps agree with the chain composed by hand") {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> length(-300, 300);
  for (const std::string& name : kinematics_profile_names()) {
    Kinematics kin = profile(name.c_str());
    for (int n = 0; n < 200; ++n) {
      RotaryPositions r = random_pose(kin, rng);
      Vec3 x(length(rng), length(rng), length(rng));
      Vec3 by_hand = tip_by_hand(name.c_str(), x, r);
      CHECK_MESSAGE(near(tip_in_part(kin, x, r), by_hand, 1e-9), name);
      // The tool direction is where the tip moves when the linear axes back off along it.
      Vec3 up = tip_by_hand(name.c_str(), x + head_offset(kin, r).rotation * kZ, r) - by_hand;
      CHECK_MESSAGE(near(tool_direction(kin, r), up, 1e-9), name);
    }
  }
}

TEST_CASE("every profile: machine and part maps invert each other; TCP/DWO agree with raw") {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> length(-300, 300);
  for (const std::string& name : kinematics_profile_names()) {
    Kinematics kin = profile(name.c_str());
    for (int n = 0; n < 200; ++n) {
      RotaryPositions r = random_pose(kin, rng);
      Vec3 p(length(rng), length(rng), length(rng)), x(length(rng), length(rng), length(rng));
      // TCP/DWO: the machine position for a part point; raw: the part point of a machine position.
      CHECK(near(tip_in_part(kin, machine_from_part(kin, p, r), r), p, 1e-9));
      CHECK(near(machine_from_part(kin, tip_in_part(kin, x, r), r), x, 1e-9));
      Frame m2p = machine_to_part(kin, r);
      CHECK(near(m2p.to_world(x), tip_in_part(kin, x, r), 1e-9));
      CHECK(near(m2p.inverse().to_world(p), machine_from_part(kin, p, r), 1e-9));
      // A rigid map: distances are kept.
      CHECK(glm::length(m2p.to_world(x) - m2p.to_world(p)) ==
            doctest::Approx(glm::length(x - p)).epsilon(1e-12));
    }
  }
}

TEST_CASE("every profile: rotary positions -> tool direction -> inverse -> the same direction") {
  std::mt19937 rng(23);
  for (const std::string& name : kinematics_profile_names()) {
    Kinematics kin = profile(name.c_str());
    for (int n = 0; n < 300; ++n) {
      RotaryPositions r = random_pose(kin, rng);
      Vec3 v = tool_direction(kin, r);
      // From the pose itself the nearest solution is the pose.
      RotaryPositions same = orient_tool(kin, v, r);
      for (int i = 0; i < 3; ++i)
        CHECK_MESSAGE(same[std::size_t(i)] == doctest::Approx(r[std::size_t(i)]).epsilon(1e-7),
                      name);
      // From elsewhere: some pose within the limits with the same direction.
      RotaryPositions from = random_pose(kin, rng);
      RotaryPositions got = orient_tool(kin, v, from);
      CHECK_MESSAGE(near(tool_direction(kin, got), v, 1e-9), name);
      CHECK_NOTHROW(check_limits(kin, got));
    }
  }
}

TEST_CASE("G53.1 reachability: every profile turns the tool to a G68.2 plane it can reach") {
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> angle(-180, 180), tilt(0, 30);
  for (const std::string& name : kinematics_profile_names()) {
    Kinematics kin = profile(name.c_str());
    for (int n = 0; n < 100; ++n) {
      Frame plane = fanuc_euler(Vec3(0), angle(rng), tilt(rng), angle(rng));
      // One axis reaches the planes it turns to: an HMC's B table, the vertical sides.
      if (kin.axes.size() == 1) plane = fanuc_euler(Vec3(0), 90, tilt(rng) * 3, 0);
      RotaryPositions r = orient_tool(kin, plane.rotation[2], {0, 0, 0});
      CHECK_MESSAGE(near(tool_direction(kin, r), plane.rotation[2], 1e-9), name);
    }
  }
}

TEST_CASE("the inverse: nearest turn, free axes, limits, unreachable directions") {
  Kinematics ac = profile("ac-trunnion");
  // A vertical tool leaves C free: it stays where it is.
  RotaryPositions r = orient_tool(ac, kZ, {30, 0, 123});
  CHECK(r[0] == doctest::Approx(0).epsilon(1e-12));
  CHECK(r[2] == 123);
  // Endless C: the turn nearest the current position (C = 90 + 360).
  RotaryPositions got = orient_tool(ac, kX, {80, 0, 440});
  CHECK(got[0] == doctest::Approx(90));
  CHECK(got[2] == doctest::Approx(450));
  // Of the two poses (A90 C90, A−90 C−90), the nearer one.
  got = orient_tool(ac, kX, {-80, 0, -80});
  CHECK(got[0] == doctest::Approx(-90));
  CHECK(got[2] == doctest::Approx(-90));

  // bc-trunnion: B −35…110; a tilt of 60° is reached with B+60 and C turned, 120° with neither.
  Kinematics bc = profile("bc-trunnion");
  Vec3 tilt60 = about(kY, 60) * kZ;
  got = orient_tool(bc, tilt60, {0, 0, 0});
  CHECK(got[1] == doctest::Approx(60));
  CHECK(std::abs(std::remainder(got[2], 360.0)) == doctest::Approx(180));
  std::string m = message_of([&] { orient_tool(bc, about(kY, 120) * kZ, {0, 0, 0}); });
  CHECK_MESSAGE(m.find("outside the rotary limits") != std::string::npos, m);
  CHECK_MESSAGE(m.find("-35 to 110") != std::string::npos, m);

  // One table axis A: only directions in the YZ plane.
  Kinematics a_only;
  a_only.type = MachineType::table_table;
  a_only.axes = {ac.axes[0]};
  CHECK(near(tool_direction(a_only, orient_tool(a_only, Vec3(0, 1, 1), {0, 0, 0})),
             glm::normalize(Vec3(0, 1, 1)), 1e-12));
  m = message_of([&] { orient_tool(a_only, kX, {0, 0, 0}); });
  CHECK_MESSAGE(m.find("not reachable") != std::string::npos, m);
  // A 45° nutating head over a C table reaches tilts up to 90°, never straight up the part's −Z.
  Kinematics nutating = profile("b-head-c-table");
  nutating.axes[0].direction = glm::normalize(Vec3(0, 1, 1));
  nutating.axes[0].limits.reset();
  CHECK(near(tool_direction(nutating, orient_tool(nutating, Vec3(1, 0, 0.2), {0, 0, 0})),
             glm::normalize(Vec3(1, 0, 0.2)), 1e-9));
  m = message_of([&] { orient_tool(nutating, -kZ, {0, 0, 0}); });
  CHECK_MESSAGE(m.find("not reachable") != std::string::npos, m);
  CHECK_THROWS_AS(orient_tool(ac, Vec3(0), {0, 0, 0}), tridex::Error);
}

TEST_CASE("check_limits names the axis, the position and the limits") {
  Kinematics ac = profile("ac-trunnion");
  CHECK_NOTHROW(check_limits(ac, {120, 0, 1e5}));
  std::string m = message_of([&] { check_limits(ac, {121, 0, 0}); });
  CHECK_MESSAGE(m.find("A121") != std::string::npos, m);
  CHECK_MESSAGE(m.find("-120 to 120") != std::string::npos, m);
}

TEST_CASE("machine file: a profile name or an object, checked key by key") {
  CHECK(kinematics_from_json(json("bc-trunnion")).axes[0].letter == 'B');
  json ac = json::parse(R"({"type": "table-table", "axes": [
      {"letter": "A", "on": "table", "direction": [2, 0, 0], "pivot": [0, 0, -75],
       "limits": [-120, 120]},
      {"letter": "c", "on": "table", "direction": [0, 0, 1], "pivot": [0, 0, 0]}]})");
  Kinematics kin = kinematics_from_json(ac);
  Kinematics want = profile("ac-trunnion");
  std::mt19937 rng(31);
  for (int n = 0; n < 50; ++n) {
    RotaryPositions r = random_pose(want, rng);
    CHECK(near(tip_in_part(kin, Vec3(5, 6, 7), r), tip_in_part(want, Vec3(5, 6, 7), r), 1e-12));
  }
  // sense −1 turns the axis the other way.
  json flipped = ac;
  flipped["axes"][1]["sense"] = -1;
  CHECK(near(tool_direction(kinematics_from_json(flipped), {90, 0, 90}), -kX, 1e-12));

  auto error = [](const json& j) { return message_of([&] { kinematics_from_json(j); }); };
  auto with = [&](const char* pointer, const json& value) {
    json j = ac;
    j[json::json_pointer(pointer)] = value;
    return error(j);
  };
  std::string m = with("/axes/0/direction", json::array({0, 0, 0}));
  CHECK_MESSAGE(m.find("kinematics.axes[0].direction") != std::string::npos, m);
  CHECK_MESSAGE(m.find("[0,0,0]") != std::string::npos, m);
  m = with("/axes/1/letter", "D");
  CHECK_MESSAGE(m.find("kinematics.axes[1].letter") != std::string::npos, m);
  CHECK_MESSAGE(m.find("\"D\"") != std::string::npos, m);
  m = with("/axes/0/limits", json::array({10, -10}));
  CHECK_MESSAGE(m.find("kinematics.axes[0].limits") != std::string::npos, m);
  m = with("/axes/0/on", "spindle");
  CHECK_MESSAGE(m.find("kinematics.axes[0].on") != std::string::npos, m);
  m = with("/axes/0/pivot", json::array({0, "x", 0}));
  CHECK_MESSAGE(m.find("kinematics.axes[0].pivot[1]") != std::string::npos, m);
  m = with("/axes/0/sense", 2);
  CHECK_MESSAGE(m.find("kinematics.axes[0].sense") != std::string::npos, m);
  m = with("/axes/0/pivots", json::array({0, 0, 0}));
  CHECK_MESSAGE(m.find("kinematics.axes[0].pivots: unknown key") != std::string::npos, m);
  m = with("/type", "head-head");
  CHECK_MESSAGE(m.find("head-head machine has no axis on the table") != std::string::npos, m);
  m = with("/axes/1/letter", "A");
  CHECK_MESSAGE(m.find("axis A appears twice") != std::string::npos, m);
  m = with("/axes/1/direction", json::array({3, 0, 0}));
  CHECK_MESSAGE(m.find("parallel") != std::string::npos, m);
  m = error(json("ab-trunnion"));
  CHECK_MESSAGE(m.find("\"ab-trunnion\"") != std::string::npos, m);
  CHECK_MESSAGE(m.find("ac-trunnion") != std::string::npos, m);
  m = error(json::parse(R"({"type": "table-table"})"));
  CHECK_MESSAGE(m.find("\"axes\" is missing") != std::string::npos, m);
  m = error(json::parse(R"({"type": "table-table", "axes": []})"));
  CHECK_MESSAGE(m.find("kinematics.axes") != std::string::npos, m);
  CHECK(message_of([&] {
          kinematics_from_json(json(3), "machine.kinematics");
        }).find("machine.kinematics") != std::string::npos);
}

TEST_CASE("travel: the machine file's linear travel and the rotary limits, axis by axis") {
  json j = json::parse(R"({"type": "table-table", "axes": [
      {"letter": "A", "on": "table", "direction": [1, 0, 0], "pivot": [0, 0, -75],
       "limits": [-120, 120]},
      {"letter": "C", "on": "table", "direction": [0, 0, 1], "pivot": [0, 0, 0]}],
      "travel": {"X": [-300, 300], "Z": [-400, 0]}})");
  Kinematics kin = kinematics_from_json(j);
  REQUIRE(kin.travel[0].has_value());
  CHECK(!kin.travel[1].has_value());  // Y not given: not limited
  // Brute force over a grid of positions: a violation exactly where a coordinate passes an end.
  for (double x : {-301.0, -300.0, 0.0, 300.0, 300.5})
    for (double z : {-400.5, -400.0, -1.0, 0.0, 2.0})
      for (double a : {-121.0, 0.0, 120.0, 130.0}) {
        std::vector<TravelViolation> v = travel_violations(kin, Vec3(x, 1e6, z), {a, 0, 7e5});
        std::vector<TravelViolation> want;
        if (x < -300) want.push_back({'X', x, -300});
        if (x > 300) want.push_back({'X', x, 300});
        if (z < -400) want.push_back({'Z', z, -400});
        if (z > 0) want.push_back({'Z', z, 0});
        if (a < -120) want.push_back({'A', a, -120});
        if (a > 120) want.push_back({'A', a, 120});
        REQUIRE(v.size() == want.size());
        for (std::size_t k = 0; k < v.size(); ++k) {
          CHECK(v[k].axis == want[k].axis);
          CHECK(v[k].value == want[k].value);
          CHECK(v[k].limit == want[k].limit);
        }
      }
  // A bundled profile with the machine's own travel.
  Kinematics bc =
      kinematics_from_json(json::parse(R"({"profile": "bc-trunnion", "travel": {"Y": [-5, 5]}})"));
  CHECK(bc.axes[0].letter == 'B');
  CHECK(travel_violations(bc, Vec3(0, 6, 0), {0, 0, 0}).size() == 1);
  auto error = [](const char* text) {
    return message_of([&] { kinematics_from_json(json::parse(text)); });
  };
  std::string m = error(R"({"profile": "bc-trunnion", "travel": {"Z": [1, -1]}})");
  CHECK_MESSAGE(m.find("kinematics.travel.Z") != std::string::npos, m);
  m = error(R"({"profile": "bc-trunnion", "travel": {"W": [1, 2]}})");
  CHECK_MESSAGE(m.find("kinematics.travel.W: unknown key") != std::string::npos, m);
  m = error(R"({"profile": "bc-trunnion", "axes": []})");
  CHECK_MESSAGE(m.find("kinematics.axes: unknown key") != std::string::npos, m);
  m = error(R"({"profile": "bc", "travel": {}})");
  CHECK_MESSAGE(m.find("kinematics.profile") != std::string::npos, m);
}
