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

#include <memory>
#include <set>
#include <string>
#include <vector>

#include "checks/machine_check.hpp"
#include "json_text.hpp"
#include "outputs/html_report.hpp"
#include "pipeline/pipeline.hpp"

namespace tridex::cli {

struct MachineRun {
  bool active = false;              // fixtures or components were given
  std::vector<std::string> bodies;  // names, as MachineCheck::bodies() lists them
  std::vector<std::string> groups;
  std::vector<std::shared_ptr<const Mesh>> meshes;
  std::set<int> spindle_unplaced;  // tools without a gauge point: spindle parts not tested
  MachineFindings found;
};

// Reads the fixtures and the components (InputError, exit status 2, naming the file), then checks
// every move. Inactive (nothing done) when there are neither fixtures nor components.
MachineRun run_machine_check(const std::vector<std::string>& fixtures, const SimulationResult& r);

// The tools' bodies as check tests them against the in-process stock (collision_check.hpp, in the
// pipeline): each tool's shank and holder sections, then, when the tool has a gauge point, the
// spindle's parts (the machine's components on "spindle") there, each as its envelope of
// revolution about the spindle axis in stacked cylinders. Exact for a nose turned about the
// spindle; a part off to one side is tested as if it turned with the spindle (conservative: it may
// be reported near material it passes beside). Against fixtures and the table's parts the machine
// check tests the meshes themselves. Reads the spindle parts' meshes (InputError, exit status 2).
std::vector<ToolBody> bodies_against_stock(const SimulationResult& r);

// The report's "machine" object.
Json machine_json(const MachineRun& run, const SimulationResult& r);

// What the machine check could not do, in words (empty: all done): the spindle's parts with the
// tools that have no gauge point. check puts it on the verdict line, in the report's
// "not_checked" and "warnings", and next to the page's verdict: never a silent pass.
std::string machine_unchecked_text(const MachineRun& run);

// The bodies and the listed findings' poses as the HTML page draws them (html_report.hpp); it
// points into `run`.
HtmlMachine machine_page(const MachineRun& run);

// "file:line: collision: A and B ..." lines on stdout, the first `limit` of each kind.
void print_machine_findings(const MachineRun& run, const SimulationResult& r, std::size_t limit);

}  // namespace tridex::cli
