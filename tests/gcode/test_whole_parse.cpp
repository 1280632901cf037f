// The plain-program fast paths against the general ones: the lexer's one-pass number reading
// against a correctly rounded conversion (strtod), digit for digit; the read-ahead
// (InterpreterOptions::read_ahead) against the interpreter reading alone, on the test programs and
// on random programs with parameters, jumps, loops, subprograms, long lines and errors mid-file.
#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "tridex/gcode/interpreter.hpp"
#include "tridex/gcode/lexer.hpp"

namespace test_whole_parse {

using namespace tridex::gcode;

// A random decimal of 1 to 18 digits with the point anywhere (or none), leading zeros included.
std::string random_decimal(std::mt19937_64& random) {
  std::uniform_int_distribution<int> length(1, 18), digit(0, 9);
  const int digits = length(random);
  std::uniform_int_distribution<int> point(-1, digits);
  const int at = point(random);
  std::string text;
  for (int k = 0; k < digits; ++k) {
    if (k == at) text += '.';
    text += static_cast<char>('0' + digit(random));
  }
  if (at == digits) text += '.';
  return text;
}

TEST_CASE("fast parse: word values equal the correctly rounded decimal, bit for bit") {
  std::mt19937_64 random(37);
  Block block;
  LexError error;
  int read = 0;
  for (int i = 0; i < 50000; ++i) {
    const std::string number = random_decimal(random);
    const bool ok = lex_line("X-" + number + " Y" + number, block, error);
    const double expected = std::strtod(number.c_str(), nullptr);
    if (expected > kMaxWordValue) {  // refused as out of range, whichever path read it
      CHECK_MESSAGE(!ok, number);
      continue;
    }
    REQUIRE_MESSAGE(ok, number << ": " << error.message);
    REQUIRE(block.words.size() == 2);
    CHECK_MESSAGE(block.words[1].value == expected, number);
    CHECK_MESSAGE(block.words[0].value == -expected, number);
    ++read;
  }
  CHECK(read > 25000);
  // Exact halfway and near-halfway cases, 15 and 16 digits, and malformed numbers.
  for (const std::string number :
       {"0.1", "0.3", "123456789.012345", "999999999.999999", "1000000000", "1000000000.",
        "0.000000000000001", "900719925.4740993", "0.30000000000000004", "1.0000000000000002"}) {
    REQUIRE_MESSAGE(lex_line("Z" + number, block, error), number);
    CHECK_MESSAGE(block.words[0].value == std::strtod(number.c_str(), nullptr), number);
  }
  CHECK(!lex_line("X1.2.3", block, error));
  CHECK(error.message == "word X: malformed number");
  CHECK(error.column == 2);
  CHECK(!lex_line("X1000000000.5", block, error));
  CHECK(error.message.find("out of range") != std::string::npos);
}

// Everything a run tells: moves and dwells (every field), warnings, blocks, files, the error.
std::string outcome(std::istream& in, const std::string& name, bool read_ahead,
                    const MachineConfig& machine) {
  InterpreterOptions options;
  options.read_ahead = read_ahead;
  Interpreter interpreter(options, machine);
  std::ostringstream out;
  auto vec = [&](const Vec3& v) { out << std::hexfloat << v.x << ',' << v.y << ',' << v.z << ' '; };
  auto move = [&](const Move& m) {
    out << m.line << ' ' << static_cast<int>(m.kind) << ' ' << m.tool << ' ' << m.file << ' ';
    vec(m.start);
    vec(m.end);
    vec(m.axis);
    vec(m.machine);
    out << m.feed << ' ' << m.spindle << ' ' << m.from_far << ' ' << int(m.rotary_axes) << ' '
        << static_cast<int>(m.pose);
    for (int k = 0; k < 3; ++k) out << ' ' << m.rotary[k] << ' ' << m.rotary_start[k];
    out << '\n';
  };
  auto dwell = [&](const Dwell& d) {
    out << "dwell " << d.line << ' ' << d.tool << ' ' << d.seconds << ' ';
    vec(d.axis);
    out << '\n';
  };
  try {
    interpreter.run(in, name, move, dwell);
  } catch (const GcodeError& e) {
    out << "error " << e.where.to_string() << '\n';
  }
  for (const Diagnostic& d : interpreter.warnings()) out << "warning " << d.to_string() << '\n';
  for (const std::string& f : interpreter.files()) out << "file " << f << '\n';
  out << "blocks " << interpreter.blocks() << '\n';
  return out.str();
}

std::string outcome_of_text(const std::string& text, bool read_ahead,
                            const MachineConfig& machine = {}) {
  std::istringstream in(text);
  return outcome(in, "soup.nc", read_ahead, machine);
}

MachineConfig machine_for(const std::filesystem::path& file) {
  MachineConfig machine =
      *MachineConfig::bundled(file.extension() == ".ngc" ? "linuxcnc" : "default");
  machine.tool_diameters[1] = 6;
  machine.tool_diameters[2] = 10;
  return machine;
}

TEST_CASE("read ahead: the test programs run as without it") {
  int programs = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(
           std::filesystem::path(TRIDEX_TEST_DATA) / "gcode")) {
    const std::filesystem::path& file = entry.path();
    if (file.extension() != ".nc" && file.extension() != ".ngc") continue;
    std::ifstream alone(file, std::ios::binary), ahead(file, std::ios::binary);
    const MachineConfig machine = machine_for(file);
    const std::string expected = outcome(alone, file.string(), false, machine);
    CHECK_MESSAGE(outcome(ahead, file.string(), true, machine) == expected, file.string());
    ++programs;
  }
  CHECK(programs > 20);
}

