#!/usr/bin/env python3
"""Issue 34's scale workload: a simultaneous 5-axis finishing program of about 10^6 segments.

A zig-zag finishing pass over a wavy 100 x 100 mm surface (bench/raster_program.py's, centred on
the ac-trunnion's C axis), rows along X 0.2 mm apart, each of 2000 segments 0.05 mm long, under
G43.4 (TCP) on the bundled `ac-trunnion` (A tilts about X, C turns the table): the tool axis
leans from the surface normal by about 20 degrees toward +Y (a side tilt, so a ball end never
cuts with its centre) and turns smoothly along the path (A 10-40 degrees, C within +-60), a fraction
of a degree per segment. The tip is placed so that each cutter touches the surface at the
programmed contact point (ball, flat and bull nose apart: one program per cutter). The stock is
the part left 0.5 mm oversize (a semi-finished casting, stock.stl), so the pass removes the
allowance only. Writes ball.nc, flat.nc, bull.nc (the same contact path), tools_ball.json,
tools_flat.json, tools_bull.json (D6; the bull nose r1) and stock.stl into the folder given.

    python3 bench/five_axis_program.py /tmp/i34 --segments 1000000
    tridex simulate /tmp/i34/ball.nc --machine ac-trunnion --tools /tmp/i34/tools_ball.json \
        --stock /tmp/i34/stock.stl --dexel-cell 0.1 -o ball.stl --report ball.json
    # the report's "simultaneous" gives the moves, sub-steps and seconds of the sweep

--segments N keeps the rows (2000 segments each) and takes the first N / 2000 of them from
y = -50 upward, so 10^5 segments cut a 10 mm strip of the same surface at the same density.
"""
import argparse
import json
import math
import pathlib
import struct

HALF, STEP, ROW_SEGMENTS, ALLOWANCE, LEAN = 50.0, 0.2, 2000, 0.5, 0.4
CUTTERS = {"ball": (3.0, 3.0), "flat": (3.0, 0.0), "bull": (3.0, 1.0)}  # (R, corner r)


def height(x, y):
    return 20 + 3 * math.sin(x / 8) * math.cos(y / 11) + 0.01 * x


def gradient(x, y):
    return (3 / 8 * math.cos(x / 8) * math.cos(y / 11) + 0.01,
            -3 / 11 * math.sin(x / 8) * math.sin(y / 11))


def unit(v):
    n = math.sqrt(sum(c * c for c in v))
    return tuple(c / n for c in v)


def pose(x, y, radius, corner):
    """The tool tip and axis that touch the surface at (x, y) with the tool leaning toward +Y."""
    fx, fy = gradient(x, y)
    n = unit((-fx, -fy, 1.0))
    a = unit((-fx, -fy + LEAN, 1.0))  # |fy| < 0.28 < LEAN: a_y > 0, so C stays within +-90
    # A torus of tube `corner` on a circle of radius R - corner touches the plane of normal n at
    # the point below its centre: tip = P + corner·n − corner·a + (R − corner)·(n ⊥ a).
    d = sum(p * q for p, q in zip(n, a))
    side = unit(tuple(p - d * q for p, q in zip(n, a)))
    p = (x, y, height(x, y))
    tip = tuple(p[i] + corner * n[i] - corner * a[i] + (radius - corner) * side[i] for i in range(3))
    return tip, a


def words(tip, a):
    angle_a = math.degrees(math.acos(a[2]))
    angle_c = math.degrees(math.atan2(a[0], a[1]))
    return f"X{tip[0]:.4f} Y{tip[1]:.4f} Z{tip[2]:.4f} A{angle_a:.4f} C{angle_c:.4f}"


