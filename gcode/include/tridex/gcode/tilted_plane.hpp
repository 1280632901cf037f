// tridex::gcode — the feature frame of each tilted-working-plane form, as pure functions of the
// block's words. The interpreter reads the words; these turn them into a tridex::Frame whose
// rotation's columns are the feature X, Y and Z axes in the work frame and whose origin is the
// feature origin in the work frame (a feature point p is at origin + rotation·p). Angles are in
// degrees, rotations right-handed (geometry.hpp's rotation_x/y/z).
//
// Sources, form by form (each function below names the definition it follows):
// - Fanuc Series 30i/31i-A Descriptions (B-63942EN/02) §5.44 "Tilted working plane command":
//   G68.2 X Y Z I J K, Euler angles Z-X-Z; G53.1 turns the tool to the feature Z.
// - Fanuc 30i/31i-A additional manual B-79976E "Specifying tilted working plane based on the tool
//   axis direction" (G68.3): Zc = the tool axis, Xc normal to Zc and the parameter-12321 vector,
//   Yc = Zc × Xc, then R rotates about Zc.
// - Mazak VORTEX i manual §4 "G68.2 P1 Qq X Y Z I J K": I, J, K the roll, pitch and yaw angles
//   about X, Y and Z, q the order of the rotations (digits: axis of the first, second, third).
// - Hurco, "5-Axis CNC Mill Programming: Transform Planes Using IJK UVW Vectors" (Hurco blog,
//   blog.hurco.com): G68.2 X Y Z I J K U V W, IJK the feature X direction, UVW its Y direction;
//   the example `G68.2 X3 Y-3 Z-6 I0 J0 K-1 U0 V1 W0` is a 90° turn about Y.
// - LinuxCNC's tilted-work-plane remap (configs/sim/axis/vismach/5axis/.../python/remap.py,
//   David Mueller, 2023-2025): calc_euler_rot_matrix, g682, g684, and remap_funcs_twp.py's
//   kins_calc_twp_origin_rot_matrix. Its reading differs from Fanuc's in the places named below.
// - Haas G268 as Autodesk's Haas posts emit it (`G268 X Y Z I J K Q123`): rotations about the
//   fixed X, then Y, then Z axes, the same as Fanuc P1 Q123 (interpreter.hpp's G268).
//
// Errors (degenerate points, parallel or zero vectors, an unknown rotation order) are
// tridex::Error whose message names the words; the interpreter adds file:line:column.
#pragma once

#include "tridex/geometry.hpp"

