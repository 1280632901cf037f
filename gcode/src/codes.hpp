// tridex::gcode — the words of one block gathered by letter, and the modal groups of the G and M
// codes (RS274/NGC table 4, plus the tilted-plane and controller-specific codes).
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace tridex::gcode {

// 'A'..'Z' are 0..25; LinuxCNC's polar words '@' (radius) and '^' (angle) take 26 and 29 ('^' -
// 'A'), so one 32-bit mask still holds every word of a block.
inline int letter_index(char c) { return c == '@' ? 26 : c - 'A'; }
inline constexpr std::size_t kWordSlots = 30;

struct Code {
  int code;    // G and M codes times ten: G53.1 -> 531, G1 -> 10
  int column;
};

struct Words {
  std::array<double, kWordSlots> value{};
  std::array<int, kWordSlots> column{};
  std::uint32_t present = 0;
  std::uint32_t used = 0;
  std::array<Code, 24> g{};
  int g_count = 0;
  std::array<Code, 8> m{};
  int m_count = 0;
  bool m_arguments = false;  // an accepted M-code that takes P Q E L R words is in the block
  const std::vector<std::string>* vacant_words = nullptr;  // the block's (Block::vacant_words)

  bool has(char c) const { return (present >> letter_index(c)) & 1u; }
  int col(char c) const { return column[static_cast<std::size_t>(letter_index(c))]; }
  double take(char c) {
    used |= 1u << letter_index(c);
    return value[static_cast<std::size_t>(letter_index(c))];
  }
  int find_g(int code) const {
    for (int i = 0; i < g_count; ++i)
      if (g[static_cast<std::size_t>(i)].code == code) return g[static_cast<std::size_t>(i)].column;
    return 0;
  }
  int find_m(int code) const {
    for (int i = 0; i < m_count; ++i)
      if (m[static_cast<std::size_t>(i)].code == code) return m[static_cast<std::size_t>(i)].column;
    return 0;
  }
};

// Modal groups (RS274/NGC table 4, plus the tilted-plane codes); -1: not supported.
enum Group {
  kNonModal, kMotion, kPlane, kDistance, kArcDistance, kFeedMode, kUnits, kCutterComp,
  kToolLength, kReturn, kWork, kSpindleMode, kPolar, kPath, kTilt, kOrient, kSmoothing,
  kDynamicOffset, kGroupCount
};

inline int g_group(int code) {
  switch (code) {
    case 40: case 100: case 280: case 300: case 530: case 520: case 650: case 920: case 921:
    case 922: case 923: return kNonModal;
    case 0: case 10: case 20: case 30: case 730: case 740: case 800: case 810: case 820: case 830:
    case 840: case 850: case 860: case 890: return kMotion;
    case 170: case 180: case 190: return kPlane;
    case 900: case 910: return kDistance;
    case 901: case 911: return kArcDistance;
    case 930: case 940: case 950: return kFeedMode;
    case 200: case 210: return kUnits;
    case 400: case 410: case 420: case 411: case 421: return kCutterComp;
    case 430: case 431: case 434: case 435: case 440: case 490: return kToolLength;
    case 980: case 990: return kReturn;
    case 540: case 550: case 560: case 570: case 580: case 590: case 541: case 1540: return kWork;
    case 970: return kSpindleMode;
    case 150: return kPolar;
    case 610: case 640: return kPath;
    case 680: case 682: case 683: case 684: case 690: case 2680: case 2690: return kTilt;
    case 531: case 533: case 536: case 2530: return kOrient;
    case 51: case 80: case 1030: case 1870: return kSmoothing;  // Fanuc G5.1 Q / G8 P, Haas G103 P, G187 P E
    case 2540: case 2550: return kDynamicOffset;     // Haas DWO
    default: return -1;
  }
}

enum MGroup { kStop, kToolChange, kSpindle, kCoolant, kMGroupCount };

inline int m_group(int code) {
  switch (code) {
    case 0: case 1: case 2: case 30: case 97: case 98: case 99: return kStop;
    case 6: case 61: return kToolChange;
    case 3: case 4: case 5: return kSpindle;
    case 7: case 8: case 9: return kCoolant;
    default: return -1;
  }
}

inline std::string code_name(char letter, int code10) {
  char text[32];
  if (code10 % 10)
    std::snprintf(text, sizeof text, "%c%d.%d", letter, code10 / 10, code10 % 10);
  else
    std::snprintf(text, sizeof text, "%c%d", letter, code10 / 10);
  return text;
}

inline std::string format_number(double v) {
  char text[48];
  std::snprintf(text, sizeof text, "%.10g", v);
  return text;
}

inline bool is_cycle(int motion) {
  return motion == 730 || motion == 740 || motion == 810 || motion == 820 || motion == 830 ||
         motion == 840 || motion == 850 || motion == 860 || motion == 890;
}

// Plane axes (u, v) and normal w as coordinate indices: G17 XY, G18 ZX, G19 YZ.
inline std::array<int, 3> plane_axes(int plane) {
  if (plane == 180) return {2, 0, 1};
  if (plane == 190) return {1, 2, 0};
  return {0, 1, 2};
}

inline constexpr char kAxisLetter[3] = {'X', 'Y', 'Z'};
inline constexpr char kCenterLetter[3] = {'I', 'J', 'K'};

// What a block asks of the program flow: go on, end, call a subprogram (M98: same locals),
// call a macro (G65: new locals from its arguments) or return (M99).
enum class Flow { next, end, call, macro, ret };

}  // namespace tridex::gcode