def program(rows, radius, corner):
    lines = ["%", "(tridex bench: issue 34 simultaneous finishing, bench/five_axis_program.py)",
             "G21 G90 G17 G40 G49 G80", "T1 M6 G43 H1", "S12000 M3"]
    first_tip, first_axis = pose(-HALF, -HALF, radius, corner)
    lead = words(first_tip, first_axis).split(" ")
    lines += ["G0 X0 Y0 Z80 A0 C0", "G43.4 H1", f"G0 {' '.join(lead[3:])}",
              f"G0 {' '.join(lead[:2])} Z{first_tip[2] + 5:.4f}", f"G1 {' '.join(lead)} F2000"]
    for row in range(rows):
        y = -HALF + row * STEP
        for k in range(1, ROW_SEGMENTS + 1) if row == 0 else range(ROW_SEGMENTS + 1):
            s = k / ROW_SEGMENTS
            x = -HALF + 2 * HALF * (s if row % 2 == 0 else 1 - s)
            lines.append(words(*pose(x, y, radius, corner)))
    lines += ["G91 G1 Z5", "G90 G49", "G0 Z80 A0 C0", "M5", "M30", "%"]
    return "\n".join(lines) + "\n"


def stock_stl(path, cell=0.5):
    """The part 0.5 mm oversize from z = 0: a closed heightfield, outward facing, binary STL."""
    n = int(round(2 * HALF / cell))
    xs = [-HALF + i * cell for i in range(n + 1)]
    top = [[height(x, y) + ALLOWANCE for x in xs] for y in xs]
    tris = []

    def quad(a, b, c, d):  # a b c d counter-clockwise from outside
        tris.append((a, b, c))
        tris.append((a, c, d))

    for j in range(n):
        for i in range(n):
            x0, x1, y0, y1 = xs[i], xs[i + 1], xs[j], xs[j + 1]
            quad((x0, y0, top[j][i]), (x1, y0, top[j][i + 1]), (x1, y1, top[j + 1][i + 1]),
                 (x0, y1, top[j + 1][i]))
            quad((x0, y0, 0), (x0, y1, 0), (x1, y1, 0), (x1, y0, 0))
    for i in range(n):
        x0, x1 = xs[i], xs[i + 1]
        quad((x0, -HALF, 0), (x1, -HALF, 0), (x1, -HALF, top[0][i + 1]), (x0, -HALF, top[0][i]))
        quad((x1, HALF, 0), (x0, HALF, 0), (x0, HALF, top[n][i]), (x1, HALF, top[n][i + 1]))
        quad((-HALF, x1, 0), (-HALF, x0, 0), (-HALF, x0, top[i][0]), (-HALF, x1, top[i + 1][0]))
        quad((HALF, x0, 0), (HALF, x1, 0), (HALF, x1, top[i + 1][n]), (HALF, x0, top[i][n]))
    with open(path, "wb") as f:
        f.write(b"tridex bench stock".ljust(80, b" ") + struct.pack("<I", len(tris)))
        for t in tris:
            f.write(struct.pack("<3f", 0, 0, 0))
            for v in t:
                f.write(struct.pack("<3f", *v))
            f.write(b"\0\0")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folder")
    parser.add_argument("--segments", type=int, default=1000000)
    parser.add_argument("--cutters", default="ball,flat,bull")
    args = parser.parse_args()
    out = pathlib.Path(args.folder)
    out.mkdir(parents=True, exist_ok=True)
    rows = max(1, args.segments // ROW_SEGMENTS)
    shapes = {"ball": {"shape": "ballnose"}, "flat": {"shape": "cylindrical"},
              "bull": {"shape": "bullnose", "corner-radius": 1}}
    for name in args.cutters.split(","):
        radius, corner = CUTTERS[name]
        (out / f"{name}.nc").write_text(program(rows, radius, corner))
        tool = {"units": "mm", "diameter": 2 * radius, "length": 40, **shapes[name]}
        (out / f"tools_{name}.json").write_text(json.dumps({"1": tool}) + "\n")
    stock_stl(out / "stock.stl")


if __name__ == "__main__":
    main()
