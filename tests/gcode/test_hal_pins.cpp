// LinuxCNC's #<_hal[pin]> parameters (its plasma programs read cut settings so): the value lives in
// the running HAL, which tridex, like rs274 run standalone ("Named parameter ... not defined"),
// does not have. An error at the parameter naming the pin, as written (HAL names keep their case).
#include <doctest/doctest.h>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

TEST_CASE("#<_hal[pin]>: an error naming the pin, at the parameter") {
  MachineConfig machine = at_origin();
  machine.dialect = Dialect::linuxcnc;
  Diagnostic d = error_of("G21\nF#<_hal[plasmac.Cut-Feed-Rate]> ; feed\n", {}, machine);
  CHECK(d.line == 2);
  CHECK(d.column == 2);
  CHECK(d.message.find("HAL pin plasmac.Cut-Feed-Rate,") != std::string::npos);
  d = error_of("#<a> = [1 + #<_HAL[motion.spindle-speed-out]>]\n", {}, machine);
  CHECK(d.column == 13);
  CHECK(d.message.find("HAL pin motion.spindle-speed-out,") != std::string::npos);
  // Other names that begin alike are ordinary parameters.
  CHECK_NOTHROW(run_program("#<_hale> = 2\nG0 X#<_hale> Y0 Z0\n", {}, machine));
}
