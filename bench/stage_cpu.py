#!/usr/bin/env python3
"""CPU seconds per stage of `tridex simulate` from a `perf record -F HZ` profile.

Usage: perf record -F 100 -o run.data build/tools/tridex simulate ...
       python3 bench/stage_cpu.py run.data 100

Wall seconds per stage (`timings_s` in the report) move with whatever else runs on the machine;
the samples a stage's own functions collect do much less (bench/README.md, "Why runs vary").
Each symbol is filed under the first stage whose pattern it matches.
"""
import collections
import re
import subprocess
import sys

STAGES = [
    ("dexelize: lower_fine_cells",
     r"lower_fine_cells|lower_cells_under_move|lower_band|lower_cell|near_moves_by_band|wall_tiles"),
    ("dexelize: raise_uncut", r"raise_uncut"),
    ("dexelize: steep_cells", r"steep_cells"),
    ("dexelize: refine (other)", r"refine_steep|refine_walls|moves_by_band|FineCellMove"),
    ("box heights (from_box, raise_uncut)", r"box_top_row"),
    ("parse", r"gcode::|Parser|LineLexer|lex_line|fast_float|MoveList|Grouper|cut_move"),
    ("zmap (Step 1)", r"Miller|Lanes|from_box|mill_|MoveGeometry|rapid_cuts|TileRow"),
    ("intersect (Steps 2-3)", r"ZMapScanner|scan_|grid_from_hits|hits_by_chunk|intersect|Dexel|dexel"),
    ("mesh", r"surface::|Extractor|check_mesh|write_stl|signed_volume"),
    ("kernel: zeroing fresh pages", r"clear_page"),
]


def main():
    data, hz = sys.argv[1], float(sys.argv[2])
    report = subprocess.run(
        ["perf", "report", "-i", data, "--no-children", "--sort", "symbol", "-n", "--stdio"],
        capture_output=True, text=True, check=True).stdout
    samples = collections.Counter()
    total = 0
    for line in report.splitlines():
        m = re.match(r"\s*[\d.]+%\s+(\d+)\s+\[.\]\s+(.*)", line)
        if not m:
            continue
        n, symbol = int(m.group(1)), m.group(2)
        total += n
        stage = next((name for name, pattern in STAGES if re.search(pattern, symbol)), "other")
        samples[stage] += n
    for name in [s for s, _ in STAGES] + ["other"]:
        print(f"{name:30} {samples[name] / hz:7.2f} s CPU {100 * samples[name] / max(total, 1):5.1f} %")
    print(f"{'all samples':30} {total / hz:7.2f} s CPU")


if __name__ == "__main__":
    main()
