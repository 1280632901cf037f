// tridex bench — a paper-scale 3+2 milling workload written as G-code.
//
// The shape follows the test pieces of Inui, Chen and Umezu, CAD&A 19(4) 2022, Fig. 9: a box
// stock machined from five spindle directions, +Z, +X tilted 20° up from the horizontal, +Y,
// −X and −Y, each with four cutters: a 10 mm flat end and an 8 mm bull nose roughing in
// Z levels, a 6 mm and a 3 mm ball end finishing. The surface each direction machines is
// mold-like: a smooth dome with ripples, in that direction's feature frame (Fanuc G68.2, as
// docs/design.md defines it). Passes are zig-zag rasters of short G01 segments; the number of
// segments is a parameter (the paper's models have 1.46 M to 5.17 M), split over directions
// and cutters in fixed shares.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "tridex/cutter.hpp"
#include "tridex/geometry.hpp"

namespace tridex::bench {

// The stock (work coordinates, G54 at its corner) and the tools of every workload.
inline Aabb workload_stock() { return Aabb{Vec3(0, 0, 0), Vec3(200, 200, 130)}; }

struct WorkloadTool {
  int number;
  const char* comment;
  Cutter cutter;
};

inline std::vector<WorkloadTool> workload_tools() {
  return {{1, "D10 FLAT END", Cutter::flat(5)},
          {2, "D8 R1 BULL NOSE", Cutter::bull_nose(4, 1)},
          {3, "D6 BALL END", Cutter::ball(3)},
          {4, "D3 BALL END", Cutter::ball(1.5)}};
}

namespace detail {

struct Direction {
  const char* name;
  bool tilted;            // G68.2 in use
  double i, j, k;         // G68.2 Euler angles (degrees)
  Vec3 origin;            // G68.2 X Y Z: the feature frame's origin in work coordinates
  double half_w, half_h;  // the machined region: |x| ≤ half_w, |y| ≤ half_h in the feature frame
  double top;             // feature z of the stock face the direction machines
  double share;           // of all segments
};

inline std::array<Direction, 5> directions() {
  return {{{"+Z", false, 0, 0, 0, Vec3(100, 100, 0), 100, 100, 130, 0.40},
           {"+X TILTED 20 DEG", true, 90, 70, 0, Vec3(190, 100, 110), 100, 30, 8, 0.15},
           {"+Y", true, 180, 90, 0, Vec3(100, 200, 65), 100, 65, 0, 0.15},
           {"-X", true, -90, 90, 0, Vec3(0, 100, 65), 100, 65, 0, 0.15},
           {"-Y", true, 0, 90, 0, Vec3(100, 0, 65), 100, 65, 0, 0.15}}};
}

// The finished surface of a direction, feature-frame height over (x, y): a dome with ripples
// below the face at `top`.
inline double mold_surface(const Direction& d, double x, double y) {
  double rx = x / d.half_w, ry = y / d.half_h;
  double dome = std::exp(-2.0 * (rx * rx + ry * ry));
  double depth = d.tilted ? 9.0 : 38.0;
  return d.top - depth + 0.55 * depth * dome + 1.5 * std::sin(x / 11.0) * std::cos(y / 13.0);
}

class Writer {
 public:
  explicit Writer(std::FILE* out) : out_(out) {}
  void line(const char* text) { std::fputs(text, out_), std::fputc('\n', out_); }
  void g0(double x, double y, double z) { std::fprintf(out_, "G0 X%.3f Y%.3f Z%.3f\n", x, y, z); }
  void g0z(double z) { std::fprintf(out_, "G0 Z%.3f\n", z); }
  void g1(double x, double y, double z) {
    std::fprintf(out_, "G1 X%.3f Y%.3f Z%.3f\n", x, y, z);
    ++segments_;
  }
  long long segments() const { return segments_; }

