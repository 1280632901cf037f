// Tool tables (CAMotics schema) -> cutters, checked against the shapes' analytic profiles.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include <nlohmann/json.hpp>

#include "errors.hpp"
#include "tool_table.hpp"

using namespace tridex;
using namespace tridex::cli;
using nlohmann::json;

namespace {

ToolTable parse(const std::string& text) { return ToolTable::from_json(json::parse(text), "table"); }

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
    table["4"] = {{"shape", "snubnose"}, {"diameter", d}, {"length", length}, {"units", units},
                  {"snub_diameter", snub}};
    table["5"] = {{"shape", "spheroid"}, {"diameter", d}, {"length", length}, {"units", units}};
    table["6"] = {{"shape", "bullnose"}, {"diameter", d}, {"length", length}, {"units", units},
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
      double bull = x <= flat ? 0 : rc - std::sqrt(std::max(0.0, rc * rc - (x - flat) * (x - flat)));
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
  CHECK(error_of(R"({"x": {"shape": "ballnose", "diameter": 2}})").find("tool number") != std::string::npos);
  CHECK(error_of(R"({"3": {"shape": "drill", "diameter": 2}})").find("tool 3: unknown shape \"drill\"") != std::string::npos);
  CHECK(error_of(R"({"4": {"shape": "ballnose"}})").find("tool 4: missing \"diameter\"") != std::string::npos);
  CHECK(error_of(R"({"5": {"shape": "ballnose", "diameter": "big"}})").find("\"diameter\" must be a number") != std::string::npos);
  CHECK(error_of(R"({"6": {"shape": "ballnose", "diameter": 0}})").find("\"diameter\" must be positive") != std::string::npos);
  CHECK(error_of(R"({"7": {"shape": "ballnose", "diameter": 2, "units": "cubits"}})").find("unknown \"units\"") != std::string::npos);
  CHECK(error_of(R"({"8": {"shape": "conical", "diameter": 2}})").find("needs a positive \"length\"") != std::string::npos);
  CHECK(error_of(R"({"9": {"shape": "bullnose", "diameter": 2}})").find("\"corner-radius\"") != std::string::npos);
  CHECK(error_of(R"({"10": {"shape": "bullnose", "diameter": 2, "corner-radius": 3}})").find("tool 10") != std::string::npos);
  CHECK(error_of(R"({"11": {"shape": "snubnose", "diameter": 2, "length": 3, "snub_diameter": 2}})").find("snub_diameter") != std::string::npos);
  CHECK(error_of(R"({"12": {"diameter": 2}})").find("missing \"shape\"") != std::string::npos);
}
