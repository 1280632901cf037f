#!/usr/bin/env python3
"""The Python module (tools/embed/python/tridex) as a CAM script uses it, against the command.

Feeds the bundled example in pieces, checks the removed volume after each against the volume of
the STL the session writes, would_cut into the stock and in the air, inside on both sides of a
cut, and the final STL against `tridex simulate` on the whole program (the same bytes).

usage: test_python.py TRIDEX_COMMAND SOURCE_DIR SCRATCH_DIR   (PYTHONPATH: the build folder)
"""

import os
import random
import struct
import subprocess
import sys

import tridex

COMMAND, SOURCE, SCRATCH = sys.argv[1:4]
EXAMPLES = os.path.join(SOURCE, "gcode", "examples")
PROGRAM = os.path.join(EXAMPLES, "mold_3plus2.nc")
TOOLS = os.path.join(EXAMPLES, "mold_3plus2.tools.json")
STOCK = (0, 0, 0, 100, 80, 50)
CELL = 2.0
failures = []


def check(condition, what):
    if not condition:
        failures.append(what)
        print("FAILED:", what, file=sys.stderr)


def stl_volume(path):
    """The signed volume of a binary STL, as the mesh's divergence sum."""
    with open(path, "rb") as f:
        data = f.read()
    (count,) = struct.unpack_from("<I", data, 80)
    six = 0.0
    for v in struct.iter_unpack("<12fH", data[84:84 + 50 * count]):
        ax, ay, az, bx, by, bz, cx, cy, cz = v[3:12]
        six += ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)
    return six / 6


os.makedirs(SCRATCH, exist_ok=True)
whole = os.path.join(SCRATCH, "python_whole.stl")
subprocess.run([COMMAND, "simulate", PROGRAM, "--tools", TOOLS, "--stock",
                "box:" + ",".join(str(v) for v in STOCK), "--dexel-cell", str(CELL), "-q",
                "-o", whole], check=True)

with open(PROGRAM) as f:
    lines = f.read().splitlines(keepends=True)
random.seed(38)
cuts = sorted({0, len(lines), 40, 400, *random.sample(range(1, len(lines)), 2)})
s = tridex.Session(stock=STOCK, tools=TOOLS, machine=None, cell=CELL)
stock_volume = 100 * 80 * 50
piece_stl = os.path.join(SCRATCH, "python_piece.stl")
last = 0.0
offset = None  # the uncut faces' offset from the lattice nodes: the same for every piece
for a, b in zip(cuts, cuts[1:]):
    s.feed("".join(lines[a:b]))
    removed = s.removed_volume()
    s.write_stl(piece_stl)
    # The removal is the uncut stock's surface volume less the solid's (docs/reports.md): the
    # mesh alone stands proud by the offset times its uncut faces, a few 1e-5 of the stock.
    mesh_removed = stock_volume - stl_volume(piece_stl)
    if offset is None:
        offset = removed - mesh_removed
    check(0 <= offset <= 1e-4 * stock_volume and
          abs(removed - mesh_removed - offset) <= 1e-6 * stock_volume,
          "lines %d-%d: removed %.3f, the mesh says %.3f" % (a, b, removed, mesh_removed))
    check(removed >= last - 1e-6, "the removed volume fell at line %d" % b)
    last = removed
    if a == 0:  # after the +z facing at Z48 (lines 9-40)
        check(s.inside((50, 40, 47)), "below the faced top is stock")
        check(not s.inside((50, 40, 49)), "above the faced top is air")
        check(s.would_cut("G1 X50 Y40 Z45") > 2.5, "a feed into the stock cuts")
        check(s.would_cut("G0 X50 Y40 Z60") == 0, "a rapid in the air cuts nothing")
        check(s.removed_volume() == removed, "would_cut cut nothing")

s.write_stl(piece_stl)
final_stl = open(piece_stl, "rb").read()

# The stock's extent along lines against inside() at points on them; the height at x, y.
random.seed(383)
checked = 0
for _ in range(8):
    p = [random.uniform(0, 100), random.uniform(0, 80), random.uniform(0, 50)]
    d = [random.uniform(-1, 1) for _ in range(3)]
    spans = s.extent(p, d)
    norm = sum(v * v for v in d) ** 0.5
    for k in range(-25, 26):
        t = 4.3 * k
        inside_spans = any(a < t < b for a, b in spans)
        if any(min(abs(t - a), abs(t - b)) < CELL for a, b in spans):
            continue  # within a dexel spacing of the surface
        q = [p[i] + t * d[i] / norm for i in range(3)]
        check(s.inside(q) == inside_spans, "extent and inside agree at %s" % q)
        checked += 1
check(checked > 100, "extent checked at %d points" % checked)
top = s.height(50, 40)
check(top is not None and s.inside((50, 40, top - CELL)) and not s.inside((50, 40, top + CELL)),
      "the height at 50, 40 is the stock's top (%s)" % top)

# Moves given directly: the session's first G-code piece as moves gives the same solid.
with tridex.Session(stock=(0, 0, 0, 40, 40, 20), tools=TOOLS, cell=1) as by_gcode, \
        tridex.Session(stock=(0, 0, 0, 40, 40, 20), tools=TOOLS, cell=1) as direct:
    removed = by_gcode.feed_measured("G21 G90 T1 M6 S9000 M3\nG0 X-10 Y10 Z25\nG1 Z18 F900\n"
                                     "G1 X50\nG1 Y30\nG1 X-10\nG0 Z25\n")
    check(abs(removed - by_gcode.removed_volume()) < 1e-9 and removed > 0, "feed_measured")
    for a, b in [((-10, 10, 25), (-10, 10, 18)), ((-10, 10, 18), (50, 10, 18)),
                 ((50, 10, 18), (50, 30, 18)), ((50, 30, 18), (-10, 30, 18))]:
        direct.add_move(a, b, tool=1, axis=(0, 0, 1))
    direct.add_move((-10, 30, 18), (-10, 30, 25), tool=1, axis=(0, 0, 1), rapid=True)
    a_stl, b_stl = (os.path.join(SCRATCH, n) for n in ("python_gcode.stl", "python_direct.stl"))
    by_gcode.write_stl(a_stl)
    direct.write_stl(b_stl)
    with open(a_stl, "rb") as f1, open(b_stl, "rb") as f2:
        check(f1.read() == f2.read(), "moves given directly cut as their G-code")

with open(whole, "rb") as f1:
    check(f1.read() == final_stl, "the pieces' STL is simulate's, byte for byte")

# Bad input raises BadInput (status 2) with the line, and changes nothing.
moves = s.moves()
try:
    s.would_cut("G1 X10 Q\n")
    check(False, "bad G-code raises")
except tridex.BadInput as e:
    check(e.status == 2 and "<fed>:" in str(e), "the error names the line: %s" % e)
# The program ended (M30): more text is not run, and a warning says so.
s.feed("G1 X50 Y40 Z10\n")
check(s.moves() == moves, "text after the end is not run")
check(any("after the end" in w for w in s.warnings()), "a warning says so")
try:
    tridex.Session(stock=(0, 0, 0, 1, 1, 1), tools=os.path.join(SCRATCH, "none.json"), cell=1)
    check(False, "a missing tool table raises")
except tridex.BadInput:
    pass

if failures:
    sys.exit("%d check(s) failed" % len(failures))
print("python: all passed (tridex %s, %d pieces)" % (tridex.version(), len(cuts) - 1))