 private:
  std::FILE* out_;
  long long segments_ = 0;
};

// One raster pass: `levels` Z levels (roughing, tip at max(level, surface + allowance)) or one
// (finishing, levels = 0), lines along x (along_x) or y, about `budget` G01 segments.
inline void raster(Writer& w, const Direction& d, double radius, int levels, double allowance,
                   bool along_x, long long budget, Vec2 shift) {
  const double clear = d.top + 10;
  const double len = along_x ? 2 * d.half_w : 2 * d.half_h,
               across = along_x ? 2 * d.half_h : 2 * d.half_w;
  const int passes = std::max(1, levels);
  // Lines and segments per line so that segments are about a quarter of the step-over long.
  const double per_pass = std::max(4.0, double(budget) / passes);
  const int lines =
      std::max(2, static_cast<int>(std::lround(std::sqrt(per_pass * across / (4 * len)))));
  const int per_line = std::max(1, static_cast<int>(std::lround(per_pass / lines)) - 1);
  const double top_level = d.top - 2, bottom_level = d.top - (d.tilted ? 9.0 : 38.0) + allowance;
  for (int p = 0; p < passes; ++p) {
    double level = levels > 0 ? top_level - (top_level - bottom_level) * (p + 1) / passes : -1e9;
    auto point = [&](double s, double t) {
      double a = -len / 2 - radius + (len + 2 * radius) * s, b = -across / 2 + across * t;
      double x = along_x ? a : b, y = along_x ? b : a;
      double z = std::max(level, mold_surface(d, x, y) + allowance);
      return Vec3(x + shift.x, y + shift.y, z);
    };
    Vec3 start = point(0, 0);
    w.g0z(clear);
    w.g0(start.x, start.y, clear);
    w.g0z(start.z + 2);
    w.line("G1 F600");
    for (int l = 0; l < lines; ++l) {
      double t = double(l) / (lines - 1);
      for (int k = 0; k <= per_line; ++k) {
        double s = double(k) / per_line;
        Vec3 q = point(l % 2 ? 1 - s : s, t);
        w.g1(q.x, q.y, q.z);
      }
    }
    w.g0z(clear);
  }
}

}  // namespace detail

// Variants of the program. `sloped_roughing`: the flat end and the bull nose rough in one 3D
// raster following the surface at their allowance (sloped moves, as a mold's roughing or rest
// machining), instead of in Z levels. `balls_only`: the same program without the roughing tools
// (the ball ends' moves unchanged), to compare Step 1 of all cutters with the ball ends alone.
struct WorkloadVariant {
  bool sloped_roughing = false;
  bool balls_only = false;
};

// Writes the program; returns the number of G01 segments (within a fraction of a percent of
// `segments`, less the roughing's with `balls_only`).
inline long long write_workload(std::FILE* out, long long segments, WorkloadVariant variant = {}) {
  detail::Writer w(out);
  w.line("%");
  w.line("O5000 (TRIDEX PAPER-SCALE 3+2 WORKLOAD: FIVE DIRECTIONS, FOUR CUTTERS EACH)");
  w.line("(STOCK X0 Y0 Z0 TO X200 Y200 Z130, G54 AT THE STOCK CORNER)");
  w.line("G21 G17 G40 G49 G80 G90");
  const auto tools = workload_tools();
  const double tool_share[4] = {0.15, 0.15, 0.25, 0.45};
  for (const detail::Direction& d : detail::directions()) {
    for (std::size_t t = 0; t < tools.size(); ++t) {
      if (variant.balls_only && t < 2) continue;
      char text[160];
      std::snprintf(text, sizeof text, "(%s, T%d %s)", d.name, tools[t].number, tools[t].comment);
      w.line(text);
      w.line("G28 G91 Z0.");
      w.line("G90");
      w.line("G69");
      std::snprintf(text, sizeof text, "T%d M6", tools[t].number);
      w.line(text);
      w.line("S10000 M3");
      w.line("G54");
      if (d.tilted) {
        std::snprintf(text, sizeof text, "G68.2 X%.3f Y%.3f Z%.3f I%.1f J%.1f K%.1f", d.origin.x,
                      d.origin.y, d.origin.z, d.i, d.j, d.k);
        w.line(text);
        w.line("G53.1");
      }
      auto budget =
          static_cast<long long>(std::llround(double(segments) * d.share * tool_share[t]));
      const double radius = tools[t].cutter.radius();
      // Without G68.2 (+Z) the feature frame is the work frame: the raster is shifted to the
      // origin instead.
      const Vec2 shift = d.tilted ? Vec2(0) : Vec2(d.origin.x, d.origin.y);
      const int levels = variant.sloped_roughing ? 0 : (t == 0 ? 4 : (t == 1 ? 2 : 0));
      const double allowance = t == 0 ? 1.0 : (t == 1 ? 0.5 : (t == 2 ? 0.2 : 0));
      detail::raster(w, d, radius, levels, allowance, t != 3, budget, shift);
      w.line("M5");
    }
  }
  w.line("G28 G91 Z0.");
  w.line("G90 G69");
  w.line("M30");
  w.line("%");
  return w.segments();
}

}  // namespace tridex::bench
