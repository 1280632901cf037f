// The `tridex` command end to end, what every command shares: --version and --help, every exit
// path of bad input and unwritable outputs, --max-memory, --block-delete, --progress and projects
// of several files. Each command's own cases are in test_command_<command>.cpp.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "command_reference.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

TEST_CASE("--version, --help and option errors") {
  fs::path dir = scratch("options");
  CommandResult version = run_tridex({"--version"}, dir);
  CHECK(version.status == 0);
  CHECK(version.out.rfind("tridex ", 0) == 0);
  CHECK(run_tridex({"--help"}, dir).status == 0);
  for (const char* command : {"simulate", "moves", "groups"}) {
    CommandResult help = run_tridex({command, "--help"}, dir);
    CHECK(help.status == 0);
    CHECK(help.out.find("PROGRAM") != std::string::npos);
  }
  CHECK(run_tridex({"simulate", "--help"}, dir).out.find("--dexel-res") != std::string::npos);
  fs::path program = dir / "p.nc";
  write_text(program, "G0 X0\n");
  CHECK(run_tridex({}, dir).status == 2);
  CHECK(run_tridex({"frobnicate"}, dir).status == 2);
  CHECK(run_tridex({"simulate"}, dir).status == 2);
  CHECK(run_tridex({"simulate", program.string(), "--no-such-option"}, dir).status == 2);
  CHECK(run_tridex({"simulate", program.string(), "--dexel-res", "100", "--dexel-cell", "1"}, dir)
            .status == 2);
  CHECK(run_tridex({"simulate", program.string(), "--zmap-cell", "-1"}, dir).status == 2);
  CHECK(run_tridex({"simulate", program.string(), "--quiet", "--progress"}, dir).status == 2);
  CHECK(run_tridex({"simulate", program.string(), "--max-memory", "lots"}, dir).status == 2);
  CommandResult missing = run_tridex({"moves", (dir / "absent.nc").string()}, dir);
  CHECK(missing.status == 2);
  CHECK(missing.err.find("absent.nc") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("a bad program exits 2 with file:line:col, and leaves no output behind") {
  fs::path dir = scratch("bad-program");
  fs::path program = dir / "bad.nc", tools = dir / "tools.json", stl = dir / "out.stl";
  write_text(tools, kTools);
  write_text(program, "G21 G90\nT1 M6\nG0 X1 Y2 Z30\nG1 X5 F100 G987\nM30\n");
  write_text(stl, "the previous result");
  for (const char* command : {"simulate", "moves", "groups"}) {
    std::vector<std::string> args{command, program.string()};
    if (std::string(command) == "simulate") args.insert(args.end(), {"--tools", tools.string()});
    args.insert(args.end(), {"-o", stl.string()});
    CommandResult r = run_tridex(args, dir);
    CHECK(r.status == 2);
    INFO(r.err);
    CHECK(has_number_between(r.err, "bad.nc:4:", ": "));
    CHECK(slurp(stl) == "the previous result");
  }
  // Nothing but the three files: no temporary file left.
  CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator()) == 3);
  fs::remove_all(dir);
}

