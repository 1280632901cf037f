// libFuzzer harness over the machine file (`--machine FILE`, README "Machine files"):
// parse_json_text and gcode::machine_from_json, kinematics included. Any input must give a machine
// or throw InputError or MachineError (exit status 2) whose message carries no text of the JSON
// library; any other exception escaping ends the run as a crash.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <string>

#include "errors.hpp"
#include "inputs/json_input.hpp"
#include "tridex/gcode/machine.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  // Library text is a defect only where the input did not bring it: messages quote the offending
  // key, and a key may spell anything.
  auto check_message = [&](const std::exception& e) {
    const bool library_text = std::string(e.what()).find("json.exception") != std::string::npos;
    if (library_text && text.find("json.exception") == std::string::npos) std::abort();
  };
  try {
    tridex::gcode::MachineConfig machine =
        tridex::gcode::machine_from_json(tridex::cli::parse_json_text(text, "fuzz"), "fuzz");
    if (!(machine.far_distance > 0) || !std::isfinite(machine.far_distance)) std::abort();
  } catch (const tridex::cli::InputError& e) {
    check_message(e);
  } catch (const tridex::gcode::MachineError& e) {
    check_message(e);
  }
  return 0;
}
