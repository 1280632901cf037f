// tridex command — the summary in a shop's words (issue 31): the tools a program used and each
// spindle direction as the machine's rotary angles (A/B/C on a machine with kinematics) or the
// G68.2 angles that tilt the work plane to it. Dexels, Z-maps and unit vectors stay in the
// report's details.
#pragma once

#include <string>

#include "pipeline/pipeline.hpp"

namespace tridex::cli {

// "tools: T1 10 mm flat end (\"10 mm flat end\"), T2 8 mm ball end"
std::string tools_text(const SimulationResult& r);

// "directions: +Z (A0 C0), tilted (A-20 C90)" on a kinematics machine, else "directions: +Z,
// G68.2 I90 J20 K0"; the spindle's direction in the work frame (tip towards holder).
std::string directions_text(const SimulationResult& r);

// The G68.2 angles (degrees, Euler Z-X-Z, K = 0) whose tool axis is `axis`:
// R = Rz(I)·Rx(J)·Rz(K), axis = R·(0, 0, 1) = (sin I sin J, −cos I sin J, cos J).
Vec3 g68_2_angles(const Vec3& axis);

}  // namespace tridex::cli