namespace tridex::gcode {

// Rotation by `degrees` about coordinate axis 1 (X), 2 (Y) or 3 (Z).
Mat3 axis_rotation(int axis, double degrees);

// ---- Fanuc, Mazak, Haas ---------------------------------------------------------------------

// G68.2 (P0 or no P) X Y Z I J K — Fanuc's Euler angles: R = Rz(I)·Rx(J)·Rz(K), intrinsic Z-X'-Z''.
// Mazak's `G68.2 X Y Z A B C` carries the same three angles in A, B, C (pass them as i, j, k);
// no Mazak manual was at hand to confirm it, so this follows the reading of Mazak output.
Frame fanuc_euler(const Vec3& origin, double i, double j, double k);

// G68.2 P1 Qq X Y Z I J K (Fanuc, Mazak) and Haas G268 X Y Z I J K Qq: I, J, K are the angles
// about X, Y and Z; q's three digits name the axis of the first, second and third rotation
// (1 = X, 2 = Y, 3 = Z), each rotation about the FIXED axes of the work coordinate system
// (roll-pitch-yaw). So R = R(q3)·R(q2)·R(q1), each R(n) turning by the angle that belongs to its
// axis. Every order of three distinct axes is accepted:
//   Q123 = Rz(K)·Ry(J)·Rx(I)   Q132 = Ry(J)·Rz(K)·Rx(I)   Q213 = Rz(K)·Rx(I)·Ry(J)
//   Q231 = Rx(I)·Rz(K)·Ry(J)   Q312 = Ry(J)·Rx(I)·Rz(K)   Q321 = Rx(I)·Ry(J)·Rz(K)
// Anything else (Q121, Q0, Q124) is an error naming Q.
Frame fixed_axis_angles(const Vec3& origin, double i, double j, double k, int q);

// G68.2 P2, three points (Fanuc; LinuxCNC's g682 P2 computes the same axes): the X axis points
// from p1 to p2, the feature XY plane holds p3 on its +Y side, so Z = (p2 − p1) × (p3 − p1)
// normalised and Y = Z × X. The origin is p1. Coincident or collinear points are an error.
Frame three_point_frame(const Vec3& p1, const Vec3& p2, const Vec3& p3);

// G68.2 P3, two vectors (Fanuc): the feature X direction and the feature Z direction. Fanuc
// raises an alarm when the angle between them is outside 85°–95° (LinuxCNC's remap quotes the
// same limits from Fanuc's manual); inside, Z is kept and X is made normal to it. Zero vectors
// or an angle outside 85°–95° are an error.
Frame two_vector_frame(const Vec3& origin, const Vec3& x_direction, const Vec3& z_direction);

// Hurco G68.2 X Y Z I J K U V W: IJK the feature X direction, UVW the feature Y direction (the
// Hurco blog above). Z = X × Y. The vectors need not be unit (the control normalises them) but
// must be normal to each other within 1e-3 (cosine); zero or non-normal vectors are an error.
Frame hurco_vector_frame(const Vec3& origin, const Vec3& x_direction, const Vec3& y_direction);

// G68.3 X Y Z R (Fanuc B-79976E): Zc is the current tool axis (unit, work frame); Xc is the unit
// normal of the plane of Zc and `reference` (parameter 12321's vector; +Y by default, which gives
// the untilted frame for a vertical tool), taken as Xc = reference × Zc; Yc = Zc × Xc; then the
// frame turns by R about Zc. A tool axis parallel to `reference` is an error.
Frame tool_axis_frame(const Vec3& origin, const Vec3& tool_axis, double r = 0.0,
                      const Vec3& reference = Vec3(0, 1, 0));

// The frame turned by `degrees` about its own Z axis (the R word of Fanuc's G68.2/G68.3).
Frame rotated_about_own_z(const Frame& frame, double degrees);

// G68.4 (Fanuc, LinuxCNC): the new frame is given in the current feature frame and composes
// with it: rotation = current·incremental, origin = current.origin + current.rotation·inc.origin
// (LinuxCNC's g684: twp_matrix_new = twp_matrix_current · twp_matrix).
Frame compose(const Frame& current, const Frame& incremental);

// ---- LinuxCNC's dialect ---------------------------------------------------------------------
// LinuxCNC's remap reads I, J, K as the FIRST, SECOND and THIRD angle of the order Q (not the
// angles about X, Y, Z as Fanuc P1 does), each rotation about the axes already turned
// (intrinsic): Q121 = Rx(I)·Ry(J)·Rx(K), Q313 = Rz(I)·Rx(J)·Rz(K) (Fanuc's P0), Q123 =
// Rx(I)·Ry(J)·Rz(K). P0 takes the six proper-Euler orders 121 131 212 232 313 323 (default 313),
// P1 the six Tait-Bryan orders 123 132 213 231 312 321 (default 123). The R word turns the frame
// by Rz(R) on the LEFT (remap_funcs_twp.py: twp_rotation = Rz(r)·euler), i.e. about the work Z.
Mat3 linuxcnc_euler_rotation(double first, double second, double third, int q, int p);

// LinuxCNC `G68.2 P0|P1 Q X Y Z I J K R` (and G68.4 with the same words, composed by `compose`).
Frame linuxcnc_angles_frame(int p, int q, const Vec3& origin, double i, double j, double k,
                            double r = 0.0);

// LinuxCNC `G68.2 P2`: Q0 gives the origin (and R), Q1, Q2, Q3 the three points; the axes are
// three_point_frame's, turned by Rz(R) on the left, and the origin is Q0's, not point 1.
Frame linuxcnc_three_point_frame(const Vec3& origin, double r, const Vec3& p1, const Vec3& p2,
                                 const Vec3& p3);

// LinuxCNC `G68.2 P3`: Q0 X Y Z I J K R, where I J K is a POINT on the feature X axis (the remap
// takes twp_vect_x = (I − X, J − Y, K − Z)), and Q1 I J K the feature Z direction; the two must
// be normal within 1e-3 (cosine). Turned by Rz(R) on the left.
Frame linuxcnc_two_vector_frame(const Vec3& origin, const Vec3& point_on_x, double r,
                                const Vec3& z_direction);

}  // namespace tridex::gcode
