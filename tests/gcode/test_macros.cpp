// Parameters, expressions and control flow: each operator and function against hand-computed
// values, random expressions against a reference evaluator of the same tree, and every control
// structure against the same program written out without macros.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <functional>
#include <string>
#include <unistd.h>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace {

MachineConfig dialect(Dialect d) {
  MachineConfig m = at_origin();
  m.dialect = d;
  return m;
}

// The value of `expression` as the X word of a rapid.
double value_of(const std::string& expression, Dialect d = Dialect::fanuc) {
  Result r = run_program("G0 X[" + expression + "] Y0 Z0\nM30\n", {}, dialect(d));
  REQUIRE(r.moves.size() == 1);
  return r.moves[0].end.x;
}

void same_moves(const std::string& macro, const std::string& plain, Dialect d = Dialect::fanuc) {
  Result a = run_program(macro, {}, dialect(d));
  Result b = run_program(plain, {}, dialect(d));
  INFO(macro);
  REQUIRE(a.moves.size() == b.moves.size());
  REQUIRE(!a.moves.empty());
  for (std::size_t i = 0; i < a.moves.size(); ++i) {
    CHECK(near(a.moves[i].start, b.moves[i].start, 1e-9));
    CHECK(near(a.moves[i].end, b.moves[i].end, 1e-9));
    CHECK(a.moves[i].feed == b.moves[i].feed);
  }
}

}  // namespace

TEST_CASE("macros: each operator and function against hand-computed values") {
  CHECK(value_of("1+2*3") == 7);
  CHECK(value_of("[1+2]*3") == 9);
  CHECK(value_of("2**3**2") == 512);  // right-associative
  CHECK(value_of("10-4-3") == 3);     // left-associative
  CHECK(value_of("10/4") == 2.5);
  CHECK(value_of("7 MOD 3") == 1);
  CHECK(value_of("-7 MOD 3") == 2);  // rs274ngc: the result is not negative
  CHECK(value_of("1 EQ 1.00001") == 1);
  CHECK(value_of("1 NE 1.001") == 1);
  CHECK(value_of("3 GT 2 AND 1 LT 0") == 0);
  CHECK(value_of("3 GE 3 OR 0") == 1);
  CHECK(value_of("1 XOR 1") == 0);
  CHECK(value_of("2 LE 1") == 0);
  CHECK(value_of("SIN[30]") == doctest::Approx(0.5));
  CHECK(value_of("COS[60]") == doctest::Approx(0.5));
  CHECK(value_of("TAN[45]") == doctest::Approx(1));
  CHECK(value_of("ASIN[1]") == doctest::Approx(90));
  CHECK(value_of("ACOS[0]") == doctest::Approx(90));
  CHECK(value_of("ATAN[1]") == doctest::Approx(45));
  CHECK(value_of("ATAN[1]/[-1]") == doctest::Approx(135));
  CHECK(value_of("SQRT[16]") == 4);
  CHECK(value_of("ABS[-3]") == 3);
  CHECK(value_of("ROUND[2.5]") == 3);
  CHECK(value_of("ROUND[-2.5]") == -3);
  CHECK(value_of("LN[EXP[2]]") == doctest::Approx(2));
  CHECK(value_of("exp[0]") == 1);  // names are case-insensitive
  // Fanuc truncates FIX toward zero and FUP away from it; LinuxCNC floors and ceils.
  CHECK(value_of("FIX[-2.5]", Dialect::fanuc) == -2);
  CHECK(value_of("FUP[-2.5]", Dialect::fanuc) == -3);
  CHECK(value_of("FIX[-2.5]", Dialect::linuxcnc) == -3);
  CHECK(value_of("FUP[-2.5]", Dialect::linuxcnc) == -2);
  CHECK(value_of("FUP[2.1]") == 3);
}

