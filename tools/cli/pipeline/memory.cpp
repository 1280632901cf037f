#include "pipeline/memory.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "errors.hpp"
#include "inputs/numbers.hpp"
#include "tridex/mill.hpp"

namespace tridex::cli {

std::uint64_t physical_memory_bytes() {
  long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page <= 0) return std::uint64_t{8} << 30;  // unknown: assume 8 GiB
  return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page);
}

double peak_rss_mib() {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

double peak_rss_bytes() { return peak_rss_mib() * (1 << 20); }

std::uint64_t parse_memory(const std::string& text) {
  std::size_t end = text.size();
  while (end > 0 && std::isalpha(static_cast<unsigned char>(text[end - 1]))) --end;
  std::string suffix = text.substr(end);
  for (char& c : suffix) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (end == 0)
    input_error("--max-memory: \"", text, "\" is not a size (a number, then K, M or G)");
  double value = parse_number(text.substr(0, end), "--max-memory");
  double scale = 0;
  if (suffix.empty() || suffix == "M" || suffix == "MB" || suffix == "MIB")
    scale = 1 << 20;
  else if (suffix == "G" || suffix == "GB" || suffix == "GIB")
    scale = 1 << 30;
  else if (suffix == "K" || suffix == "KB" || suffix == "KIB")
    scale = 1 << 10;
  else
    input_error("--max-memory: unknown unit \"", suffix, "\" (use K, M or G)");
  if (!(value > 0)) input_error("--max-memory: must be positive, got ", text);
  double bytes = value * scale;
  if (!(bytes < 1e19)) input_error("--max-memory: ", text, " is too large");
  return static_cast<std::uint64_t>(bytes);
}

std::uint64_t max_memory_bytes(const std::string& option) {
  return option.empty() ? physical_memory_bytes() / 10 * 8 : parse_memory(option);
}

double resident_bytes() {
  // statm's second field: resident pages. Freed memory the allocator kept counts, so this is
  // still an upper bound of what is live.
  if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
    unsigned long long size = 0, resident = 0;
    const int read = std::fscanf(f, "%llu %llu", &size, &resident);
    std::fclose(f);
    const long page = ::sysconf(_SC_PAGESIZE);
    if (read == 2 && page > 0) return static_cast<double>(resident) * static_cast<double>(page);
  }
  return peak_rss_bytes();
}

double MemoryEstimate::total() const {
  const double stages = std::max({milling, zmaps + dump, zmaps + walls, zmaps + fine + dexels,
                                  result + mesh + after + (keep_maps ? zmaps : 0.0)});
  // The stages' figures are measured means; the allocator's rounding and a stage's transient
  // buffers add a little: 5 % and at least 4 MiB (the walls' stage peaked 2.2 MiB above its
  // figure in tests/tools/test_memory_bound.cpp).
  const double slack = std::max(4.0 * (1 << 20), 0.05 * stages);
  return std::max(peak_before, held + stages + slack);
}

MemoryEstimate estimate_memory(double held_bytes, double peak_bytes, const MemoryShape& shape) {
  MemoryEstimate e;
  e.peak_before = peak_bytes;
  e.held = held_bytes;
  e.keep_maps = shape.keep_maps;
  // Float heights and tile maxima (4.1 bytes a point); raise_uncut marks a byte a point of the
  // largest map; a kept copy adds to all. A dumped map's polyhedron and its STL stream add to the
  // maps while it is written (measured under 60 bytes a point of the largest).
  e.zmaps = 4.2 * shape.zmap_points + 1.0 * shape.largest_map;
  if (shape.keep_maps) e.zmaps += 4.2 * shape.zmap_points;
  if (shape.dump_maps) e.dump = 60.0 * shape.largest_map;
  // The largest direction's moves as CutMoves (feeds and rapids, a pointer to each rapid), each
  // filed in one or two of the miller's blocks; and each thread's scratch for the moves of its
  // block (geometry and vector lanes, measured about 2.5 KiB a move, 2.75 counted: 39 MiB a thread
  // for 222,000 arc chords on one circle, about 14,000 in each block it crosses). A block's share
  // is not known before binning: four times the mean, at least 2,048 and at most 16,384 moves, is
  // counted, which covers the bench programs and the tests (bench/README.md, issue 37).
  const double block_moves =
      std::min({shape.largest_group, 16384.0,
                std::max(2048.0, 4 * shape.largest_group / std::max(1.0, shape.group_blocks))});
  e.milling = e.zmaps + (sizeof(CutMove) + 8 + 4 * 4) * shape.largest_group +
              shape.threads * (2816.0 * block_moves + (1 << 20));
  // A ray costs a 4-byte offset and, typically, one or two 8-byte intervals, in the stock and
  // in the result (measured 66-91 bytes a ray with the grid trees and the threads' buffers).
  e.dexels = 120.0 * shape.rays + 1.0 * shape.zmap_points;
  e.result = 60.0 * shape.rays;
  e.mesh = kTrianglesPerRay * shape.rays * kSurfaceBytesPerTriangle;
  return e;
}

std::string format_mib(double bytes) {
  char text[64];
  std::snprintf(text, sizeof text, "%.0f MiB", bytes / (1 << 20));
  return text;
}

}  // namespace tridex::cli
