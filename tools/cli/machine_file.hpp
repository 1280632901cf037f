// tridex command — `--machine FILE|NAME`: what the interpreter needs to know of the machine, from
// a bundled profile or a JSON machine file (README "Machine files" documents the keys).
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "machining_time.hpp"
#include "tridex/gcode/interpreter.hpp"

namespace tridex::cli {

// The bundled kinematics profiles are machines too: the default machine with those rotary axes.
inline constexpr const char* kBundledMachines =
    "default, haas, linuxcnc, ac-trunnion, bc-trunnion, b-head-c-table, head-head";

// An empty name is the default machine. `subprogram_dirs` (--subprograms) are searched before
// the machine file's own. Throws InputError naming the file, the key and the value.
// The machine from a parsed machine file; `file` names it in messages. Throws InputError.
// `rates`, where given, receives the machine's speeds (left as they are where the file has none).
gcode::MachineConfig machine_from_json(const nlohmann::json& doc, const std::string& file,
                                       MachineRates* rates = nullptr);

gcode::MachineConfig load_machine(const std::string& name_or_file,
                                  const std::vector<std::string>& subprogram_dirs = {},
                                  MachineRates* rates = nullptr);

}  // namespace tridex::cli