TEST_CASE("macros: parameters, indirection, named parameters and the vacant value") {
  Result r = run_program("#1 = 2\n#2 = [#1 * 3]\n#[#1 + 1] = 7\nG0 X#2 Y##1 Z#3\nM30\n", {},
                         dialect(Dialect::fanuc));
  REQUIRE(r.moves.size() == 1);
  CHECK(near(r.moves[0].end, Vec3(6, 6, 7)));
  // LinuxCNC: settings on a line take effect after the line is read.
  r = run_program("#1 = 1\n#1 = 2 #2 = #1\nG0 X#1 Y#2 Z0\nM30\n", {}, dialect(Dialect::linuxcnc));
  CHECK(near(r.moves[0].end, Vec3(2, 1, 0)));
  r = run_program(
      "#<depth> = -2\n#<_safe> = 5\nG0 X EXISTS[#<depth>] Y EXISTS[#<nope>] Z[#<_safe> + "
      "#<depth>]\nM30\n",
      {}, dialect(Dialect::linuxcnc));
  CHECK(near(r.moves[0].end, Vec3(1, 0, 3)));
  // Fanuc: a word whose value is vacant is left out; vacant is 0 in arithmetic and only EQ #0.
  r = run_program("G0 X1 Y2 Z3\n#5 = #0\nG0 X#5 Y[#5 + 4] Z[#5 EQ #0]\nM30\n", {},
                  dialect(Dialect::fanuc));
  REQUIRE(r.moves.size() == 2);
  CHECK(near(r.moves[1].end, Vec3(1, 4, 1)));
  CHECK(value_of("0 EQ #0") == 0);
  // A feed left out for a vacant value (a persistent common the machine holds) is named.
  CHECK(error_of("G0 X0 Y0 Z5\nG1 Z0 F#650\n").message.find("F#650 was left out") !=
        std::string::npos);
  // LinuxCNC reads the same word as 0.
  r = run_program("G0 X1 Y2 Z3\nG0 X#5\nM30\n", {}, dialect(Dialect::linuxcnc));
  CHECK(near(r.moves[1].end, Vec3(0, 2, 3)));
  // System variables: the position (#5001, #<_x>), the work offsets (#5221...).
  r = run_program("G0 X4 Y5 Z6\n#5221 = 10\nG0 X[#5001 + #<_y>] Y#5221 Z#5043\nM30\n", {},
                  dialect(Dialect::fanuc));
  REQUIRE(r.moves.size() == 2);
  // G54 moved by 10 in X while active: the tip (machine 4) now reads X-6, so X is -6 + 5 = -1,
  // machine 9; Y is #5221 = 10; Z is the current Z, 6.
  CHECK(near(r.moves[1].end, Vec3(9, 10, 6)));
}

TEST_CASE("macros: random expressions agree with a reference evaluation of the same tree") {
  std::mt19937_64 rng(11);
  struct Node {
    int op = -1;  // -1: a number
    double value = 0;
    int left = -1, right = -1;
  };
  // Precedence (LinuxCNC's): ** 5; * / MOD 4; + - 3; comparisons 2; AND OR XOR 1.
  const char* names[] = {"**", "*",  "/",  "MOD", "+",   "-",  "EQ", "NE",
                         "GT", "GE", "LT", "LE",  "AND", "OR", "XOR"};
  const int prec[] = {5, 4, 4, 4, 3, 3, 2, 2, 2, 2, 2, 2, 1, 1, 1};
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<Node> nodes;
    std::function<int(int)> build = [&](int depth) {
      Node n;
      if (depth == 0 || rng() % 3 == 0) {
        n.value = static_cast<double>(static_cast<int>(rng() % 9) + 1);
      } else {
        n.op = static_cast<int>(rng() % 15);
        if (n.op == 0) n.op = 1 + static_cast<int>(rng() % 14);  // keep ** rare: overflow
        n.left = build(depth - 1);
        n.right = build(depth - 1);
      }
      nodes.push_back(n);
      return static_cast<int>(nodes.size()) - 1;
    };
    int root = build(4);
    std::function<double(int)> eval = [&](int k) {
      const Node& n = nodes[static_cast<std::size_t>(k)];
      if (n.op < 0) return n.value;
      double a = eval(n.left), b = eval(n.right);
      if (std::isnan(a) || std::isnan(b)) return std::nan("");  // an error anywhere fails it all
      switch (n.op) {
        case 0:
          return std::pow(a, b);
        case 1:
          return a * b;
        case 2:
          return b == 0 ? NAN : a / b;
        case 3: {
          if (b == 0) return std::nan("");
          double r = std::fmod(a, b);
          return r < 0 ? r + std::abs(b) : r;
        }
        case 4:
          return a + b;
        case 5:
          return a - b;
        case 6:
          return std::abs(a - b) < 1e-4 ? 1.0 : 0.0;
        case 7:
          return std::abs(a - b) < 1e-4 ? 0.0 : 1.0;
        case 8:
          return a > b ? 1.0 : 0.0;
        case 9:
          return a >= b ? 1.0 : 0.0;
        case 10:
          return a < b ? 1.0 : 0.0;
        case 11:
          return a <= b ? 1.0 : 0.0;
        case 12:
          return a != 0 && b != 0 ? 1.0 : 0.0;
        case 13:
          return a != 0 || b != 0 ? 1.0 : 0.0;
        default:
          return (a != 0) != (b != 0) ? 1.0 : 0.0;
      }
    };
    // Brackets only where precedence needs them (and at random elsewhere).
    std::function<std::string(int, int, bool)> print = [&](int k, int parent, bool right) {
      const Node& n = nodes[static_cast<std::size_t>(k)];
      if (n.op < 0) return cat(n.value);
      std::string text = cat(print(n.left, prec[n.op], false), " ", names[n.op], " ",
                             print(n.right, prec[n.op], true));
      bool needed =
          prec[n.op] < parent || (prec[n.op] == parent && right) || (parent == 5 && !right);
      return needed || rng() % 4 == 0 ? "[" + text + "]" : text;
    };
    double expected = eval(root);
    std::string text = print(root, 0, false);
    if (!std::isfinite(expected) || std::abs(expected) > 1e9) {
      Diagnostic d = error_of("G0 X[" + text + "] Y0 Z0\nM30\n", {}, at_origin());
      CHECK(d.line == 1);
      continue;
    }
    INFO(text);
    CHECK(value_of(text) == doctest::Approx(expected).epsilon(1e-12));
  }
}

