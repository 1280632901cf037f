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

// clang-format off
// The G codes by name, as Code::code holds them (times ten: G53.1 is kG53_1 = 531). Every code the
// interpreter reads is named here; a bare number in gcode/src is a parameter, a count or a length.
inline constexpr int kG0 = 0, kG1 = 10, kG2 = 20, kG3 = 30, kG4 = 40;
inline constexpr int kG5 = 50, kG5_1 = 51, kG5_2 = 52, kG5_3 = 53;  // LinuxCNC's splines, NURBS
inline constexpr int kG7 = 70, kG8 = 80, kG9 = 90, kG10 = 100, kG13_1 = 131, kG15 = 150;
inline constexpr int kG17 = 170, kG18 = 180, kG19 = 190, kG20 = 200, kG21 = 210;
inline constexpr int kG28 = 280, kG30 = 300, kG31 = 310, kG33 = 330;
inline constexpr int kG38_2 = 382, kG38_3 = 383, kG38_4 = 384, kG38_5 = 385;
inline constexpr int kG40 = 400, kG41 = 410, kG41_1 = 411, kG42 = 420, kG42_1 = 421;
inline constexpr int kG43 = 430, kG43_1 = 431, kG43_4 = 434, kG43_5 = 435, kG44 = 440, kG49 = 490;
inline constexpr int kG50 = 500, kG50_1 = 501, kG52 = 520, kG53 = 530;
inline constexpr int kG53_1 = 531, kG53_3 = 533, kG53_6 = 536;
inline constexpr int kG54 = 540, kG54_1 = 541, kG55 = 550, kG56 = 560, kG57 = 570, kG58 = 580,
                     kG59 = 590;
inline constexpr int kG61 = 610, kG61_1 = 611, kG62 = 620, kG63 = 630, kG64 = 640, kG65 = 650;
inline constexpr int kG67 = 670, kG68 = 680, kG68_2 = 682, kG68_3 = 683, kG68_4 = 684, kG69 = 690;
inline constexpr int kG70 = 700, kG71 = 710, kG71_1 = 711, kG71_2 = 712, kG72 = 720, kG72_1 = 721,
                     kG72_2 = 722;
inline constexpr int kG73 = 730, kG74 = 740, kG76 = 760, kG80 = 800, kG81 = 810, kG82 = 820,
                     kG83 = 830, kG84 = 840, kG85 = 850, kG86 = 860, kG89 = 890;
inline constexpr int kG90 = 900, kG90_1 = 901, kG91 = 910, kG91_1 = 911;
inline constexpr int kG92 = 920, kG92_1 = 921, kG92_2 = 922, kG92_3 = 923;
inline constexpr int kG93 = 930, kG94 = 940, kG95 = 950, kG96 = 960, kG97 = 970, kG98 = 980,
                     kG99 = 990;
inline constexpr int kG103 = 1030, kG154 = 1540, kG187 = 1870;  // Haas look-ahead, offsets; G187
inline constexpr int kG234 = 2340, kG253 = 2530, kG254 = 2540, kG255 = 2550, kG268 = 2680,
                     kG269 = 2690;  // Haas

// The M codes by name, as Code::code holds them for M (not times ten: M98 is 98).
inline constexpr int kM0 = 0, kM1 = 1, kM2 = 2, kM3 = 3, kM4 = 4, kM5 = 5, kM6 = 6;
inline constexpr int kM7 = 7, kM8 = 8, kM9 = 9, kM30 = 30, kM61 = 61, kM97 = 97, kM98 = 98, kM99 = 99;

// clang-format on

struct Code {
  int code;  // G codes times ten: G53.1 -> 531 (kG53_1), G1 -> 10 (kG1); M codes as written
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
  bool m_arguments = false;    // an accepted M-code that takes P Q E L R words is in the block
  int kinematics_switch = -1;  // a machine's kinematics switch M-code in the block (or -1)
  int kinematics_switch_column = 0;                        // and its column
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

// The codes and their groups read as tables.
// clang-format off
// Modal groups (RS274/NGC table 4, plus the tilted-plane codes); -1: not supported.
enum Group {
  kNonModal, kMotion, kPlane, kDistance, kArcDistance, kFeedMode, kUnits, kCutterComp,
  kToolLength, kReturn, kWork, kSpindleMode, kPolar, kPath, kTilt, kOrient, kSmoothing,
  kDynamicOffset, kGroupCount
};

inline int g_group(int code) {
  switch (code) {
    case kG4: case kG10: case kG28: case kG30: case kG53: case kG52: case kG65: case kG92:
    case kG92_1: case kG92_2: case kG92_3: return kNonModal;
    case kG0: case kG1: case kG2: case kG3: case kG73: case kG74: case kG80: case kG81: case kG82:
    case kG83: case kG84: case kG85: case kG86: case kG89: return kMotion;
    case kG17: case kG18: case kG19: return kPlane;
    case kG90: case kG91: return kDistance;
    case kG90_1: case kG91_1: return kArcDistance;
    case kG93: case kG94: case kG95: return kFeedMode;
    case kG20: case kG21: return kUnits;
    case kG40: case kG41: case kG42: case kG41_1: case kG42_1: return kCutterComp;
    case kG43: case kG43_1: case kG43_4: case kG43_5: case kG44: case kG49: return kToolLength;
    case kG98: case kG99: return kReturn;
    case kG54: case kG55: case kG56: case kG57: case kG58: case kG59: case kG54_1: case kG154:
      return kWork;
    case kG97: return kSpindleMode;
    case kG15: return kPolar;
    case kG61: case kG64: return kPath;
    case kG68: case kG68_2: case kG68_3: case kG68_4: case kG69: case kG268: case kG269: return kTilt;
    case kG53_1: case kG53_3: case kG53_6: case kG253: return kOrient;
    case kG5_1: case kG8: case kG103: case kG187:
      return kSmoothing;  // Fanuc G5.1 Q / G8 P, Haas G103 P, G187 P E
    case kG254: case kG255: return kDynamicOffset;  // Haas DWO
    default: return -1;
  }
}

enum MGroup { kStop, kToolChange, kSpindle, kCoolant, kMGroupCount };

inline int m_group(int code) {
  switch (code) {
    case kM0: case kM1: case kM2: case kM30: case kM97: case kM98: case kM99: return kStop;
    case kM6: case kM61: return kToolChange;
    case kM3: case kM4: case kM5: return kSpindle;
    case kM7: case kM8: case kM9: return kCoolant;
    default: return -1;
  }
}

// clang-format on

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
  return motion == kG73 || motion == kG74 || motion == kG81 || motion == kG82 || motion == kG83 ||
         motion == kG84 || motion == kG85 || motion == kG86 || motion == kG89;
}

// Plane axes (u, v) and normal w as coordinate indices: G17 XY, G18 ZX, G19 YZ.
inline std::array<int, 3> plane_axes(int plane) {
  if (plane == kG18) return {2, 0, 1};
  if (plane == kG19) return {1, 2, 0};
  return {0, 1, 2};
}

inline constexpr char kAxisLetter[3] = {'X', 'Y', 'Z'};
inline constexpr char kCenterLetter[3] = {'I', 'J', 'K'};

// What a block asks of the program flow: go on, end, call a subprogram (M98: same locals),
// call a macro (G65: new locals from its arguments) or return (M99).
enum class Flow { next, end, call, macro, ret };

}  // namespace tridex::gcode
