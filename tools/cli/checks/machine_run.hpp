// tridex check — the machine check's inputs and outputs (issue 33): the fixtures (--fixture, a
// project's "fixtures") and the machine file's components read, the tools' parts made as meshes,
// every move of the program walked in order through MachineCheck (machine_check.hpp), and the
// findings as the report, stdout and the HTML page give them.
//
// A tool's parts: its flutes (the cutter's profile turned about the axis, up to the shank's
// bottom; with no shank, to the gauge point, else max(the profile's height, 6 radii)), its shank
// and each holder section (frusta), all as polygons around the round bodies. The gauge point
// (where the spindle's parts hang from) lies the tool's length above the tip: the tool table's
// tool length, else the top of the holder. A tool with neither has no gauge point: the spindle's
// parts are not tested while it is in the spindle (placing them at the flutes' top would put a
// 90 mm spindle nose a few millimetres above a small ball end's tip: false crashes), and the
// report and stdout name such tools.
//
// Of a move that comes from "far along the tool axis" (from_far: the start is a stand-in, where
// the machine stood is unknown) only the pose it ends at is checked: a first rapid that lands
// in a clamp is found; the way there is not known. Under raw rotary programs a turn of the rotaries
// happens at the machine position where the last move ended, before the move that follows
// (rotary.cpp): it is checked as a rotary-only move at that move's line.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "checks/machine_check.hpp"
#include "json_text.hpp"
#include "pipeline/pipeline.hpp"

namespace tridex::cli {

struct MachineRun {
  bool active = false;  // fixtures or components were given
  std::vector<std::string> bodies;
  std::set<int> spindle_unplaced;  // tools without a gauge point: spindle parts not tested
  MachineFindings found;
};

// Reads the fixtures and the components (InputError, exit status 2, naming the file), then checks
// every move. Inactive (nothing done) when there are neither fixtures nor components.
MachineRun run_machine_check(const std::vector<std::string>& fixtures, const SimulationResult& r);

// The report's "machine" object.
Json machine_json(const MachineRun& run, const SimulationResult& r);

// "file:line: collision: A and B ..." lines on stdout, the first `limit` of each kind.
void print_machine_findings(const MachineRun& run, const SimulationResult& r, std::size_t limit);

}  // namespace tridex::cli