TEST_CASE("macros: Fanuc control flow gives the moves of the same program written out") {
  same_moves("#1 = 0\nWHILE [#1 LT 3] DO1\nG0 X#1 Y0 Z0\n#1 = #1 + 1\nEND1\nM30\n",
             "G0 X0 Y0 Z0\nG0 X1\nG0 X2\nM30\n");
  // Nested loops, a counted GOTO loop backwards, a forward IF GOTO past a block.
  same_moves(
      "#1 = 0\nWHILE [#1 LT 2] DO1\n#2 = 0\nWHILE [#2 LT 2] DO2\nG0 X#1 Y#2 Z0\n#2 = #2 + 1\n"
      "END2\n#1 = #1 + 1\nEND1\nM30\n",
      "G0 X0 Y0 Z0\nY1\nX1 Y0\nY1\nM30\n");
  same_moves(
      "#1 = 3\nN10 G0 X#1 Y0 Z0\n#1 = #1 - 1\nIF [#1 GT 0] GOTO 10\nIF [1] GOTO 30\nG0 X99\nN30 G0 "
      "Z5\nM30\n",
      "G0 X3 Y0 Z0\nX2\nX1\nZ5\nM30\n");
  same_moves("#1 = 1\nIF [#1 EQ 1] THEN #2 = 5\nIF [#1 EQ 2] THEN #2 = 6\nG0 X#2 Y0 Z0\nM30\n",
             "G0 X5 Y0 Z0\nM30\n");
  // A false WHILE skips to its END; DO without WHILE runs until a GOTO leaves it.
  same_moves(
      "WHILE [0] DO1\nG0 X9 Y9 Z9\nEND1\n#1 = 0\nDO2\n#1 = #1 + 1\nG0 X#1 Y0 Z0\nIF [#1 GE 2] GOTO "
      "5\nEND2\nN5 M30\n",
      "G0 X1 Y0 Z0\nX2\nM30\n");
  // G65: arguments become locals of a new level; the caller's locals are untouched.
  same_moves(
      "#1 = 100\nG65 P9000 A1 B2 X3 L2\nG0 X#1 Y0 Z0\nM30\nO9000\nG0 X[#1 + #2] Y#24 Z#3\n#1 = "
      "50\nM99\n",
      "G0 X3 Y3 Z0\nG0 X3 Y3 Z0\nG0 X100 Y0 Z0\nM30\n");
  // M, S and T are arguments in a G65 block (#13, #19, #20), not codes.
  same_moves("G65 P9100 M0.07 T13.16 S5.\nM30\nO9100\nG0 X#13 Y#20 Z#19\nM99\n",
             "G0 X0.07 Y13.16 Z5\nM30\n");
}