TEST_CASE("bad tool tables, missing tools and bad stocks exit 2 naming the problem") {
  fs::path dir = scratch("bad-input");
  fs::path program = dir / "p.nc", tools = dir / "tools.json";
  write_text(program,
             "G21 G90\nT1 M6\nG0 X1 Y2 Z30\nG1 Z5 F100\nT5 M6\nG0 X3 Y3 Z30\nG1 Z4\nM30\n");
  auto simulate_with = [&](const std::string& table, const std::string& stock) {
    write_text(tools, table);
    return run_tridex({"simulate", program.string(), "--tools", tools.string(), "--stock", stock,
                       "--dexel-res", "32", "-o", (dir / "out.stl").string()},
                      dir);
  };
  CommandResult not_json = simulate_with("{\"1\": {", "auto");
  CHECK(not_json.status == 2);
  CHECK(not_json.err.find("tools.json") != std::string::npos);
  CommandResult bad_shape = simulate_with(R"({"1": {"shape": "drill", "diameter": 3}})", "auto");
  CHECK(bad_shape.status == 2);
  CHECK(bad_shape.err.find("tool 1: unknown shape") != std::string::npos);
  CommandResult missing_tool =
      simulate_with(R"({"1": {"shape": "ballnose", "diameter": 3}})", "auto");
  CHECK(missing_tool.status == 2);
  INFO(missing_tool.err);
  CHECK(missing_tool.err.find("p.nc:5") != std::string::npos);
  CHECK(missing_tool.err.find("tool 5") != std::string::npos);
  CHECK(run_tridex({"simulate", program.string(), "--dexel-res", "32"}, dir).status ==
        2);  // no table

  const std::string good =
      R"({"1": {"shape": "ballnose", "diameter": 3}, "5": {"shape": "cylindrical", "diameter": 2}})";
  for (const char* stock :
       {"box:0,0,0,10,10", "box:0,0,0,10,10,a", "box:0,0,5,10,10,5", "cube:1", "auto:-2"})
    CHECK(simulate_with(good, stock).status == 2);
  fs::path broken = dir / "broken.stl";
  write_text(broken, "solid broken\n  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n");
  CommandResult bad_stl = simulate_with(good, broken.string());
  CHECK(bad_stl.status == 2);
  CHECK(bad_stl.err.find("broken.stl") != std::string::npos);
  CHECK(!fs::exists(dir / "out.stl"));
  fs::remove_all(dir);
}

// CAMotics ships TPL programs (JavaScript that writes G-code) beside its G-code examples, and
// its projects name them as they name G-code files.
TEST_CASE("a CAMotics TPL program, given or named by a project, is refused as not G-code") {
  fs::path dir = scratch("tpl");
  write_text(dir / "gear.tpl", "var teeth = 12;\nfunction gear() {}\n");
  write_text(dir / "gear.camotics",
             R"({"files": ["gear.tpl"], "tools": {"1": {"shape": "cylindrical", "diameter": 2}}})");
  for (const char* program : {"gear.tpl", "gear.camotics"}) {
    CAPTURE(program);
    CommandResult r = run_tridex({"moves", (dir / program).string()}, dir);
    CHECK(r.status == 2);
    CHECK(r.err.find("gear.tpl: a CAMotics TPL program") != std::string::npos);
  }
  fs::remove_all(dir);
}

TEST_CASE("unwritable outputs and inputs named as outputs are refused before any work") {
  fs::path dir = scratch("outputs");
  fs::path program = dir / "p.nc", tools = dir / "tools.json";
  write_text(program, program_of({&kDirections[0]}));
  write_text(tools, kTools);
  std::string before = slurp(program);
  std::vector<std::string> base{"simulate", program.string(), "--tools",     tools.string(),
                                "--stock",  kStock,           "--dexel-res", "32"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return run_tridex(args, dir);
  };
  CommandResult no_dir = with({"-o", (dir / "missing" / "out.stl").string()});
  CHECK(no_dir.status == 2);
  CHECK(no_dir.err.find("does not exist") != std::string::npos);
  CHECK(with({"--png", dir.string()}).status == 2);
  CommandResult over_input = with({"-o", program.string()});
  CHECK(over_input.status == 2);
  CHECK(over_input.err.find("would overwrite an input") != std::string::npos);
  CHECK(with({"--report", tools.string()}).status == 2);
  CHECK(slurp(program) == before);
  CHECK(run_tridex({"moves", program.string(), "-o", program.string()}, dir).status == 2);
  CHECK(slurp(program) == before);
  if (::geteuid() != 0) {
    fs::create_directories(dir / "locked");
    fs::permissions(dir / "locked", fs::perms::owner_read | fs::perms::owner_exec);
    CHECK(with({"-o", (dir / "locked" / "out.stl").string()}).status == 2);
    fs::permissions(dir / "locked", fs::perms::owner_all);
  }
  fs::remove_all(dir);
}

