// Tool tables (CAMotics schema, and Fusion's tool libraries) -> cutters, checked against the
// shapes' analytic profiles; the shank and holder parts.
#include <doctest/doctest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>

#include <nlohmann/json.hpp>

#include "errors.hpp"
#include "inputs/tool_table.hpp"

using namespace tridex;
using namespace tridex::cli;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

ToolTable parse(const std::string& text) {
  return ToolTable::from_json(json::parse(text), "table");
}

std::string error_of(const std::string& text) {
  try {
    parse(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("every CAMotics shape maps to the cutter with its analytic lower surface") {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> size(0.5, 20.0), unit(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    double d = size(random), length = size(random), snub = d * 0.8 * unit(random);
    double corner = (d / 2) * (0.05 + 0.9 * unit(random));
    bool inch = trial % 2 == 1;
    double s = inch ? 25.4 : 1.0;
    json table;
    const char* units = inch ? "inch" : "mm";
    table["1"] = {{"shape", "cylindrical"}, {"diameter", d}, {"length", length}, {"units", units}};
    table["2"] = {{"shape", "ballnose"}, {"diameter", d}, {"length", length}, {"units", units}};
    table["3"] = {{"shape", "conical"}, {"diameter", d}, {"length", length}, {"units", units}};
    table["4"] = {{"shape", "snubnose"},
                  {"diameter", d},
                  {"length", length},
                  {"units", units},
                  {"snub_diameter", snub}};
    table["5"] = {{"shape", "spheroid"}, {"diameter", d}, {"length", length}, {"units", units}};
    table["6"] = {{"shape", "bullnose"},
                  {"diameter", d},
                  {"length", length},
                  {"units", units},
                  {"corner-radius", corner}};
    ToolTable tools = ToolTable::from_json(table, "random");
    REQUIRE(tools.tools().size() == 6);
    double R = s * d / 2, L = s * length, r0 = s * snub / 2, rc = s * corner;
    for (int k = 1; k <= 6; ++k) CHECK(tools.find(k)->cutter.radius() == doctest::Approx(R));
    for (int sample = 0; sample < 20; ++sample) {
      double x = R * unit(random);
      CHECK(tools.find(1)->cutter.lower_height(x) == doctest::Approx(0).epsilon(1e-9));
      CHECK(tools.find(2)->cutter.lower_height(x) ==
            doctest::Approx(R - std::sqrt(R * R - x * x)).epsilon(1e-9));
      CHECK(tools.find(3)->cutter.lower_height(x) == doctest::Approx(x * L / R).epsilon(1e-9));
      double snub_h = x <= r0 ? 0 : (x - r0) * L / (R - r0);
      CHECK(tools.find(4)->cutter.lower_height(x) == doctest::Approx(snub_h).epsilon(1e-9));
      // The spheroid is a 64-piece chord polyline of the ellipse: above it by at most the
      // sagitta, never below.
      double b = L / 2, ellipse = b - b * std::sqrt(std::max(0.0, 1 - (x / R) * (x / R)));
      double h = tools.find(5)->cutter.lower_height(x);
      CHECK(h >= ellipse - 1e-9 * (1 + b));
      CHECK(h <= ellipse + 0.02 * b + 1e-9);
      double flat = R - rc;
      double bull =
          x <= flat ? 0 : rc - std::sqrt(std::max(0.0, rc * rc - (x - flat) * (x - flat)));
      CHECK(tools.find(6)->cutter.lower_height(x) == doctest::Approx(bull).epsilon(1e-9));
    }
  }
}

TEST_CASE("tool tables written by CAMotics load unchanged") {
  ToolTable tools = parse(R"({"1": {"units": "metric", "shape": "cylindrical", "length": 10,
      "diameter": 3.175, "description": "1/8 end mill"},
      "7": {"units": "imperial", "shape": "Ballnose", "length": 1, "diameter": 0.25}})");
  CHECK(tools.find(1)->description == "1/8 end mill");
  CHECK(tools.find(7)->cutter.radius() == doctest::Approx(3.175));
  CHECK(tools.find(7)->cutter.shape() == CutterShape::ball);
  CHECK(tools.find(2) == nullptr);
}

TEST_CASE("bad tool tables are refused with the tool and the key named") {
  CHECK(error_of("[1, 2]").find("JSON object keyed by tool number") != std::string::npos);
  CHECK(error_of(R"({"x": {"shape": "ballnose", "diameter": 2}})").find("tool number") !=
        std::string::npos);
  CHECK(error_of(R"({"3": {"shape": "drill", "diameter": 2}})")
            .find("tool 3: unknown shape \"drill\"") != std::string::npos);
  CHECK(error_of(R"({"4": {"shape": "ballnose"}})").find("tool 4: missing \"diameter\"") !=
        std::string::npos);
  CHECK(error_of(R"({"5": {"shape": "ballnose", "diameter": "big"}})")
            .find("\"diameter\" must be a number") != std::string::npos);
  CHECK(error_of(R"({"6": {"shape": "ballnose", "diameter": 0}})")
            .find("\"diameter\" must be positive") != std::string::npos);
  CHECK(error_of(R"({"7": {"shape": "ballnose", "diameter": 2, "units": "cubits"}})")
            .find("unknown \"units\"") != std::string::npos);
  CHECK(error_of(R"({"8": {"shape": "conical", "diameter": 2}})")
            .find("needs a positive \"length\"") != std::string::npos);
  CHECK(error_of(R"({"9": {"shape": "bullnose", "diameter": 2}})").find("\"corner-radius\"") !=
        std::string::npos);
  CHECK(error_of(R"({"10": {"shape": "bullnose", "diameter": 2, "corner-radius": 3}})")
            .find("tool 10") != std::string::npos);
  CHECK(error_of(R"({"11": {"shape": "snubnose", "diameter": 2, "length": 3, "snub_diameter": 2}})")
            .find("snub_diameter") != std::string::npos);
  CHECK(error_of(R"({"12": {"diameter": 2}})").find("missing \"shape\"") != std::string::npos);
}

TEST_CASE("the shank and holder keys give the tool's non-cutting parts") {
  ToolTable tools = parse(
      R"({"1": {"shape": "cylindrical", "diameter": 0.25, "units": "inch", "flute-length": 0.5,
      "shank-diameter": 0.375, "stick-out": 1.5,
      "holder": [{"bottom-diameter": 1, "top-diameter": 1, "length": 1}, {"bottom-diameter": 1, "top-diameter": 2, "length": 0.5}]},
      "2": {"shape": "ballnose", "diameter": 6, "flute-length": 12},
      "3": {"shape": "ballnose", "diameter": 6}})");
  const ToolBody& body = tools.find(1)->body;
  REQUIRE(body.parts.size() == 3);
  CHECK(body.stick_out == doctest::Approx(38.1));
  CHECK(body.parts[0].name == "shank");
  CHECK(body.parts[0].bottom == doctest::Approx(12.7));
  CHECK(body.parts[0].shape.bottom_radius == doctest::Approx(4.7625));
  CHECK(body.parts[0].shape.length == doctest::Approx(25.4));
  CHECK(body.parts[1].name == "holder section 1");
  CHECK(body.parts[1].bottom == doctest::Approx(38.1));
  CHECK(body.parts[2].name == "holder section 2");
  CHECK(body.parts[2].bottom == doctest::Approx(63.5));
  CHECK(body.parts[2].shape.top_radius == doctest::Approx(25.4));
  // The widening section's lower surface: its face, then the cone (0.5" up over 0.5" out).
  Cutter cone = part_surface(body.parts[2], 0);
  CHECK(cone.lower_height(10) == doctest::Approx(0));
  CHECK(cone.lower_height(20) == doctest::Approx(20 - 12.7));
  // Without a stick-out the shank goes on up; the shank diameter defaults to the cutter's.
  REQUIRE(tools.find(2)->body.parts.size() == 1);
  CHECK(tools.find(2)->body.parts[0].shape.bottom_radius == doctest::Approx(3));
  CHECK(!tools.find(2)->body.has_holder());
  CHECK(tools.find(3)->body.parts.empty());

  CHECK(
      error_of(
          R"({"4": {"shape": "ballnose", "diameter": 2, "holder": [{"bottom-diameter": 9, "top-diameter": 9, "length": 9}]}})")
          .find("tool 4: \"holder\" needs a positive \"stick-out\"") != std::string::npos);
  CHECK(
      error_of(
          R"({"5": {"shape": "ballnose", "diameter": 2, "stick-out": 9, "holder": [{"bottom-diameter": 9, "length": 9}]}})")
          .find("tool 5: \"holder\" section 1: missing \"top-diameter\"") != std::string::npos);
  CHECK(
      error_of(R"({"6": {"shape": "ballnose", "diameter": 2, "flute-length": 10, "stick-out": 5}})")
          .find("tool 6: \"flute-length\" 10 mm is longer than \"stick-out\" 5 mm") !=
      std::string::npos);
  CHECK(error_of(R"({"7": {"shape": "ballnose", "diameter": 2, "shank-diameter": 3}})")
            .find("tool 7: \"shank-diameter\" needs \"flute-length\"") != std::string::npos);
  CHECK(error_of(R"({"8": {"shape": "ballnose", "diameter": 2, "stick-out": 9, "holder": {}}})")
            .find("tool 8: \"holder\" must be a non-empty list") != std::string::npos);
}