TEST_CASE("macros: LinuxCNC o-words give the moves of the same program written out") {
  Dialect l = Dialect::linuxcnc;
  same_moves("o100 sub\nG0 X#1 Y#2 Z0\no100 endsub\no100 call [1] [2]\no100 call [3] [4]\nM2\n",
             "G0 X1 Y2 Z0\nG0 X3 Y4 Z0\nM2\n", l);
  same_moves(
      "#1 = 2\no1 if [#1 EQ 1]\nG0 X1 Y0 Z0\no1 elseif [#1 EQ 2]\nG0 X2 Y0 Z0\no1 else\nG0 X3 Y0 "
      "Z0\no1 endif\nM2\n",
      "G0 X2 Y0 Z0\nM2\n", l);
  same_moves("#1 = 0\no2 while [#1 LT 3]\nG0 X#1 Y0 Z0\n#1 = [#1 + 1]\no2 endwhile\nM2\n",
             "G0 X0 Y0 Z0\nX1\nX2\nM2\n", l);
  same_moves("#1 = 0\no3 do\nG0 X#1 Y0 Z0\n#1 = [#1 + 1]\no3 while [#1 LT 2]\nM2\n",
             "G0 X0 Y0 Z0\nX1\nM2\n", l);
  same_moves(
      "#1 = 0\no4 repeat [5]\n#1 = [#1 + 1]\no5 if [#1 EQ 2]\no4 continue\no5 endif\n"
      "o6 if [#1 EQ 4]\no4 break\no6 endif\nG0 X#1 Y0 Z0\no4 endrepeat\nM2\n",
      "G0 X1 Y0 Z0\nX3\nM2\n", l);
  same_moves(
      "o<twice> sub\no<twice> return [#1 * 2]\no<twice> endsub\no<twice> call [21]\nG0 X#<_value> "
      "Y0 Z0\nM2\n",
      "G0 X42 Y0 Z0\nM2\n", l);
  // A numbered subroutine defined after its call, read ahead as rs274 finds it (interp_o_word.cc
  // control_back_to: "skip to the o_word"); `o100 sub` was taken for a Fanuc program number O100,
  // so the call found no subroutine.
  same_moves("o100 call [5]\nM2\no100 sub\nG0 X#1 Y0 Z0\no100 endsub\n", "G0 X5 Y0 Z0\nM2\n", l);
  same_moves("o100 call\nG0 X3 Y0 Z0\nM2\no100 sub (a comment)\nG0 X2 Y0 Z0\no100 endsub\n",
             "G0 X2 Y0 Z0\nX3\nM2\n", l);
  // Named locals belong to the call; globals are shared.
  same_moves(
      "o10 sub\n#<a> = 7\n#<_g> = 8\no10 endsub\n#<a> = 1\no10 call\nG0 X#<a> Y#<_g> Z0\nM2\n",
      "G0 X1 Y8 Z0\nM2\n", l);
}

