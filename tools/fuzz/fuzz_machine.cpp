// libFuzzer harness over the machine file (`--machine FILE`, README "Machine files"):
// parse_json_text and machine_from_json, kinematics included. Any input must give a machine or
// throw InputError (exit status 2) whose message carries no text of the JSON library; any other
// exception escaping ends the run as a crash.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "errors.hpp"
#include "json_input.hpp"
#include "machine_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  try {
    tridex::gcode::MachineConfig machine =
        tridex::cli::machine_from_json(tridex::cli::parse_json_text(text, "fuzz"), "fuzz");
    if (!(machine.far_distance > 0) || !std::isfinite(machine.far_distance)) std::abort();
  } catch (const tridex::cli::InputError& e) {
    // Library text is a defect only where the input did not bring it: messages quote the
    // offending key, and a key may spell anything.
    const bool library_text = std::string(e.what()).find("json.exception") != std::string::npos;
    if (library_text && text.find("json.exception") == std::string::npos) std::abort();
  }
  return 0;
}