namespace {

// A Fusion tool library written for the test from Autodesk's published schema (the library
// export's "data" list; geometry keys DC, LCF, LB, OAL, SFDM, RE; holder segments bottom first).
json fusion_library() {
  return json::parse(R"({"version": 18, "data": [
    {"type": "flat end mill", "unit": "millimeters", "description": "6mm flat", "guid": "a",
     "geometry": {"DC": 6, "LCF": 18, "LB": 30, "OAL": 60, "SFDM": 6, "RE": 0, "NOF": 3},
     "holder": {"type": "holder", "unit": "millimeters", "segments": [
        {"height": 10, "lower-diameter": 20, "upper-diameter": 20},
        {"height": 15, "lower-diameter": 32, "upper-diameter": 40}]},
     "post-process": {"number": 1, "comment": ""}},
    {"type": "ball end mill", "unit": "inches", "description": "1/4 ball", "guid": "b",
     "geometry": {"DC": 0.25, "LCF": 0.75, "LB": 1.25, "OAL": 2.5, "SFDM": 0.375, "RE": 0.125},
     "post-process": {"number": 2}},
    {"type": "bull nose end mill", "unit": "millimeters", "description": "10R1",
     "geometry": {"DC": 10, "LCF": 20, "LB": 35, "OAL": 75, "SFDM": 10, "RE": 1},
     "post-process": {"number": 3}},
    {"type": "drill", "unit": "millimeters", "description": "5mm jobber",
     "geometry": {"DC": 5, "SIG": 118, "LCF": 30, "LB": 40, "OAL": 80, "SFDM": 5},
     "post-process": {"number": 4}},
    {"type": "probe", "unit": "millimeters", "geometry": {"DC": 2}, "post-process": {"number": 5}},
    {"type": "holder", "unit": "millimeters", "segments": []}
  ]})");
}