// LinuxCNC's #5410: the loaded tool's diameter as its tool table holds it, in the table's units
// (inches for rs274 run standalone) whatever the program's; 0 with no tool (rs274ngc_pre.cc
// set_tool_parameters; rs274 -t with T1 D0.125: G21 ... T1 M6 G0 X#5410 goes to X0.125). It read
// 0, and ngcgui's helix.ngc, ihex.ngc and the like, which size their compensated entry from it,
// were refused as entries too short for the tool.
TEST_CASE("macros: LinuxCNC's #5410 is the loaded tool's diameter in the tool table's units") {
  MachineConfig m = linuxcnc_at_origin();
  m.tool_diameters = {{1, 0.125 * 25.4}, {2, 6.0}};
  auto x_of = [&](const std::string& text) {
    Result r = run_program(text, {}, m);
    REQUIRE(!r.moves.empty());
    return r.moves.back().end.x;
  };
  CHECK(x_of("G21 G90\nG0 X#5410 Y0 Z0\nM2\n") == doctest::Approx(0));  // no tool yet
  CHECK(x_of("G21 G90\nT1 M6\nG0 X#5410 Y0 Z0\nM2\n") == doctest::Approx(0.125));
  CHECK(x_of("G20 G90\nT1 M6\nG0 X#5410 Y0 Z0\nM2\n") == doctest::Approx(0.125 * 25.4));
  // G10 L1 rewrites the loaded tool's entry, and #5410 with it (rs274: R0.5 mm, 0.0394 in).
  CHECK(x_of("G21 G90\nT1 M6\nG10 L1 P1 R0.5\nG0 X#5410 Y0 Z0\nM2\n") ==
        doctest::Approx(1.0 / 25.4));
  // A machine whose table is in mm (LinuxCNC's LINEAR_UNITS = mm) holds millimetres.
  m.tool_table_in_inches = false;
  CHECK(x_of("G21 G90\nT2 M6\nG0 X#5410 Y0 Z0\nM2\n") == doctest::Approx(6.0));
  // Fanuc has no such variable: it stays vacant and the word is left out.
  MachineConfig fanuc = at_origin();
  fanuc.tool_diameters = {{1, 6.0}};
  Result r = run_program("G21 G90\nT1 M6\nG0 X5 Y0 Z0\nG0 X#5410 Y1\nM30\n", {}, fanuc);
  REQUIRE(!r.moves.empty());
  CHECK(r.moves.back().end.x == doctest::Approx(5));
}

