#include "inputs/stock.hpp"

#include <cmath>
#include <sstream>
#include <vector>

#include "errors.hpp"
#include "inputs/numbers.hpp"

namespace tridex::cli {

Aabb parse_box(const std::string& numbers, const std::string& option) {
  std::vector<double> v = parse_number_list(numbers, option + " box");
  if (v.size() != 6)
    input_error(option, " box: expected XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX (6 numbers), got ", v.size());
  Aabb box{Vec3(v[0], v[1], v[2]), Vec3(v[3], v[4], v[5])};
  for (double value : v)
    if (!(std::abs(value) <= kMaxStockCoordinate))
      input_error(option, " box: ", value, " mm is beyond ±", kMaxStockCoordinate, " mm");
  const char* names = "XYZ";
  for (int a = 0; a < 3; ++a)
    if (!(box.min[a] < box.max[a]))
      input_error(option, " box: ", names[a], "MIN ", box.min[a], " must be less than ", names[a],
                  "MAX ", box.max[a]);
  return box;
}

Aabb parse_envelope(const std::string& text) {
  if (text.rfind("box:", 0) != 0)
    input_error("--envelope ", text, ": expected box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX");
  return parse_box(text.substr(4), "--envelope");
}

StockSpec parse_stock(const std::string& text) {
  StockSpec spec;
  if (text.rfind("box:", 0) == 0) {
    spec.kind = StockSpec::Kind::box;
    spec.box = parse_box(text.substr(4), "--stock");
    return spec;
  }
  if (text == "auto" || text.rfind("auto:", 0) == 0) {
    spec.kind = StockSpec::Kind::automatic;
    if (text.size() > 4) {
      double margin = parse_number(text.substr(5), "--stock auto margin");
      if (margin < 0) input_error("--stock auto: the margin must not be negative, got ", margin);
      if (margin > kMaxStockCoordinate)
        input_error("--stock auto: the margin ", margin, " mm is beyond ", kMaxStockCoordinate,
                    " mm");
      spec.margin_mm = margin;
    }
    return spec;
  }
  if (text.empty()) input_error("--stock: empty value");
  spec.kind = StockSpec::Kind::mesh;
  spec.mesh_path = text;
  std::error_code error;
  if (!std::filesystem::is_regular_file(spec.mesh_path, error))
    input_error(
        "--stock ", text,
        ": no such file (expected box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX, FILE.stl or auto[:MARGIN])");
  return spec;
}

Aabb automatic_stock(const Aabb& cutting_bounds, const StockSpec& spec) {
  if (cutting_bounds.empty())
    input_error(
        "--stock auto: the program has no cutting moves to put a stock around; give --stock");
  Aabb box = cutting_bounds;
  if (box.min.z < 0) box.max.z = std::max(box.max.z, 0.0);
  if (box.max.z - box.min.z < 2) box.min.z = box.max.z - 2;
  if (spec.margin_mm) return box.inflated(*spec.margin_mm);
  double percent = spec.margin_percent.value_or(5.0);
  Vec3 margin = box.size() * (percent / 100.0);
  box.min -= margin;
  box.max.x += margin.x, box.max.y += margin.y;
  // A flat program (all cuts in one plane) still needs a stock of non-zero width.
  for (int a = 0; a < 2; ++a)
    if (box.max[a] - box.min[a] < 1e-6) box.min[a] -= 1, box.max[a] += 1;
  return box;
}

std::string describe(const StockSpec& spec) {
  std::ostringstream out;
  switch (spec.kind) {
    case StockSpec::Kind::box:
      out << "box:" << spec.box.min.x << ',' << spec.box.min.y << ',' << spec.box.min.z << ','
          << spec.box.max.x << ',' << spec.box.max.y << ',' << spec.box.max.z;
      break;
    case StockSpec::Kind::mesh:
      out << spec.mesh_path.string();
      break;
    case StockSpec::Kind::automatic:
      out << "auto";
      if (spec.margin_mm) out << ':' << *spec.margin_mm;
      break;
  }
  return out.str();
}

}  // namespace tridex::cli