std::string fusion_error(const std::function<void(json&)>& spoil) {
  json library = fusion_library();
  spoil(library);
  try {
    ToolTable::from_fusion_json(library, "lib.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("Fusion tool libraries: the cutting part, the shank and the holder") {
  ToolTable tools = ToolTable::from_fusion_json(fusion_library(), "lib.json");
  CHECK(tools.tools().size() == 4);  // the probe and the lone holder cannot cut
  const ToolSpec& flat = *tools.find(1);
  CHECK(flat.cutter.shape() == CutterShape::flat);
  CHECK(flat.cutter.radius() == doctest::Approx(3));
  CHECK(flat.description == "6mm flat");
  REQUIRE(flat.body.parts.size() == 3);
  CHECK(flat.body.parts[0].name == "shank");
  CHECK(flat.body.parts[0].bottom == doctest::Approx(18));
  CHECK(flat.body.parts[0].shape.length == doctest::Approx(12));
  CHECK(flat.body.stick_out == doctest::Approx(30));
  CHECK(flat.body.parts[1].bottom == doctest::Approx(30));
  CHECK(flat.body.parts[1].shape.bottom_radius == doctest::Approx(10));
  CHECK(flat.body.parts[2].bottom == doctest::Approx(40));
  CHECK(flat.body.parts[2].shape.bottom_radius == doctest::Approx(16));
  CHECK(flat.body.parts[2].shape.top_radius == doctest::Approx(20));
  CHECK(tools.find(2)->cutter.shape() == CutterShape::ball);
  CHECK(tools.find(2)->cutter.radius() == doctest::Approx(3.175));
  CHECK(tools.find(2)->body.parts[0].bottom == doctest::Approx(19.05));
  CHECK(tools.find(2)->body.parts[0].shape.bottom_radius == doctest::Approx(4.7625));  // SFDM 3/8"
  CHECK(!tools.find(2)->body.has_holder());
  CHECK(tools.find(3)->cutter.shape() == CutterShape::bull_nose);
  CHECK(tools.find(3)->cutter.corner_radius() == doctest::Approx(1));
  // The drill: a cone of half its point angle (issue 31: it was skipped, and then "missing").
  REQUIRE(tools.find(4) != nullptr);
  CHECK(tools.find(4)->cutter.radius() == doctest::Approx(2.5));
  CHECK(tools.find(4)->cutter.lower_height(2.5) ==
        doctest::Approx(2.5 / std::tan(glm::radians(59.0))));
  // The probe is held, to be named with its type if a program uses it.
  CHECK(tools.find(5) == nullptr);
  REQUIRE(tools.unusable(5) != nullptr);
  CHECK(tools.unusable(5)->find("tool 5 is a Fusion \"probe\", not a cutter") != std::string::npos);

  // A library file is told from a CAMotics table by its "data" list.
  fs::path file =
      fs::temp_directory_path() / ("tridex-fusion-" + std::to_string(::getpid()) + ".json");
  std::ofstream(file) << fusion_library().dump(1);
  CHECK(ToolTable::read(file).find(3) != nullptr);
  fs::remove(file);
}

TEST_CASE("Fusion tool libraries: a missing or malformed field names the tool and the field") {
  auto has = [](const std::string& message, const std::string& part) {
    INFO(message);
    CHECK(message.find(part) != std::string::npos);
  };
  has(fusion_error([](json& l) { l["data"][0]["geometry"].erase("DC"); }),
      "lib.json: tool 1 (\"6mm flat\"): \"geometry\": missing \"DC\"");
  has(fusion_error([](json& l) { l["data"][0]["geometry"].erase("LB"); }),
      "tool 1 (\"6mm flat\"): \"geometry\": missing \"LB\"");
  has(fusion_error([](json& l) { l["data"][1]["geometry"]["LCF"] = "long"; }),
      "tool 2 (\"1/4 ball\"): \"geometry\": \"LCF\" must be a number, got a string");
  has(fusion_error([](json& l) { l["data"][2]["geometry"].erase("RE"); }),
      "tool 3 (\"10R1\"): \"geometry\": missing \"RE\"");
  has(fusion_error([](json& l) { l["data"][0]["holder"]["segments"][1].erase("height"); }),
      "tool 1 (\"6mm flat\"): \"holder\": \"segments\"[1]: missing \"height\"");
  has(fusion_error([](json& l) { l["data"][0]["holder"]["segments"][0]["lower-diameter"] = -3; }),
      "\"lower-diameter\" must be a finite non-negative number, got -3");
  has(fusion_error([](json& l) { l["data"][0]["geometry"]["LB"] = 70; }),
      "\"LB\" 70 mm is longer than \"OAL\" 60 mm");
  has(fusion_error([](json& l) { l["data"][0]["geometry"]["LCF"] = 40; }),
      "\"LCF\" 40 mm is longer than \"LB\" 30 mm");
  has(fusion_error([](json& l) { l["data"][1].erase("post-process"); }),
      "\"data\"[1] (\"1/4 ball\"): missing \"post-process\"");
  has(fusion_error([](json& l) { l["data"][1]["post-process"]["number"] = 1; }),
      "\"data\"[0] and \"data\"[1] are both tool 1");
  has(fusion_error([](json& l) { l["data"][0]["unit"] = "cubits"; }),
      "unknown \"unit\" \"cubits\"");
  has(fusion_error([](json& l) { l["data"][0].erase("type"); }), "\"data\"[0]: missing \"type\"");
  has(fusion_error([](json& l) { l["data"] = 3; }), "must be a JSON object with a \"data\" list");
}

TEST_CASE("LinuxCNC .tbl tool tables: diameters and lengths in inches, comments as descriptions") {
  ToolTable table = ToolTable::from_tbl(
      "T1 P1 D0.125000 Z+0.511000 ;1/8 end mill\n"
      "\n"
      "; a comment line\n"
      "t2 p2 z-0.25 d0.5 x0 i0 ;lower case, a negative length\n"
      "T98876 P543 Z+0.100000 ;no diameter: a length, no cutter\n",
      "sim.tbl");
  REQUIRE(table.tools().size() == 2);
  const ToolSpec* one = table.find(1);
  REQUIRE(one != nullptr);
  CHECK(one->diameter_mm == doctest::Approx(3.175));
  CHECK(one->shape == "cylindrical");
  CHECK(one->description == "1/8 end mill");
  CHECK(table.find(2)->diameter_mm == doctest::Approx(12.7));
  CHECK(table.find(98876) == nullptr);
  REQUIRE(table.tool_lengths().size() == 3);
  CHECK(table.tool_lengths().at(1) == doctest::Approx(12.9794));
  CHECK(table.tool_lengths().at(2) == doctest::Approx(-6.35));
  CHECK(table.tool_lengths().at(98876) == doctest::Approx(2.54));
}

TEST_CASE("LinuxCNC .tbl tool tables in mm (a machine whose LINEAR_UNITS are mm)") {
  ToolTable table = ToolTable::from_tbl("T1 P1 D6 Z+50.5 ;6 mm\n", "mm.tbl", 1.0);
  REQUIRE(table.find(1) != nullptr);
  CHECK(table.find(1)->diameter_mm == 6);
  CHECK(table.tool_lengths().at(1) == 50.5);
}

TEST_CASE("LinuxCNC .tbl tool tables: bad lines name file, line, column and the word") {
  auto error_of_tbl = [](const std::string& text) {
    try {
      ToolTable::from_tbl(text, "t.tbl");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(error_of_tbl("T1 D0.1\nT2 Zfoo\n").find("t.tbl:2:4: \"Zfoo\"") != std::string::npos);
  CHECK(error_of_tbl("P1 D0.1\n").find("t.tbl:1: no tool number T") != std::string::npos);
  CHECK(error_of_tbl("T1.5 D0.1\n").find("t.tbl:1:1: T1.5") != std::string::npos);
  CHECK(error_of_tbl("T1 D0.1\nT1 D0.2\n").find("tool 1 again (first at line 1)") !=
        std::string::npos);
  CHECK(error_of_tbl("T1 D0.1 Y0.2\n").find("t.tbl:1:9: tool 1 has a sideways offset Y0.2") !=
        std::string::npos);
  CHECK(error_of_tbl("T1 D0.1 Z1 Z2\n").find("repeated word Z") != std::string::npos);
  CHECK(error_of_tbl("T1 D-0.1\n").find("must not be negative") != std::string::npos);
}

TEST_CASE("LinuxCNC .tbl tool tables: a missing file or a directory is an input error naming it") {
  const fs::path dir = fs::temp_directory_path() / ("tridex-tbl-" + std::to_string(::getpid()));
  fs::create_directories(dir / "folder.tbl");
  auto error_of_read = [](const fs::path& path) {
    try {
      ToolTable::read(path);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(error_of_read(dir / "folder.tbl").find("folder.tbl: is a directory, not a tool table") !=
        std::string::npos);
  CHECK(error_of_read(dir / "none.tbl").find("none.tbl: no such file") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("LinuxCNC .tbl tool tables: the sample configurations' tables load") {
  // LinuxCNC's own tables (GPL: read where the package installed them, not copied here).
  const fs::path sim = "/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/simtcl/sim.tbl";
  if (!fs::exists(sim)) {
    MESSAGE("SKIPPED: " << sim << " not found (Debian package linuxcnc-uspace)");
    return;
  }
  ToolTable table = ToolTable::read(sim);
  CHECK(table.tool_lengths().at(1) == doctest::Approx(0.511 * 25.4));  // rs274's own default table
  CHECK(table.find(3)->diameter_mm == doctest::Approx(0.201 * 25.4));
}

TEST_CASE("a JSON tool table's \"tool-length\" is the length for G43") {
  ToolTable table = parse(R"({"1": {"shape": "cylindrical", "diameter": 6, "tool-length": 75.5},
                              "2": {"shape": "ballnose", "diameter": 0.25, "units": "inch", "tool_length": -1},
                              "3": {"shape": "cylindrical", "diameter": 6, "length": 20}})");
  REQUIRE(table.tool_lengths().size() == 2);
  CHECK(table.tool_lengths().at(1) == 75.5);
  CHECK(table.tool_lengths().at(2) == doctest::Approx(-25.4));
  CHECK(error_of(R"({"1": {"shape": "cylindrical", "diameter": 6, "tool-length": "long"}})")
            .find("table: tool 1: \"tool-length\" must be a finite number") != std::string::npos);
}

TEST_CASE("LinuxCNC .tbl: an entry without Z has length 0, as LinuxCNC reads it") {
  // xyzbc-trt.tbl (LinuxCNC's sample) is `T1 P1 D1` with G43 H1 in its demo.
  ToolTable table = ToolTable::from_tbl("T1 P1 D1\nT2 P2 Z10 D8\nT3 P3\n", "xyzbc.tbl", 1.0);
  REQUIRE(table.tool_lengths().size() == 3);
  CHECK(table.tool_lengths().at(1) == 0);
  CHECK(table.tool_lengths().at(2) == 10);
  CHECK(table.tool_lengths().at(3) == 0);  // no D either: in the table, a length of 0
}
