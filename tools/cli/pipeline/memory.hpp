// tridex command — memory: the machine's RAM, this process's peak, and the up-front estimate
// that lets `simulate` refuse a resolution before allocating it.
#pragma once

#include <cstdint>
#include <string>

namespace tridex::cli {

std::uint64_t physical_memory_bytes();
double peak_rss_mib();  // getrusage ru_maxrss
double peak_rss_bytes();

// "800M", "16G", "1.5GiB", "2048" (MiB when no suffix); throws InputError.
std::uint64_t parse_memory(const std::string& text);
// --max-memory's value, or 80 % of RAM when it was not given.
std::uint64_t max_memory_bytes(const std::string& option);

// The figure checked against --max-memory, in bytes, with its parts for the message: an upper
// bound of the process's peak resident size (tests/tools/test_memory_bound.cpp runs the command
// just above it and measures). The coefficients are measured (README "Limits"): bytes at the
// peak of each stage over what the process already holds, with a margin.
struct MemoryEstimate {
  double held = 0;    // the peak so far: the libraries, the moves kept, the meshes read
  double zmaps = 0;   // every direction's heights and the milling's buffers
  double dexels = 0;  // the stock triple dexel, the result, the grid trees over the Z-maps
  double mesh = 0;    // the surface while it is extracted
  double after = 0;   // what the caller needs after the surface (check: trees, samples)
  double walls =
      0;  // the steep cells' sub-grids (fine_cells.hpp), counted once the maps are milled
  double total() const { return held + zmaps + dexels + mesh + after + walls; }
};

struct MemoryShape {
  double zmap_points = 0;  // the sum over directions of nx·ny
  double largest_map = 0;  // nx·ny of the largest direction's map
  double rays = 0;         // nx·ny + ny·nz + nz·nx of the triple dexel's lattice
  bool keep_maps = false;  // the milled maps are copied and kept to the end
  bool dump_maps = false;  // --dump-zmaps: each map's polyhedron is built and written
};

inline constexpr double kTrianglesPerRay = 8;  // measured 3.9-5.1 on the example and 12 directions
inline constexpr double kSurfaceBytesPerTriangle = 80;  // measured 60-67 at extract_surface's peak

MemoryEstimate estimate_memory(double held_bytes, const MemoryShape& shape);

std::string format_mib(double bytes);

}  // namespace tridex::cli
