#!/usr/bin/env python3
"""Issue 13's raster program, to time Step 1 of `tridex simulate` for each cutter shape.

A zig-zag finishing raster over bench_mill's wavy surface (mill_bench.cpp), 100 x 100 mm, 0.25 mm
segments at 0.25 mm stepover: 160,801 moves. Writes raster.nc and one tool table per cutter
(tools_ball.json, tools_flat.json, tools_bull.json: D6, the bull nose r1) into the folder given.

    python3 bench/raster_program.py /tmp/i13
    tridex simulate /tmp/i13/raster.nc --tools /tmp/i13/tools_bull.json \
        --stock box:0,0,0,100,100,25 --zmap-cell 0.02 -o bull.stl --report bull.json
    # Step 1 is the report's timings_s.zmap
"""
import json
import math
import pathlib
import sys

SIDE, STEP = 100.0, 0.25


def wavy(x, y):
    return 20 + 3 * math.sin(x / 8) * math.cos(y / 11) + 0.01 * x


def main(folder):
    out = pathlib.Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    steps = int(SIDE / STEP)
    lines = ["%", "G21 G90 G17 G94", "T1 M6", "S10000 M3", "G43 H1", "G0 X0 Y0 Z30", f"G1 Z{wavy(0, 0):.4f} F1000"]
    for row in range(steps + 1):
        y = row * STEP
        xs = [(s if row % 2 == 0 else steps - s) * STEP for s in range(steps + 1)]
        lines.append(f"G1 X{xs[0]:.4f} Y{y:.4f} Z{wavy(xs[0], y):.4f}")
        lines += [f"X{x:.4f} Z{wavy(x, y):.4f}" for x in xs[1:]]
    lines += ["G0 Z30", "M5", "M30", "%"]
    (out / "raster.nc").write_text("\n".join(lines) + "\n")
    shapes = {"ball": {"shape": "ballnose"}, "flat": {"shape": "cylindrical"},
              "bull": {"shape": "bullnose", "corner-radius": 1}}
    for name, shape in shapes.items():
        tool = {"units": "mm", "diameter": 6, "length": 40, **shape}
        (out / f"tools_{name}.json").write_text(json.dumps({"1": tool}) + "\n")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
