// Bad input through the built command (issue 16): every case exits with status 2, says where the
// fault is (file and line, or file and key, or the option) and the offending value, lets no text
// of a library through, and writes no file. One row per kind of fault, run in a fresh folder whose
// listing is compared before and after.
#include <doctest/doctest.h>

#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>

#include <csignal>
#include <cstdio>
#include <cmath>
#include <functional>
#include <set>
#include <thread>

#include "command_harness.hpp"
#include "outputs/output.hpp"

using namespace tridex;
using namespace tridex::test;

namespace test_bad_input {

const std::string kProgram =
    "G21 G90\nT1 M6\nS1000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10 Y5\nG0 Z5\nM30\n";
const std::string kTools =
    R"({"1": {"units": "mm", "shape": "ballnose", "diameter": 4, "length": 20}})";
// Nested subprogram loops: 9999 × 9999 passes over two moves from a few bytes.
const std::string kMacroBomb =
    "G21 G90\nT1 M6\nS1000 M3\nM98 P2 L9999\nM30\nO2\nM98 P3 L9999\nM99\nO3\nG1 X1 Y1 Z-1 F100\nG1 "
    "X0 Y0 Z-1\nM99\n";

// A closed box as ASCII STL, with `x_max` written as given (to put any text in a coordinate).
std::string box_stl(double lo, double hi, const std::string& x_max = "") {
  auto num = [](double v) {
    char text[64];
    std::snprintf(text, sizeof text, "%.17g", v);
    return std::string(text);
  };
  std::string xs[2] = {num(lo), x_max.empty() ? num(hi) : x_max};
  std::string c[2] = {num(lo), num(hi)};
  auto v = [&](int k) { return xs[k & 1] + " " + c[(k >> 1) & 1] + " " + c[(k >> 2) & 1]; };
  const int faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                            {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  std::string text = "solid box\n";
  for (const auto& f : faces) {
    text += "facet normal 0 0 0\nouter loop\n";
    for (int k : f) text += "vertex " + v(k) + "\n";
    text += "endloop\nendfacet\n";
  }
  return text + "endsolid box\n";
}

// A binary STL header announcing `count` triangles, extended to the matching size without
// writing the records (a sparse file).
void sparse_binary_stl(const fs::path& path, std::uint32_t count) {
  std::string header(80, 'x');
  header.append(reinterpret_cast<const char*>(&count), 4);
  write_text(path, header);
  fs::resize_file(path, 84 + 50 * static_cast<std::uintmax_t>(count));
}

std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    names.insert(fs::relative(entry.path(), dir).string());
  return names;
}

// Text that only a library writes (nlohmann's "[json.exception…", libstdc++'s "basic_filebuf",
// "std::" names, CLI11's bare "what()").
bool has_library_text(const std::string& text) {
  for (const char* marker : {"json.exception", "basic_filebuf", "basic_ios", "std::", "what()",
                             "bad_alloc", "terminate called"})
    if (text.find(marker) != std::string::npos) return true;
  return false;
}

struct BadInput {
  const char* name;
  // Writes the case's files into the folder and returns the command's arguments.
  std::function<std::vector<std::string>(const fs::path&)> setup;
  std::vector<std::string> message;  // each must appear in stderr
};

std::string at(const fs::path& dir, const char* name) { return (dir / name).string(); }

// Writes the usual program and tool table; returns `simulate PROGRAM --tools TOOLS --dexel-res 24`
// and the extra arguments.
std::vector<std::string> simulate_with(const fs::path& dir, std::vector<std::string> extra) {
  write_text(dir / "p.nc", kProgram);
  write_text(dir / "tools.json", kTools);
  std::vector<std::string> args{
      "simulate", at(dir, "p.nc"), "--tools", at(dir, "tools.json"), "--dexel-res", "24"};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

std::vector<std::string> check_with(const fs::path& dir, std::vector<std::string> extra) {
  std::vector<std::string> args = simulate_with(dir, {});
  args[0] = "check";
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

std::vector<std::string> with_tools(const fs::path& dir, const std::string& table) {
  std::vector<std::string> args = simulate_with(dir, {"-o", at(dir, "out.stl")});
  write_text(dir / "tools.json", table);
  return args;
}

std::vector<std::string> with_project(const fs::path& dir, const std::string& workpiece) {
  write_text(dir / "p.nc", kProgram);
  write_text(dir / "job.camotics",
             R"({"files": ["p.nc"], "tools": )" + kTools + R"(, "workpiece": )" + workpiece + "}");
  return {"simulate", at(dir, "job.camotics"), "--dexel-res", "24", "-o", at(dir, "out.stl")};
}

const std::vector<BadInput>& cases() {
  static const std::vector<BadInput> all = {
      // ---- options --------------------------------------------------------------------------
      {"--zmap-cell nan",
       [](const fs::path& d) {
         return simulate_with(d, {"--zmap-cell", "nan", "-o", at(d, "o.stl")});
       },
       {"--zmap-cell", "finite positive", "nan"}},
      {"--dexel-cell nan",
       [](const fs::path& d) {
         auto a = simulate_with(d, {"--dexel-cell", "nan", "-o", at(d, "o.stl")});
         a.erase(a.begin() + 4, a.begin() + 6);  // --dexel-res excludes --dexel-cell
         return a;
       },
       {"--dexel-cell", "finite positive", "nan"}},
      {"--arc-tolerance nan",
       [](const fs::path& d) {
         return simulate_with(d, {"--arc-tolerance", "nan"});
       },
       {"--arc-tolerance", "finite positive", "nan"}},
      {"--arc-tolerance inf",
       [](const fs::path& d) {
         return simulate_with(d, {"--arc-tolerance", "inf"});
       },
       {"--arc-tolerance", "inf"}},
      {"--tolerance nan",
       [](const fs::path& d) {
         return check_with(d, {"--design", at(d, "p.nc"), "--tolerance", "nan"});
       },
       {"--tolerance", "nan"}},
      {"--stock ''",
       [](const fs::path& d) {
         return simulate_with(d, {"--stock", "", "-o", at(d, "o.stl")});
       },
       {"--stock", "must not be empty"}},
      {"--envelope ''",
       [](const fs::path& d) {
         return check_with(d, {"--design", at(d, "p.nc"), "--envelope", ""});
       },
       {"--envelope", "must not be empty"}},
      {"--envelope box with nan",
       [](const fs::path& d) {
         write_text(d / "part.stl", box_stl(0, 1));
         return check_with(d, {"--design", at(d, "part.stl"), "--envelope", "box:0,0,0,nan,1,1"});
       },
       {"--envelope", "\"nan\" is not a number"}},
      {"--max-memory nan",
       [](const fs::path& d) {
         return simulate_with(d, {"--max-memory", "nan"});
       },
       {"--max-memory", "\"nan\" is not a size"}},
      {"--max-memory 1e999M",
       [](const fs::path& d) {
         return simulate_with(d, {"--max-memory", "1e999M"});
       },
       {"--max-memory", "1e999"}},
      {"--max-blocks 0",
       [](const fs::path& d) {
         return simulate_with(d, {"--max-blocks", "0"});
       },
       {"--max-blocks"}},
      {"-o ''",
       [](const fs::path& d) {
         return simulate_with(d, {"-o", ""});
       },
       {"--output", "must not be empty"}},
      {"--dump-zmaps ''",
       [](const fs::path& d) {
         return simulate_with(d, {"--dump-zmaps", ""});
       },
       {"--dump-zmaps", "must not be empty"}},
      // ---- tool tables ------------------------------------------------------------------------
      {"tool keys 1 and 01",
       [](const fs::path& d) {
         return with_tools(
             d,
             R"({"1": {"shape": "ballnose", "diameter": 4}, "01": {"shape": "cylindrical", "diameter": 6}})");
       },
       {"tools.json", "\"01\" and \"1\" are both tool 1"}},
      {"tool key ' 1'",
       [](const fs::path& d) {
         return with_tools(d, R"({" 1": {"shape": "ballnose", "diameter": 4}})");
       },
       {"tools.json", "tool \" 1\"", "tool number"}},
      {"tool key given twice",
       [](const fs::path& d) {
         return with_tools(
             d,
             R"({"1": {"shape": "ballnose", "diameter": 4}, "1": {"shape": "ballnose", "diameter": 8}})");
       },
       {"tools.json", "key \"1\" appears twice"}},
      {"tool diameter 1e999",
       [](const fs::path& d) {
         return with_tools(d, "{\"1\": {\"shape\": \"ballnose\",\n \"diameter\": 1e999}}");
       },
       {"tools.json:2:", "1e999", "out of range", "diameter"}},
      {"tool diameter a string",
       [](const fs::path& d) {
         return with_tools(d, R"({"1": {"shape": "ballnose", "diameter": "4"}})");
       },
       {"tools.json: tool 1", "\"diameter\" must be a number, got a string"}},
      {"tool table not JSON",
       [](const fs::path& d) { return with_tools(d, "{\"1\": {\"shape\": ballnose}}"); },
       {"tools.json:1:", "not valid JSON"}},
      {"tool table a directory",
       [](const fs::path& d) {
         auto a = simulate_with(d, {"-o", at(d, "o.stl")});
         fs::create_directories(d / "table");
         a[3] = at(d, "table");
         return a;
       },
       {"table", "is a directory"}},
      // ---- projects ---------------------------------------------------------------------------
      {"project automatic \"false\"",
       [](const fs::path& d) { return with_project(d, R"({"automatic": "false"})"); },
       {"job.camotics", "\"automatic\" must be true or false", "\"false\""}},
      {"project automatic null",
       [](const fs::path& d) { return with_project(d, R"({"automatic": null})"); },
       {"job.camotics", "\"automatic\"", "null"}},
      {"project margin a string",
       [](const fs::path& d) { return with_project(d, R"({"margin": "5"})"); },
       {"job.camotics", "\"margin\"", "a string"}},
      {"project bounds min of strings",
       [](const fs::path& d) {
         return with_project(
             d, R"({"automatic": false, "bounds": {"min": ["0", 0, 0], "max": [1, 1, 1]}})");
       },
       {"job.camotics", "bounds min", "not a number"}},
      {"project files a number",
       [](const fs::path& d) {
         write_text(d / "job.camotics", R"({"files": [7]})");
         return std::vector<std::string>{"simulate", at(d, "job.camotics")};
       },
       {"job.camotics", "\"files\"", "a number"}},
      // ---- STL --------------------------------------------------------------------------------
      {"binary STL announcing 1.4 billion triangles",
       [](const fs::path& d) {
         sparse_binary_stl(d / "huge.stl", 1'400'000'000u);
         return simulate_with(d, {"--stock", at(d, "huge.stl"), "--max-memory", "1G"});
       },
       {"huge.stl", "1400000000 triangles", "--max-memory"}},
      {"design announcing 1.4 billion triangles",
       [](const fs::path& d) {
         sparse_binary_stl(d / "huge.stl", 1'400'000'000u);
         return check_with(d, {"--design", at(d, "huge.stl"), "--max-memory", "1G"});
       },
       {"huge.stl", "1400000000 triangles", "--max-memory"}},
      {"ASCII STL coordinate beyond float",
       [](const fs::path& d) {
         write_text(d / "part.stl", box_stl(0, 1, "1e39"));
         return check_with(d, {"--design", at(d, "part.stl")});
       },
       {"part.stl", "line ", "1e39", "beyond the range"}},
      {"design a directory",
       [](const fs::path& d) {
         fs::create_directories(d / "part");
         return check_with(d, {"--design", at(d, "part")});
       },
       {"part", "is a directory"}},
      // ---- coordinates out of the exact range -----------------------------------------------
      {"box stock near 1e15 mm",
       [](const fs::path& d) {
         return simulate_with(
             d, {"--stock", "box:1e15,1e15,1e15,1.0000001e15,1.0000001e15,1.0000001e15"});
       },
       {"the stock reaches", "represents exactly"}},
      {"design at 1e30 mm",
       [](const fs::path& d) {
         write_text(d / "far.stl", box_stl(1e30, 1.0001e30));
         return check_with(d, {"--design", at(d, "far.stl")});
       },
       {"--design", "far.stl", "represents exactly"}},
      {"box stock cut 1 km from the origin",
       [](const fs::path& d) {
         auto a = simulate_with(d, {"--stock", "box:999990,-10,-10,1000010,10,0"});
         write_text(d / "p.nc",
                    "G21 G90\nT1 M6\nG0 X1000000 Y0 Z5\nG1 Z-1 F100\nG1 X1000005\nM30\n");
         return a;
       },
       {"the stock reaches", "represents exactly", "100000 spacings"}},
      // ---- machine files ------------------------------------------------------------------------
      {"machine file with a number out of range",
       [](const fs::path& d) {
         write_text(d / "m.json", "{\"home\":\n [0, 0, 1e999]}");
         return simulate_with(d, {"--machine", at(d, "m.json")});
       },
       {"m.json:2:", "1e999", "out of range"}},
      {"machine file with a key twice",
       [](const fs::path& d) {
         write_text(d / "m.json", R"({"units": "mm", "units": "inch"})");
         return simulate_with(d, {"--machine", at(d, "m.json")});
       },
       {"m.json", "\"units\" appears twice"}},
      {"machine file a directory",
       [](const fs::path& d) {
         fs::create_directories(d / "machine");
         return simulate_with(d, {"--machine", at(d, "machine")});
       },
       {"--machine", "machine", "neither a bundled machine"}},
      {"--max-memory below what tridex holds before reading",
       [](const fs::path& d) {
         return simulate_with(d, {"--max-memory", "4M", "-o", at(d, "o.stl")});
       },
       {"p.nc:", "before keeping any move", "--max-memory 4 MiB"}},
      // ---- programs that expand without bound -------------------------------------------------
      {"macro bomb through simulate",
       [](const fs::path& d) {
         auto a = simulate_with(d, {"--max-memory", "200M", "-o", at(d, "o.stl")});
         write_text(d / "p.nc", kMacroBomb);
         return a;
       },
       {"p.nc:", "more than", "moves", "--max-memory"}},
      {"macro bomb through moves",
       [](const fs::path& d) {
         write_text(d / "p.nc", kMacroBomb);
         return std::vector<std::string>{"moves", at(d, "p.nc"), "--max-blocks",
                                         "50000", "-o",          at(d, "m.jsonl")};
       },
       {"p.nc:", "more than 50000 blocks", "--max-blocks"}},
      {"macro bomb through groups",
       [](const fs::path& d) {
         write_text(d / "p.nc", kMacroBomb);
         return std::vector<std::string>{"groups", at(d, "p.nc"), "--max-memory",
                                         "200M",   "-o",          at(d, "g.json")};
       },
       {"p.nc:", "more than", "moves", "--max-memory"}},
      {"an arc of radius 1000 at --arc-tolerance 1e-10",
       [](const fs::path& d) {
         auto a = simulate_with(
             d, {"--arc-tolerance", "1e-10", "--max-memory", "200M", "-o", at(d, "o.stl")});
         write_text(d / "p.nc",
                    "G21 G90\nT1 M6\nG0 X1000 Y0 Z0\nG2 X1000 Y0 I-1000 J0 F100\nM30\n");
         return a;
       },
       {"p.nc:4", "more than", "moves", "--max-memory"}},
      // ---- outputs ----------------------------------------------------------------------------
      {"-o and --report the same file",
       [](const fs::path& d) {
         return simulate_with(d, {"-o", at(d, "r"), "--report", at(d, "r")});
       },
       {"-o", "--report", "name the same file"}},
      {"-o and --png the same file through another spelling",
       [](const fs::path& d) {
         return simulate_with(d, {"-o", at(d, "r.x"), "--png", (d / "." / "r.x").string()});
       },
       {"name the same file"}},
      {"--dump-zmaps over the stock",
       [](const fs::path& d) {
         fs::create_directories(d / "dump");
         write_text(d / "dump" / "zmap-1-+z.stl", box_stl(-20, 20));
         return simulate_with(
             d, {"--stock", at(d, "dump/zmap-1-+z.stl"), "--dump-zmaps", at(d, "dump")});
       },
       {"--dump-zmaps", "zmap-1-+z.stl", "would overwrite an input"}},
      {"--dump-zmaps over the program",
       [](const fs::path& d) {
         fs::create_directories(d / "dump");
         auto a = simulate_with(d, {"--dump-zmaps", at(d, "dump")});
         fs::rename(d / "p.nc", d / "dump" / "zmap-1-+z.png");
         a[1] = at(d, "dump/zmap-1-+z.png");
         return a;
       },
       {"--dump-zmaps", "would overwrite an input"}},
      {"-o on a dump file",
       [](const fs::path& d) {
         fs::create_directories(d / "dump");
         return simulate_with(d,
                              {"--dump-zmaps", at(d, "dump"), "-o", at(d, "dump/zmap-1-+z.stl")});
       },
       {"--dump-zmaps", "name the same file"}},
  };
  return all;
}

TEST_CASE(
    "bad input: exit status 2, the place and the value in the message, no library text, no file "
    "written") {
  for (const BadInput& c : cases()) {
    CAPTURE(c.name);
    fs::path dir = scratch("bad-input");
    std::vector<std::string> args = c.setup(dir);
    std::set<std::string> before = listing(dir);
    CommandResult r = run_tridex(args, dir);
    CAPTURE(r.err);
    CHECK(r.status == 2);
    for (const std::string& part : c.message) {
      CAPTURE(part);
      CHECK(r.err.find(part) != std::string::npos);
    }
    CHECK(!has_library_text(r.err));
    CHECK(listing(dir) == before);
    fs::remove_all(dir);
  }
}

TEST_CASE("a box stock that no move reaches comes out whole, with a warning, even 1 km away") {
  // Near the work, and 1 km away (beyond the 10^5 spacings that a cut stock must keep within at
  // the default resolution: only its faces need representing).
  for (double offset : {500.0, 1e6}) {
    CAPTURE(offset);
    fs::path dir = scratch("uncut");
    const double size = offset < 1e3 ? 20 : 100;
    std::ostringstream stock;
    stock.precision(17);
    stock << "box:" << offset << "," << offset << ",-10," << offset + size << "," << offset + size
          << ",0";
    std::vector<std::string> args =
        simulate_with(dir, {"--stock", stock.str(), "-o", at(dir, "out.stl")});
    if (offset > 1e3) args.erase(args.begin() + 4, args.begin() + 6);  // the default resolution
    CommandResult r = run_tridex(args, dir);
    CAPTURE(r.err);
    REQUIRE(r.status == 0);
    CHECK(r.err.find("nothing was cut") != std::string::npos);
    Mesh mesh = read_binary_stl(dir / "out.stl");
    REQUIRE(!mesh.triangles.empty());
    // Every vertex on the stock box's boundary, and its volume the box's (one dexel layer of
    // rounding at most).
    Aabb box = mesh.bounds();
    CHECK(std::abs(box.min.x - offset) <= size / 24);  // within a dexel spacing (at most size/24)
    CHECK(std::abs(box.max.y - (offset + size)) <= size / 24);
    CHECK(std::abs(box.min.z + 10) <= size / 24);
    CHECK(mesh.signed_volume() == doctest::Approx(size * size * 10).epsilon(0.05));
    fs::remove_all(dir);
  }
}

TEST_CASE("an existing special file is written in place, never renamed over") {
  if (::geteuid() != 0) return;  // mknod needs root
  fs::path dir = scratch("special");
  fs::path node = dir / "null";
  REQUIRE(::mknod(node.c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0);  // a copy of /dev/null
  std::vector<std::string> args =
      simulate_with(dir, {"-o", node.string(), "--report", node.string()});
  CommandResult r = run_tridex(args, dir);
  CHECK(r.status == 0);
  CHECK(fs::is_character_file(node));
  CHECK(listing(dir) == std::set<std::string>{"null", "p.nc", "tools.json"});
  fs::remove_all(dir);
}

TEST_CASE("SIGTERM removes the temporary file of an output being written") {
  fs::path dir = scratch("sigterm");
  pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    cli::remove_temporaries_on_signals();
    cli::AtomicOutput out(dir / "result.stl");
    out.stream() << "partial";
    out.stream().flush();
    std::raise(SIGTERM);
    std::_Exit(0);  // not reached
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  CHECK(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == SIGTERM);
  CHECK(listing(dir).empty());
  fs::remove_all(dir);
}

// Runs the bundled example through `command` (simulate or check) at `resolution` with `extra`
// arguments, waits for the temporary file of `output` (a file in the scratch folder) to appear,
// sends `signal`, and checks that the process died of it leaving only the inputs behind. A run
// that wrote its output between two looks (the window is milliseconds) proves nothing: it is
// run again, up to four times.
void interrupt_while_writing(const std::string& command, const std::string& resolution,
                             const std::vector<std::string>& extra, const std::string& output,
                             int signal) {
  fs::path dir = scratch("interrupted");
  const fs::path example =
      fs::path(TRIDEX_SOURCE_DIR) / "gcode" / "examples" / "mold_3plus2.camotics";
  const std::set<std::string> inputs{"mold_3plus2.camotics", "mold_3plus2.nc",
                                     "mold_3plus2.tools.json"};
  for (const std::string& name : inputs) fs::copy_file(example.parent_path() / name, dir / name);
  std::vector<std::string> args{TRIDEX_COMMAND,
                                command,
                                (dir / "mold_3plus2.camotics").string(),
                                "--dexel-res",
                                resolution,
                                "--threads",
                                "2",
                                "-q"};
  args.insert(args.end(), extra.begin(), extra.end());
  args.push_back(command == "check" ? "--ply" : "-o");
  args.push_back((dir / output).string());
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const std::string temporary = "." + output + ".tmp-";
  bool seen = false;
  int status = 0;
  for (int attempt = 0; attempt < 4 && !seen; ++attempt) {
    fs::remove(dir / output);  // a run that finished
    pid_t child = ::fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      std::freopen("/dev/null", "w", stdout);
      std::freopen("/dev/null", "w", stderr);
      ::execv(TRIDEX_COMMAND, argv.data());
      std::_Exit(127);
    }
    // Wait for the temporary file of the output, then interrupt.
    while (!seen && ::waitpid(child, &status, WNOHANG) == 0) {
      for (const std::string& name : listing(dir))
        if (name.rfind(temporary, 0) == 0) seen = true;
      if (seen)
        ::kill(child, signal);
      else
        std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
    if (seen) ::waitpid(child, &status, 0);
  }
  REQUIRE(seen);  // every run ended before its output was being written: the test proved nothing
  CHECK(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == signal);
  std::set<std::string> left = listing(dir);
  CHECK(left == inputs);
  fs::remove_all(dir);
}

TEST_CASE(
    "SIGINT to a running simulate while it writes its STL leaves no temporary or partial file") {
  interrupt_while_writing("simulate", "400", {}, "big.stl", SIGINT);
}

TEST_CASE(
    "SIGTERM to a running check while it writes its PLY leaves no temporary or partial file") {
  // The design is the bundled example's own result, written first (not interrupted).
  fs::path dir = scratch("design-for-check");
  const fs::path example =
      fs::path(TRIDEX_SOURCE_DIR) / "gcode" / "examples" / "mold_3plus2.camotics";
  REQUIRE(run_tridex({"simulate", example.string(), "--dexel-res", "64", "-q", "-o",
                      (dir / "design.stl").string()},
                     dir)
              .status == 0);
  // --lattice-only: 200 dexels cannot resolve the default ±0.02 mm under the 2 mm ball end, and
  // check would refuse them before any work (the subject here is the interrupted output).
  interrupt_while_writing("check", "200",
                          {"--design", (dir / "design.stl").string(), "--lattice-only"}, "big.ply",
                          SIGTERM);
  fs::remove_all(dir);
}

}  // namespace test_bad_input
