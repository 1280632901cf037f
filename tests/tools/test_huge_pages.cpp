// huge_pages.hpp: a big fresh block is marked for transparent huge pages, as the kernel records
// it (the "hg" flag of its mapping in /proc/self/smaps), and a small one is left alone.
#include <doctest/doctest.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "pipeline/huge_pages.hpp"

namespace {

// The VmFlags of the mapping that holds `address`, or "" when none does.
std::string mapping_flags(const void* address) {
  const auto at = reinterpret_cast<std::uintptr_t>(address);
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t begin = 0, end = 0;
    char dash = 0;
    std::istringstream header(line);
    if (header >> std::hex >> begin >> dash >> end && dash == '-' &&
        line.find(' ') != std::string::npos && line.find(':') > line.find(' ')) {
      inside = begin <= at && at < end;
    } else if (inside && line.rfind("VmFlags:", 0) == 0) {
      return line;
    }
  }
  return {};
}

}  // namespace

TEST_CASE("huge pages: a big fresh block is marked MADV_HUGEPAGE, a small one is not") {
  if (!std::filesystem::exists("/sys/kernel/mm/transparent_hugepage/enabled")) {
    MESSAGE("skipped: this kernel has no transparent huge pages");
    return;
  }
  const std::size_t big = tridex::cli::kHugePageBlockBytes + (std::size_t{3} << 20);
  void* block = std::malloc(big);
  REQUIRE(block != nullptr);
  CHECK(mapping_flags(static_cast<char*>(block) + big / 2).find(" hg") == std::string::npos);
  CHECK(tridex::cli::advise_huge_pages(block, big));
  CHECK(mapping_flags(static_cast<char*>(block) + big / 2).find(" hg") != std::string::npos);
  std::free(block);

  const std::size_t small = tridex::cli::kHugePageBlockBytes / 2;
  void* little = std::malloc(small);
  REQUIRE(little != nullptr);
  CHECK_FALSE(tridex::cli::advise_huge_pages(little, small));
  std::free(little);
}