TEST_CASE("a resolution over --max-memory is refused up front with the figure") {
  fs::path dir = scratch("memory");
  fs::path program = dir / "p.nc", tools = dir / "tools.json", stl = dir / "out.stl";
  write_text(program, program_of({&kDirections[0], &kDirections[1]}));
  write_text(tools, kTools);
  CommandResult r =
      run_tridex({"simulate", program.string(), "--tools", tools.string(), "--stock", kStock,
                  "--dexel-res", "4000", "--max-memory", "512M", "-o", stl.string()},
                 dir);
  CHECK(r.status == 2);
  INFO(r.err);
  CHECK(has_number_between(r.err, "needs an estimated ", " MiB"));
  CHECK(r.err.find("--max-memory 512 MiB") != std::string::npos);
  CHECK(!fs::exists(stl));
  // The same run fits with the default resolution.
  CHECK(run_tridex({"simulate", program.string(), "--tools", tools.string(), "--stock", kStock,
                    "--dexel-res", "48", "--zmap-cell", "0.2", "--max-memory", "512M", "-o",
                    stl.string(), "--quiet"},
                   dir)
            .status == 0);
  CHECK(fs::file_size(stl) > 84);
  fs::remove_all(dir);
}

TEST_CASE("--block-delete: on (the default) skips the blocks that start with '/', off runs them") {
  fs::path dir = scratch("block_delete");
  fs::path program = dir / "p.nc";
  write_text(program, "G21 G90\nG0 X0 Y0 Z5\n/G0 X10\nG0 Y20\nM30\n");
  // The end of the last move, for the command's extra options.
  auto last_end = [&](std::vector<std::string> args) {
    args.insert(args.begin(), {"moves", program.string()});
    CommandResult r = run_tridex(args, dir);
    INFO(r.err);
    REQUIRE(r.status == 0);
    std::istringstream lines(r.out);
    std::string line, last;
    while (std::getline(lines, line)) last = line;
    return vec(json::parse(last)["end"]);
  };
  CHECK(glm::length(last_end({}) - Vec3(0, 20, 5)) < 1e-12);
  CHECK(glm::length(last_end({"--block-delete", "on"}) - Vec3(0, 20, 5)) < 1e-12);
  CHECK(glm::length(last_end({"--block-delete", "off"}) - Vec3(10, 20, 5)) < 1e-12);
  CommandResult bad = run_tridex({"moves", program.string(), "--block-delete", "yes"}, dir);
  CHECK(bad.status == 2);
  CHECK(bad.err.find("--block-delete") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE(
    "progress goes to stderr only when asked (stderr is not a terminal here), and projects with "
    "several files") {
  fs::path dir = scratch("progress");
  fs::path tools = dir / "tools.json", first = dir / "first.nc", second = dir / "second.nc",
           project = dir / "job.camotics";
  write_text(tools, kTools);
  write_text(first, program_of({&kDirections[0]}));
  write_text(second, program_of({&kDirections[3]}));
  write_text(
      project,
      R"({"files": ["first.nc", "second.nc"], "tools": )" + kTools +
          R"(, "workpiece": {"automatic": false, "bounds": {"min": [0, 0, 0], "max": [40, 30, 20]}}})");
  std::vector<std::string> args{"simulate", project.string(), "--dexel-res",
                                "40",       "--zmap-cell",    "0.2"};
  CommandResult plain = run_tridex(args, dir);
  REQUIRE(plain.status == 0);
  CHECK(plain.out.find("job.camotics: ") == 0);
  CHECK(plain.err.find("milling direction") == std::string::npos);
  args.push_back("--progress");
  CommandResult progress = run_tridex(args, dir);
  REQUIRE(progress.status == 0);
  CHECK(progress.err.find("milling direction 2/2") != std::string::npos);
  CHECK(progress.err.find("extracting the surface") != std::string::npos);
  CHECK(progress.out ==
        plain.out.substr(0, plain.out.rfind(';')) + progress.out.substr(progress.out.rfind(';')));

  // `moves` on the project: both files, in order, each record naming its file.
  CommandResult moves = run_tridex({"moves", project.string()}, dir);
  REQUIRE(moves.status == 0);
  std::istringstream lines(moves.out);
  std::string line, last_file;
  std::vector<std::string> files;
  while (std::getline(lines, line)) {
    std::string file = json::parse(line)["file"].get<std::string>();
    if (file != last_file) files.push_back(file), last_file = file;
  }
  REQUIRE(files.size() == 2);
  CHECK(fs::path(files[0]).filename() == "first.nc");
  CHECK(fs::path(files[1]).filename() == "second.nc");
  fs::remove_all(dir);
}
