// Atomic outputs: whole files or nothing, never an input overwritten.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

#include "errors.hpp"
#include "outputs/output.hpp"

using namespace tridex;
using namespace tridex::cli;
namespace fs = std::filesystem;

namespace test_output {

fs::path scratch_dir(const std::string& name) {
  fs::path dir =
      fs::temp_directory_path() / ("tridex-test-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::size_t entries(const fs::path& dir) {
  return static_cast<std::size_t>(
      std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

TEST_CASE("an output appears only when committed, and replaces the old file whole") {
  fs::path dir = scratch_dir("output");
  fs::path target = dir / "result.stl";
  {
    AtomicOutput out(target);
    out.stream() << "partial";
    CHECK(!fs::exists(target));
    CHECK(entries(dir) == 1);  // the temporary file
  }
  CHECK(!fs::exists(target));
  CHECK(entries(dir) == 0);  // abandoned: nothing left behind
  write_file_atomically(target, std::string("first"));
  CHECK(slurp(target) == "first");
  {
    AtomicOutput out(target);
    out.stream() << "second, longer";
    CHECK(slurp(target) == "first");
    out.commit();
  }
  CHECK(slurp(target) == "second, longer");
  CHECK(entries(dir) == 1);
  fs::remove_all(dir);
}

TEST_CASE("output paths are checked before any work") {
  fs::path dir = scratch_dir("paths");
  fs::path input = dir / "program.nc";
  write_file_atomically(input, std::string("G0 X0\n"));
  std::vector<fs::path> inputs{input};
  CHECK_NOTHROW(check_output_path("-o", dir / "new.stl", inputs));
  CHECK_THROWS_WITH_AS(check_output_path("-o", input, inputs),
                       doctest::Contains("would overwrite an input"), InputError);
  CHECK_THROWS_WITH_AS(check_output_path("-o", dir / "missing" / "a.stl", inputs),
                       doctest::Contains("does not exist"), InputError);
  CHECK_THROWS_WITH_AS(check_output_path("--png", dir, inputs), doctest::Contains("is a directory"),
                       InputError);
  // The same file through another spelling is still the input.
  CHECK_THROWS_AS(check_output_path("-o", dir / "." / "program.nc", inputs), InputError);
  if (::geteuid() != 0) {  // root may write anywhere
    fs::create_directories(dir / "locked");
    fs::permissions(dir / "locked", fs::perms::owner_read | fs::perms::owner_exec);
    CHECK_THROWS_WITH_AS(check_output_path("-o", dir / "locked" / "a.stl", inputs),
                         doctest::Contains("not writable"), InputError);
    fs::permissions(dir / "locked", fs::perms::owner_all);
  }
  fs::remove_all(dir);
}

}  // namespace test_output
