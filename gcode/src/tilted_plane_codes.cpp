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

// The Q numbers (bit q) a several-block form takes, and those it needs before its plane is known.
unsigned several_block_allowed(int p, bool linuxcnc) {
  return p == 2 ? 0b1111u : linuxcnc ? 0b0011u : 0b0110u;
}
unsigned several_block_needed(int p, bool linuxcnc) {
  return p == 2 && !linuxcnc ? 0b1110u : several_block_allowed(p, linuxcnc);
}

std::string q_list(unsigned bits) {
  std::string list;
  for (int n = 0; n < 4; ++n)
    if ((bits >> n) & 1u) list += (list.empty() ? "Q" : ", Q") + std::to_string(n);
  return list;
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
//   G68.2 P2 Qq …, G68.2 P3 Qq …  over several blocks: several_block_plane
// nullopt while a several-block form waits for its next block.
std::optional<Frame> Interpreter::State::plane_words(int code) {
  int column = w.find_g(code);
  long long p = 0;
  if (w.has('P')) {
    if (code == kG268) error(w.col('P'), "G268 has no P word");
    p = integer('P', "G68.2 P", 0, 3);
  }
  if (p == 2 || p == 3) return several_block_plane(code, static_cast<int>(p));
  Vec3 o(0.0);
  for (int i = 0; i < 3; ++i)
    if (w.has(kAxisLetter[i])) o[i] = length(kAxisLetter[i]);
  bool abc = w.has('A') || w.has('B') || w.has('C');
  bool uvw = w.has('U') || w.has('V') || w.has('W');
  bool ijk = w.has('I') || w.has('J') || w.has('K');
  int q = code == kG268 || p == 1 ? 123 : 0;
  int q_column = column;
  if (w.has('Q')) {
    q_column = w.col('Q');
    q = static_cast<int>(integer('Q', (code_name('G', code) + " Q").c_str(), 0, 999));
  }
  if (abc && (ijk || uvw))
    error(w.col(w.has('A')   ? 'A'
                : w.has('B') ? 'B'
                             : 'C'),
          code_name('G', code) + " with both A B C and I J K/U V W angles");
  if (abc && (p != 0 || w.has('Q')))
    error(column, code_name('G', code) + " A B C (Mazak's Euler angles) take no P1 or Q");
  if (uvw && (p != 0 || w.has('Q')))
    error(column, code_name('G', code) + " I J K U V W (Hurco's vectors) take no P1 or Q");
  if (uvw && code == kG268) error(column, "G268 has no U V W words");
  if (abc && code == kG268) error(column, "G268 takes its angles in I J K, not A B C");
  try {
    if (uvw) {
      Vec3 x = word_vector(w, 'I', 'J', 'K'), y = word_vector(w, 'U', 'V', 'W');
      return hurco_vector_frame(o, x, y);
    }
    Vec3 angles = abc ? word_vector(w, 'A', 'B', 'C') : word_vector(w, 'I', 'J', 'K');
    bool linuxcnc = machine.dialect == Dialect::linuxcnc && code != kG268;
    if (p == 1 && linuxcnc)  // LinuxCNC's P1: I J K the first to third angle of the order Q
      return linuxcnc_angles_frame(1, q, o, angles.x, angles.y, angles.z,
                                   w.has('R') ? w.take('R') : 0.0);
    if (code == kG268 || p == 1) return fixed_axis_angles(o, angles.x, angles.y, angles.z, q);
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

// G68.2 / G68.4 P2 and P3: the plane written over consecutive blocks, one Q each, X Y Z the
// work coordinates of a point (an omitted word is 0) and I J K a direction. Fanuc's forms, as
// posts for Fanuc 30i-series controls write them (no Fanuc manual was at hand: the Q0 block's
// reading follows a post's quote of it, "amount of shift from the first point to the origin of a
// feature coordinate system", which it applies in the feature frame):
//   P2 [Q0 X Y Z R]               optional: X Y Z the shift from the first point to the feature
//                                 origin, in the feature frame; R turns the frame about its Z
//      Q1 X Y Z, Q2 X Y Z, Q3 X Y Z  the three points of three_point_frame
//   P3 Q1 X Y Z I J K             the origin and the feature X direction
//      Q2 I J K                   the feature Z direction (two_vector_frame)
// LinuxCNC's remap (g682; machine dialect linuxcnc) numbers them differently and needs every one:
//   P2 Q0 X Y Z R (the origin itself), Q1 Q2 Q3 the points (linuxcnc_three_point_frame)
//   P3 Q0 X Y Z I J K R (I J K a point on X), Q1 I J K the Z direction (linuxcnc_two_vector_frame)
// The blocks may come in any order; the plane takes effect with the block that completes it, and
// any other block before that is an error (execute, with incomplete_plane's message).
std::optional<Frame> Interpreter::State::several_block_plane(int code, int p) {
  const std::string form = code_name('G', code) + " P" + std::to_string(p);
  bool linuxcnc = machine.dialect == Dialect::linuxcnc;
  unsigned allowed = several_block_allowed(p, linuxcnc);
  unsigned needed = several_block_needed(p, linuxcnc);
  if (!w.has('Q') && !linuxcnc)
    error(w.find_g(code), form + " needs Q (which of its blocks this is)");
  int q_column = w.has('Q') ? w.col('Q') : w.find_g(code);
  int q = w.has('Q') ? static_cast<int>(integer('Q', (form + " Q").c_str(), 0, 3)) : 0;
  if (!((allowed >> q) & 1u))
    error(q_column,
          form + " Q" + std::to_string(q) + ": this form's blocks are " + q_list(allowed));
  PlaneBlocks& b = tilt.plane_blocks;
  if (b.code == 0) b = PlaneBlocks{code, p, context.line, 0, {}, {}, 0.0};
  if (b.code != code || b.p != p)
    error(w.find_g(code), form + " while " + code_name('G', b.code) + " P" + std::to_string(b.p) +
                              " begun at line " + std::to_string(b.first_line) + " is incomplete");
  if ((b.given >> q) & 1u)
    error(q_column, form + " Q" + std::to_string(q) + " given twice (the plane begun at line " +
                        std::to_string(b.first_line) + ")");
  b.given |= 1u << q;
  // The direction-only block (Fanuc P3 Q2, LinuxCNC P3 Q1) has no point; R only on Q0.
  bool direction_only = p == 3 && q == (linuxcnc ? 1 : 2);
  for (int i = 0; i < 3; ++i) {
    char c = kAxisLetter[i];
    if (!w.has(c)) continue;
    if (direction_only)
      error(w.col(c),
            form + " Q" + std::to_string(q) + " takes only I J K (a direction), not " + c);
    b.xyz[static_cast<std::size_t>(q)][i] = length(c);
  }
  if (p == 3) b.ijk[static_cast<std::size_t>(q)] = word_vector(w, 'I', 'J', 'K');
  if (q == 0 && w.has('R')) b.r = w.take('R');
  if ((b.given & needed) != needed) return std::nullopt;

  PlaneBlocks done = b;
  tilt.plane_blocks = PlaneBlocks{};
  auto& xyz = done.xyz;
  auto& ijk = done.ijk;
  try {
    if (linuxcnc)
      return p == 2 ? linuxcnc_three_point_frame(xyz[0], done.r, xyz[1], xyz[2], xyz[3])
                    : linuxcnc_two_vector_frame(xyz[0], ijk[0], done.r, ijk[1]);
    if (p == 3) return two_vector_frame(xyz[1], ijk[1], ijk[2]);
    Frame points = three_point_frame(xyz[1], xyz[2], xyz[3]);
    points.origin = points.to_world(xyz[0]);
    return rotated_about_own_z(points, done.r);
  } catch (const Error& e) {
    error(q_column, form + ": " + e.what());
  }
}

// A several-block plane under way: what is missing, for the error of the block that is not its
// next one (execute) or of the program's end (Interpreter::run).
std::string Interpreter::State::incomplete_plane() const {
  const PlaneBlocks& b = tilt.plane_blocks;
  unsigned needed = several_block_needed(b.p, machine.dialect == Dialect::linuxcnc);
  return code_name('G', b.code) + " P" + std::to_string(b.p) + " begun at line " +
         std::to_string(b.first_line) + " is incomplete (" + q_list(needed & ~b.given) +
         " missing): its blocks must follow one another";
}

void Interpreter::State::tilted_plane(int code) {
  if (code == kG69 || code == kG269) {
    frame.tilted = false;
    update_frame();
    return;
  }
  int column = w.find_g(code);
  if (modal.incremental)
    error(column, code_name('G', code) + " under G91 is not supported; use G90");
  Frame feature;
  if (code == kG68) {
    // Fanuc's coordinate rotation G68 X Y R (G17; Fanuc 0i-MF operator's manual, "Coordinate
    // system rotation"): the program's points turn by R degrees, counter-clockwise, about the
    // centre X Y (where either is left out, the current point's): p = C + Rz(R)·(p' − C).
    if (frame.tilted) error(column, "G68 while a rotation or tilted plane is active (G69 first)");
    if (modal.plane != kG17)
      error(column, "G68 (coordinate rotation) is read in the XY plane (G17) only");
    if (w.has('Z'))
      error(w.col('Z'), "G68 Z: the rotation in G17 is about an axis along Z through X Y");
    if (!w.has('R')) error(column, "G68 needs R (the angle of rotation, degrees)");
    if ((!w.has('X') || !w.has('Y')) && tool.far)
      error(column,
            "G68 without X and Y turns about the current point, but the tool is retracted "
            "far along its axis: give X and Y");
    Vec3 centre = tool.far ? Vec3(0.0) : to_program(tool.pos);
    if (w.has('X')) centre.x = length('X');
    if (w.has('Y')) centre.y = length('Y');
    centre.z = 0;
    const Mat3 turn = rotation_z(w.take('R'));
    feature = Frame{turn, centre - turn * centre + frame.work_offset + frame.local_offset};
  } else if (code == kG68_3) {
    // G68.3 X Y Z R (Fanuc B-79976E): Z along the tool; the origin is X Y Z, all three or none
    // (none: the tool tip where it stands).
    int given = int(w.has('X')) + int(w.has('Y')) + int(w.has('Z'));
    if (given != 0 && given != 3)
      error(column, "G68.3 needs all of X, Y and Z for the origin, or none of them");
    Vec3 o(0.0);
    if (given == 3) {
      for (int i = 0; i < 3; ++i) o[i] = length(kAxisLetter[i]);
      o += frame.work_offset + frame.local_offset;
    } else {
      if (tool.far)
        error(column,
              "G68.3 without X Y Z takes the tool tip as the origin, but the tool is "
              "retracted far along its axis: give X, Y and Z");
      o = tool.pos;
    }
    try {
      feature = tool_axis_frame(o, tool.axis, w.has('R') ? w.take('R') : 0.0);
    } catch (const Error& e) {
      error(column, std::string("G68.3: ") + e.what());
    }
  } else if (code == kG68_4) {
    // G68.4: the same forms as G68.2, given in the active feature frame and composed with it.
    if (!frame.tilted)
      error(column, "G68.4 (incremental tilted plane) without an active tilted plane");
    std::optional<Frame> incremental_frame = plane_words(kG68_4);
    if (!incremental_frame) return;
    feature = compose(Frame{tilt.rotation, tilt.origin}, *incremental_frame);
  } else {
    std::optional<Frame> written = plane_words(code);
    if (!written) return;
    feature = *written;
    feature.origin +=
        frame.work_offset + frame.local_offset;  // on the active work coordinate system
  }
  tilt.rotation = feature.rotation;
  tilt.origin = feature.origin;
  frame.tilted = true;
  tilt.line = context.line;
  update_frame();
}

// G53.1 / G53.6 / G253 turn the tool to the feature Z; LinuxCNC's G53.1, G53.3 and G53.6 take P
// (0 shortest, 1 positive, 2 negative turn of the rotaries: which pose, not which direction),
// and G53.3 I J K then rapids to that point of the plane (remap.py's g53n_core). That remap turns
// the rotaries, or makes G53.3's move, with a G0 block of its own, which leaves G0 the motion
// mode: LinuxCNC's TWP demos (incremental_repetition_g533.ngc) move with bare X Y Z after G53.6.
void Interpreter::State::orient_to_plane(int code) {
  int column = w.find_g(code);
  if (!frame.tilted) error(column, code_name('G', code) + " without an active tilted plane");
  if (code != kG253 && w.has('P')) integer('P', (code_name('G', code) + " P").c_str(), 0, 2);
  Vec3 direction = glm::normalize(tilt.rotation[2]);
  if (machine.kinematics) {  // the machine must reach it; the rotaries it picks are remembered
    try {
      frame.rotary_position = orient_tool(*machine.kinematics, direction, frame.rotary_position);
    } catch (const Error& e) {
      error(column, code_name('G', code) + ": " + e.what());
    }
  }
  if (glm::dot(direction, tool.axis) < 1 - kSameDirection) {
    tool.axis = direction;
    go_far();  // the machine turns the tool: where the tip ends is the kinematics' business
  }
  update_frame();
  if (machine.dialect == Dialect::linuxcnc) modal.motion = kG0;
  if (code != kG53_3) return;
  // LinuxCNC's remap (g533remap.ngc) requires X, Y and Z, and hands them on to M530 as I J K.
  for (char c : {'I', 'J', 'K'})
    if (w.has(c))
      error(w.col(c), "G53.3 takes the point of the plane to go to as X Y Z, not I J K");
  if (!(w.has('X') && w.has('Y') && w.has('Z')))
    error(column, "G53.3 needs X, Y and Z: the point of the plane to go to");
  Vec3 target(length('X'), length('Y'), length('Z'));
  // The point is G53.3's own rapid, made here: the motion stage must not move to it again.
  for (char c : {'X', 'Y', 'Z'}) w.present &= ~(1u << letter_index(c));
  move_to(target, {true, true, true}, frame.rotation, frame.origin, MoveKind::rapid, 0.0);
}

}  // namespace tridex::gcode