TEST_CASE("macros: subprogram files are found by name, or by the O number they start with") {
  namespace fs = std::filesystem;
  fs::path dir = fs::temp_directory_path() / ("tridex_subs_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "O9810.nc") << "%\nO9810 (PROBE)\nG0 X#24 Y#25 Z1\nM99\n%\n";
  std::ofstream(dir / "corner.ngc") << "o<corner> sub\nG0 X#1 Y#1 Z2\no<corner> endsub\n";
  MachineConfig m = at_origin();
  m.subprogram_dirs.push_back(dir.string());
  Result r = run_program("G65 P9810 X4 Y5\nM98 P9810\no<corner> call [3]\nM30\n", {}, m);
  REQUIRE(r.moves.size() == 3);
  CHECK(near(r.moves[0].end, Vec3(4, 5, 1)));
  CHECK(near(r.moves[2].end, Vec3(3, 3, 2)));
  // Each move names its file (an index into Interpreter::files()) and its line in that file.
  CHECK((r.moves[0].file == 1 && r.moves[0].line == 3 && r.moves[1].file == 1 &&
         r.moves[2].file == 2 && r.moves[2].line == 2));
  Interpreter interpreter({}, m);
  std::istringstream program("G0 X0 Y0 Z0\no<corner> call [3]\nM98 P9810\nG0 X1\nM30\n");
  std::vector<std::pair<int, int>> places;
  interpreter.run(program, "main.nc",
                  [&](const Move& move) { places.emplace_back(move.file, move.line); });
  CHECK(places == std::vector<std::pair<int, int>>{{0, 1}, {1, 2}, {2, 3}, {0, 4}});
  REQUIRE(interpreter.files().size() == 3);
  CHECK(interpreter.files()[0] == "main.nc");
  CHECK(fs::path(interpreter.files()[1]).filename() == "corner.ngc");
  CHECK(fs::path(interpreter.files()[2]).filename() == "O9810.nc");
  // Not found: an error naming the program; with lenient, a warning and the call skipped.
  Diagnostic d = error_of("G65 P9999\nM30\n", {}, m);
  CHECK(d.message.find("O9999") != std::string::npos);
  InterpreterOptions lenient;
  lenient.lenient = true;
  r = run_program("G65 P9999\nG0 X1 Y1 Z1\nM30\n", lenient, m);
  CHECK(r.moves.size() == 1);
  CHECK(!r.warnings.empty());
  // Failing a name, by the O number a file starts with (after %, blank lines and comments), as a
  // control keeps them; Fanuc's ':' spelling too. A file that starts otherwise is not taken.
  std::ofstream(dir / "gauge_tool.cnc") << "%\n(TOOL GAUGE)\n\nO1002 (SUB)\nG0 X7 Y8 Z3\nM99\n%\n";
  std::ofstream(dir / "second.txt") << ":1003\nG0 X9 Y9 Z9\nM99\n";
  std::ofstream(dir / "notes.txt") << "G0 X1\nO1004\nM99\n";
  r = run_program("M98 P1002\nM98 P1003\nM30\n", {}, m);
  REQUIRE(r.moves.size() == 2);
  CHECK(near(r.moves[0].end, Vec3(7, 8, 3)));
  CHECK(near(r.moves[1].end, Vec3(9, 9, 9)));
  CHECK(error_of("M98 P1004\nM30\n", {}, m).message.find("O1004") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("macros: bad input is an error at its line and column") {
  MachineConfig m = at_origin();
  Diagnostic d = error_of("G0 X0 Y0 Z0\nG0 X[1/0]\n", {}, m);
  CHECK(d.line == 2);
  CHECK(d.column == 7);
  CHECK(d.message.find("division by zero") != std::string::npos);
  d = error_of("G0 X#<nope> Y0 Z0\n", {}, dialect(Dialect::linuxcnc));
  CHECK(d.column == 5);
  CHECK(d.message.find("#<nope>") != std::string::npos);
  d = error_of("G0 X[1+2 Y0 Z0\n", {}, m);
  CHECK(d.message.find("not closed") != std::string::npos);
  CHECK(error_of("G0 X SQRT[-1] Y0 Z0\n", {}, m).message.find("SQRT") != std::string::npos);
  CHECK(error_of("#0 = 1\n", {}, m).message.find("#0") != std::string::npos);
  CHECK(error_of("#3000 = 12 (TOOL BROKEN)\n", {}, m).message.find("alarm") != std::string::npos);
  CHECK(error_of("END1\n", {}, m).message.find("END 1") != std::string::npos);
  CHECK(error_of("GOTO 50\nM30\n", {}, m).message.find("N50") != std::string::npos);
  CHECK(error_of("WHILE [0] DO1\nG0 X1 Y1 Z1\n", {}, m).message.find("END 1") != std::string::npos);
  CHECK(
      error_of("o1 if [0]\nG0 X1 Y1 Z1\n", {}, dialect(Dialect::linuxcnc)).message.find("endif") !=
      std::string::npos);
  // LinuxCNC's own nestedcall.ngc says `o<g20sub> callsub`: rs274 refuses it too ("Unexpected
  // character after O-word"). The keyword is the whole word, named in the message.
  d = error_of("o<g20sub> callsub\n", {}, dialect(Dialect::linuxcnc));
  CHECK(d.column == 11);
  CHECK(d.message.find("unknown o-word keyword 'callsub'") != std::string::npos);
  CHECK(error_of("o100 ifx [1]\n", {}, dialect(Dialect::linuxcnc)).message.find("'ifx'") !=
        std::string::npos);
  // Endless loops stop at the block limit.
  InterpreterOptions bounded;
  bounded.max_blocks = 10000;
  d = error_of("WHILE [1] DO1\nEND1\n", bounded, m);
  CHECK(d.message.find("10000 blocks") != std::string::npos);
  d = error_of("N1 GOTO 1\n", bounded, m);
  CHECK(d.message.find("blocks") != std::string::npos);
  // The limit names the statement that passed it: its line and the column where it starts.
  // Blocks: G21 is 1, then WHILE, #100, END repeat (3k+2, 3k+3, 3k+4): block 10001 is a WHILE.
  const std::string loop = "G21\n  WHILE [1] DO1\n   #100 = [#100 + 1]\nEND1\n";
  d = error_of(loop, bounded, m);
  CHECK(d.line == 2);
  CHECK(d.column == 3);
  bounded.max_blocks = 10001;
  d = error_of(loop, bounded, m);
  CHECK(d.line == 3);  // an assignment alone
  CHECK(d.column == 4);
  bounded.max_blocks = 10002;
  d = error_of(loop, bounded, m);
  CHECK(d.line == 4);  // the END of the loop
  CHECK(d.column == 1);
  d = error_of("G21\nM98 P2 L9999\nM30\nO2\n N5 G4 P0\nM99\n", bounded, m);
  CHECK(d.line == 5);
  CHECK(d.column == 2);
}
