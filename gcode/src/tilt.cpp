// tridex::gcode — the tilted-working-plane codes: G68.2 in each control's form, G68.3, G68.4,
// Haas G268, and the orienting codes G53.1, G53.6, G253 and LinuxCNC's G53.3. This file reads
// the words; the frames and the manuals they follow are in tilted_plane.hpp.
#include "state.hpp"
#include "tridex/gcode/tilted_plane.hpp"

namespace tridex::gcode {
namespace {

Vec3 word_vector(Words& w, char a, char b, char c) {
  return Vec3(w.has(a) ? w.take(a) : 0.0, w.has(b) ? w.take(b) : 0.0, w.has(c) ? w.take(c) : 0.0);
}

}  // namespace

// The frame of a G68.2 / G68.4 / G268 block in the frame it is written in (the work frame for
// G68.2 and G268, the current feature frame for G68.4). Words, by form:
//   G68.2 [P0] X Y Z I J K        Fanuc Euler Z-X-Z
//   G68.2 [P0] X Y Z A B C        Mazak: the same angles in A B C
//   G68.2 X Y Z I J K U V W       Hurco: IJK the feature X direction, UVW its Y direction
//   G68.2 [P0] Q X Y Z I J K [R]  LinuxCNC: Q the Euler order (121 … 323), R about the work Z
//   G68.2 P1 [Q] X Y Z I J K      Fanuc/Mazak: angles about the fixed X, Y, Z in the order Q;
//                                 LinuxCNC's dialect (machine file): I J K the first to third
//                                 angle of the intrinsic order Q, and R about the work Z
//   G268 X Y Z I J K [Q]          Haas: as P1 (Q123 when Q is absent)
Frame Interpreter::State::plane_words(int code) {
  int column = w.find_g(code);
  Vec3 o(0.0);
  for (int i = 0; i < 3; ++i)
    if (w.has(kAxisLetter[i])) o[i] = length(kAxisLetter[i]);
  bool abc = w.has('A') || w.has('B') || w.has('C');
  bool uvw = w.has('U') || w.has('V') || w.has('W');
  bool ijk = w.has('I') || w.has('J') || w.has('K');
  long long p = 0;
  if (w.has('P')) {
    if (code == 2680) error(w.col('P'), "G268 has no P word");
    p = integer('P', "G68.2 P", 0, 3);
  }
  if (p == 2 || p == 3)
    error(w.col('P'), code_name('G', code) + " P" + std::to_string(p) +
                          " (three points / two vectors over several blocks) is not read yet");
  int q = code == 2680 || p == 1 ? 123 : 0;
  int q_column = column;
  if (w.has('Q')) {
    q_column = w.col('Q');
    q = static_cast<int>(integer('Q', (code_name('G', code) + " Q").c_str(), 0, 999));
  }
  if (abc && (ijk || uvw))
    error(w.col(w.has('A') ? 'A' : w.has('B') ? 'B' : 'C'),
          code_name('G', code) + " with both A B C and I J K/U V W angles");
  if (abc && (p != 0 || w.has('Q')))
    error(column, code_name('G', code) + " A B C (Mazak's Euler angles) take no P1 or Q");
  if (uvw && (p != 0 || w.has('Q')))
    error(column, code_name('G', code) + " I J K U V W (Hurco's vectors) take no P1 or Q");
  if (uvw && code == 2680) error(column, "G268 has no U V W words");
  if (abc && code == 2680) error(column, "G268 takes its angles in I J K, not A B C");
  try {
    if (uvw) {
      Vec3 x = word_vector(w, 'I', 'J', 'K'), y = word_vector(w, 'U', 'V', 'W');
      return hurco_vector_frame(o, x, y);
    }
    Vec3 angles = abc ? word_vector(w, 'A', 'B', 'C') : word_vector(w, 'I', 'J', 'K');
    bool linuxcnc = machine.dialect == Dialect::linuxcnc && code != 2680;
    if (p == 1 && linuxcnc)  // LinuxCNC's P1: I J K the first to third angle of the order Q
      return linuxcnc_angles_frame(1, q, o, angles.x, angles.y, angles.z,
                                   w.has('R') ? w.take('R') : 0.0);
    if (code == 2680 || p == 1) return fixed_axis_angles(o, angles.x, angles.y, angles.z, q);
    if (w.has('Q'))  // LinuxCNC's P0: Q names the Euler order; R turns about the work Z
      return linuxcnc_angles_frame(0, q, o, angles.x, angles.y, angles.z,
                                   w.has('R') ? w.take('R') : 0.0);
    return fanuc_euler(o, angles.x, angles.y, angles.z);
  } catch (const GcodeError&) {
    throw;
  } catch (const Error& e) {
    error(q_column, code_name('G', code) + ": " + e.what());
  }
}

void Interpreter::State::tilted_plane(int code) {
  if (code == 690 || code == 2690) {
    tilted = false;
    update_frame();
    return;
  }
  int column = w.find_g(code);
  if (incremental) error(column, code_name('G', code) + " under G91 is not supported; use G90");
  Frame feature;
  if (code == 683) {
    // G68.3 X Y Z R (Fanuc B-79976E): Z along the tool; the origin is X Y Z, all three or none
    // (none: the tool tip where it stands).
    int given = int(w.has('X')) + int(w.has('Y')) + int(w.has('Z'));
    if (given != 0 && given != 3)
      error(column, "G68.3 needs all of X, Y and Z for the origin, or none of them");
    Vec3 o(0.0);
    if (given == 3) {
      for (int i = 0; i < 3; ++i) o[i] = length(kAxisLetter[i]);
      o += work_offset + local_offset;
    } else {
      if (far)
        error(column, "G68.3 without X Y Z takes the tool tip as the origin, but the tool is "
                      "retracted far along its axis: give X, Y and Z");
      o = pos;
    }
    try {
      feature = tool_axis_frame(o, axis, w.has('R') ? w.take('R') : 0.0);
    } catch (const Error& e) {
      error(column, std::string("G68.3: ") + e.what());
    }
  } else if (code == 684) {
    // G68.4: the same forms as G68.2, given in the active feature frame and composed with it.
    if (!tilted) error(column, "G68.4 (incremental tilted plane) without an active tilted plane");
    feature = compose(Frame{tilt_rotation, tilt_origin}, plane_words(684));
  } else {
    feature = plane_words(code);
    feature.origin += work_offset + local_offset;  // on the active work coordinate system
  }
  tilt_rotation = feature.rotation;
  tilt_origin = feature.origin;
  tilted = true;
  tilt_line = line;
  update_frame();
}

// G53.1 / G53.6 / G253 turn the tool to the feature Z; LinuxCNC's G53.1, G53.3 and G53.6 take P
// (0 shortest, 1 positive, 2 negative turn of the rotaries: which pose, not which direction),
// and G53.3 I J K then rapids to that point of the plane (remap.py's g53n_core).
void Interpreter::State::orient_to_plane(int code) {
  int column = w.find_g(code);
  if (!tilted) error(column, code_name('G', code) + " without an active tilted plane");
  if (code != 2530 && w.has('P')) integer('P', (code_name('G', code) + " P").c_str(), 0, 2);
  Vec3 direction = glm::normalize(tilt_rotation[2]);
  if (machine.kinematics) {  // the machine must reach it; the rotaries it picks are remembered
    try {
      rotary_position = orient_tool(*machine.kinematics, direction, rotary_position);
    } catch (const Error& e) {
      error(column, code_name('G', code) + ": " + e.what());
    }
  }
  if (glm::dot(direction, axis) < 1 - kSameDirection) {
    axis = direction;
    go_far();  // the machine turns the tool: where the tip ends is the kinematics' business
  }
  update_frame();
  if (code != 533) return;
  if (!(w.has('I') && w.has('J') && w.has('K')))
    error(column, "G53.3 needs I, J and K: the point of the plane to go to");
  Vec3 target(length('I'), length('J'), length('K'));
  // I J K are a position here, not arc centre offsets: the motion stage must not see them.
  for (char c : {'I', 'J', 'K'}) w.present &= ~(1u << letter_index(c));
  move_to(target, {true, true, true}, rotation, origin, MoveKind::rapid, 0.0);
}

}  // namespace tridex::gcode
