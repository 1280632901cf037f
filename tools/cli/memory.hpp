// tridex command — memory: the machine's RAM, this process's peak, and the up-front estimate
// that lets `simulate` refuse a resolution before allocating it.
#pragma once

#include <cstdint>
#include <string>

namespace tridex::cli {

std::uint64_t physical_memory_bytes();
double peak_rss_mib();  // getrusage ru_maxrss

// "800M", "16G", "1.5GiB", "2048" (MiB when no suffix); throws InputError.
std::uint64_t parse_memory(const std::string& text);
// --max-memory's value, or 80 % of RAM when it was not given.
std::uint64_t max_memory_bytes(const std::string& option);

// The figure checked against --max-memory, in bytes, with its parts for the message.
struct MemoryEstimate {
  double moves = 0;   // the program's moves, kept grouped by direction
  double zmaps = 0;   // every direction's heights (all are alive while the dexels are built)
  double dexels = 0;  // the stock triple dexel, one direction's dexels and the running result
  double mesh = 0;    // the extracted surface
  double total() const { return moves + zmaps + dexels + mesh; }
};

// zmap_points: the sum over directions of nx·ny; lattice nodes nx, ny, nz of the triple dexel.
MemoryEstimate estimate_memory(double zmap_points, double nx, double ny, double nz);

std::string format_mib(double bytes);

}  // namespace tridex::cli