// A random program: plain moves above all, with now and then what the read-ahead must leave to
// the interpreter (parameters, settings, IF/GOTO, WHILE loops, M98 calls) and, where asked, an
// error at a random line, a line too long for the reader, a byte order mark, CR LF line ends.
std::string block_soup(std::mt19937_64& random, int lines, bool jumps, bool faults) {
  std::uniform_real_distribution<double> coordinate(-50, 50);
  std::uniform_int_distribution<int> pick(0, 99);
  std::string text = pick(random) < 30 ? "\xEF\xBB\xBF%\n" : "%\n";
  text += "O1000\nG21 G90 G17 G54\nT1 M6\nS5000 M3\n#1 = 2\n#2 = 0\n";
  const bool crlf = pick(random) < 30;
  const int bad =
      faults && pick(random) < 70 ? std::uniform_int_distribution<int>(1, lines)(random) : -1;
  const int longline =
      faults && pick(random) < 30 ? std::uniform_int_distribution<int>(1, lines)(random) : -1;
  char line[200];
  for (int i = 0; i < lines; ++i) {
    const int p = pick(random);
    const double x = coordinate(random), y = coordinate(random), z = coordinate(random) / 10;
    if (i == bad) {
      const char* faulty[] = {"G1 X1..2",      "G1 X(unclosed", "G1 Q",     "G1 X[1/0]",
                              "G2 X1 Y1 R0.1", "G1 X#",         "M98 P9999"};
      text += faulty[pick(random) % 7];
    } else if (i == longline) {
      text += "G1 X1 (" + std::string(70000, 'c') + ")";
    } else if (p < 55) {
      std::snprintf(line, sizeof line, "G1 X%.3f Y%.3f Z%.3f", x, y, z);
      text += line;
      if (p < 10) text += " F" + std::to_string(100 + pick(random) * 10);
    } else if (p < 62) {
      std::snprintf(line, sizeof line, "N%d g0x%.4fY%.2f (rapid) ; note", i, x, y);
      text += line;
    } else if (p < 66) {
      std::snprintf(line, sizeof line, "/G1 X%.3f", x);
      text += line;
    } else if (p < 70) {
      std::snprintf(line, sizeof line, "G1 X[%.3f + #1] Y#2 Z-[#1 * 0.5]", x);
      text += line;
    } else if (p < 73) {
      text += "#2 = [#2 + 0.25]";
    } else if (p < 76) {
      text += "(a comment) G4 P10";
    } else if (p < 78) {
      text += "";
    } else if (p < 81) {
      text += "G81 X1 Y2 Z-3 R1 F100\nG80";
    } else if (jumps && p < 83) {
      text += "IF [#2 GT 1000] GOTO 9000";
    } else if (jumps && p < 85) {
      text += "M98 P2000 L2";
    } else if (jumps && p < 86) {
      text += "#3 = 0\nWHILE [#3 LT 3] DO1\nG1 X#3 Y-#3\n#3 = [#3 + 1]\nEND1";
    } else if (p < 88) {
      text += "IF [0 EQ 1] THEN #4 = 1";
    } else {
      std::snprintf(line, sizeof line, "G1 X%.6f Y%.1f Z%.0f F1200.", x, y, z);
      text += line;
    }
    text += crlf ? "\r\n" : "\n";
  }
  text += "N9000 M30\n";
  text += "O2000\nG91 G1 X1 Y1\nG90\nM99\n";
  if (pick(random) < 50) text += "%";  // with or without a last line end
  return text;
}

TEST_CASE("read ahead: random programs run as without it, errors mid-file included") {
  std::mt19937_64 random(2026);
  int errors = 0;
  for (int program = 0; program < 24; ++program) {
    const bool jumps = program % 3 == 0, faults = program % 2 == 1;
    const int lines = program % 8 == 0 ? 12000 : 600;  // some cross the 64 KiB chunks
    const std::string text = block_soup(random, lines, jumps, faults);
    const std::string expected = outcome_of_text(text, false);
    CHECK_MESSAGE(outcome_of_text(text, true) == expected, "program " << program);
    errors += expected.find("error ") != std::string::npos;
  }
  CHECK(errors >= 3);
}

}  // namespace test_whole_parse
