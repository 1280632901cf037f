// tridex command — memory: the machine's RAM, this process's peak, and the up-front estimate
// that lets `simulate` refuse a resolution before allocating it.
#pragma once

#include <cstdint>
#include <string>

namespace tridex::cli {

std::uint64_t physical_memory_bytes();
double peak_rss_mib();  // getrusage ru_maxrss
double peak_rss_bytes();
double resident_bytes();  // /proc/self/statm: resident now (the peak where unreadable)

// "800M", "16G", "1.5GiB", "2048" (MiB when no suffix); throws InputError.
std::uint64_t parse_memory(const std::string& text);
// --max-memory's value, or 80 % of RAM when it was not given.
std::uint64_t max_memory_bytes(const std::string& option);

// The figure checked against --max-memory, in bytes, with its parts for the message: an upper
// bound of the process's peak resident size (tests/tools/test_memory_bound.cpp runs the command
// just above it and measures, and checks it within 1.5x of that peak). The stages free most of
// what they build before the next one (the Z-maps go after Steps 2-3, the walls' move lists after
// refining), so the peak is what the process holds before milling plus the largest stage, not
// the sum of them all. The coefficients are measured (bench/README.md, "Memory"): bytes at the
// peak of each stage over what the process already holds, with a margin.
struct MemoryEstimate {
  double peak_before = 0;  // the peak resident size before milling (a floor of the total)
  double held = 0;     // resident before milling: the libraries, the moves kept, the meshes read
  double zmaps = 0;    // every direction's heights (and their kept copies)
  double dump = 0;     // --dump-zmaps: the largest map's polyhedron while it is written
  double milling = 0;  // the largest direction's moves as cutter sweeps, binned, while milled
  double dexels = 0;   // the stock triple dexel, the result, the scan's buffers over the Z-maps
  double result = 0;   // the result's triple dexel alone, which outlives the maps
  double mesh = 0;     // the surface while it is extracted, and its check
  double after = 0;    // what the caller needs after the surface (check: trees, samples)
  double walls =
      0;            // the steep cells' sub-grids (fine_cells.hpp), counted once the maps are milled
  double fine = 0;  // the part of `walls` the maps keep (the sub-grids, not the move lists)
  bool keep_maps = false;  // the milled maps are kept to the end, next to the surface
  // held plus the largest stage: milling, refining the walls, Steps 2-3, the surface.
  double total() const;
};

struct MemoryShape {
  double zmap_points = 0;    // the sum over directions of nx·ny
  double largest_map = 0;    // nx·ny of the largest direction's map
  double largest_group = 0;  // the moves of the direction with most
  double group_blocks = 1;   // its map's blocks of 128 × 128 points (the miller's work blocks)
  double threads = 1;        // the threads milling, each with its block's scratch
  double rays = 0;           // nx·ny + ny·nz + nz·nx of the triple dexel's lattice
  bool keep_maps = false;    // the milled maps are copied and kept to the end
  bool dump_maps = false;    // --dump-zmaps: each map's polyhedron is built and written
};

// The result's surface: measured 3.4-5.1 triangles a ray (model D, the example, 12 directions)
// and 60-67 bytes a triangle at extract_surface's peak. Model D's peak is 1.47x below the estimate.
inline constexpr double kTrianglesPerRay = 5.3;
inline constexpr double kSurfaceBytesPerTriangle = 68;

// `held_bytes`: resident now; `peak_bytes`: the peak so far (ru_maxrss).
MemoryEstimate estimate_memory(double held_bytes, double peak_bytes, const MemoryShape& shape);

std::string format_mib(double bytes);

}  // namespace tridex::cli
