#!/usr/bin/env python3
"""Writes tridex's bundled 3+2 example: gcode/examples/mold_3plus2.{nc,tools.json,camotics}.

An original program in the style of the paper's test models (Inui, Chen and Umezu, CAD&A 19(4)
2022): a 100 x 80 x 50 mm block machined from five spindle directions, +Z, +X tilted 20 degrees
above horizontal, +Y, -X and -Y, with four cutters in each (T1 a 10 mm flat end, T2-T4 ball ends
of 8, 4 and 2 mm). The top becomes a mold-like surface (facing, Z-level roughing, ball-end
semi-finishing and finishing rasters, an engraved rose); each side gets a rounded pocket, a
ball-end slot, a circular groove (G2 arcs) and an engraved wave; the tilted direction first
faces a 20-degree bevel and puts its features on it.

It is written as a CAM post writes 3+2 work: per operation `G68.2 X Y Z I J K` (Euler Z-X-Z) +
`G53.1`, positioning `G0 X Y`, `G43 Z H`, cutting, then `G28 G91 Z0.` and `G69`.

Its rotary-indexed twin, mold_3plus2_bc.nc with the machine file mold_3plus2_bc.machine.json
(the bundled `bc-trunnion` kinematics, a Haas UMC-style B/C table), is the same part written as
Autodesk's Haas posts write 3+2 work: `G0 B.. C..` to index the table, `G254` (dynamic work
offset) and the moves in the part's work coordinates, `G255` to cancel. DWO arcs must lie in a
G17/G18/G19 plane of the part, which the tilted face's are not, so the twin writes every arc as
lines within 0.0005 mm (half of tridex's default arc tolerance). Run this script again to
regenerate the files (the output is deterministic).
"""
import json
import math
import os

STOCK = (0.0, 0.0, 0.0, 100.0, 80.0, 50.0)
TOOLS = {
    1: {"shape": "cylindrical", "diameter": 10.0, "length": 40.0, "description": "10 mm flat end"},
    2: {"shape": "ballnose", "diameter": 8.0, "length": 40.0, "description": "8 mm ball end"},
    3: {"shape": "ballnose", "diameter": 4.0, "length": 30.0, "description": "4 mm ball end"},
    4: {"shape": "ballnose", "diameter": 2.0, "length": 20.0, "description": "2 mm ball end"},
}
FEED = {1: 1200, 2: 1500, 3: 1800, 4: 900}
SPEED = {1: 9000, 2: 12000, 3: 16000, 4: 20000}


def surface(x, y):
    """The mold-like top: a dome with a gentle ripple (world mm)."""
    dome = 8.0 * math.exp(-((x - 50.0) ** 2 / 450.0 + (y - 40.0) ** 2 / 300.0))
    return 36.0 + dome + 1.5 * math.sin(x / 8.0) * math.cos(y / 10.0)


def fmt(v):
    s = f"{v:.4f}".rstrip("0")
    return s + "0" if s.endswith(".") else s


class Post:
    def __init__(self):
        self.lines = []
        self.tool = None

    def emit(self, text):
        self.lines.append(text)

    def move(self, code, **axes):
        words = " ".join(f"{k}{fmt(v)}" for k, v in axes.items())
        self.emit(f"{code} {words}")

    def operation(self, comment, tool, plane, clearance):
        """Starts an operation: retract, cancel the plane, change tool, tilt, orient."""
        self.emit(f"({comment})")
        self.emit("G28 G91 Z0.")
        self.emit("G90")
        self.emit("G69")
        if self.tool != tool:
            self.emit(f"T{tool} M6")
            self.tool = tool
        self.emit(f"S{SPEED[tool]} M3")
        self.emit("G54")
        if plane is not None:
            (x, y, z), (i, j, k) = plane
            self.emit(f"G68.2 X{fmt(x)} Y{fmt(y)} Z{fmt(z)} I{fmt(i)} J{fmt(j)} K{fmt(k)}")
            self.emit("G53.1")
        self.clearance = clearance
        self.first = True

    def rapid_to(self, u, v):
        """Goes to (u, v) at the clearance height; the first time as a CAM post does it."""
        if self.first:
            self.move("G0", X=u, Y=v)
            self.emit(f"G43 Z{fmt(self.clearance)} H{self.tool}")
            self.first = False
        else:
            self.move("G0", Z=self.clearance)
            self.move("G0", X=u, Y=v)

    def plunge(self, z, feed, approach):
        """Rapids down to `approach` (clear of material) and feeds down to z."""
        self.move("G0", Z=approach)
        self.emit(f"G1 Z{fmt(z)} F{FEED[self.tool] if feed is None else feed}")

    def end_operation(self):
        self.move("G0", Z=self.clearance)
        self.emit("M5")


class RotaryPost(Post):
    """The Haas DWO twin: reads each line the G68.2 post writes and writes it for a B/C table.

    The feature-frame position (u, v, w) is tracked; w is unknown (None) after a retract or an
    index, as the tool is then far along its axis, and the first move that completes the position
    writes it.
    """

    ARC_TOLERANCE = 0.0005  # mm, chord error of the lines that replace an arc

    def __init__(self):
        super().__init__()
        self.origin = (0.0, 0.0, 0.0)
        self.rot = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))  # columns: feature axes
        self.u = self.v = self.w = None
        self.motion = None

    def to_work(self, u, v, w):
        return tuple(self.origin[r] + sum(self.rot[c][r] * (u, v, w)[c] for c in range(3))
                     for r in range(3))

    def write(self, code, feed=None):
        x, y, z = self.to_work(self.u, self.v, self.w)
        line = f"{code} X{fmt(x)} Y{fmt(y)} Z{fmt(z)}"
        self.lines.append(line + (f" F{feed}" if feed is not None else ""))

    def set_plane(self, x, y, z, a, b, c):
        def rz(t):
            t = math.radians(t)
            return ((math.cos(t), -math.sin(t), 0.0), (math.sin(t), math.cos(t), 0.0), (0.0, 0.0, 1.0))

        def rx(t):
            t = math.radians(t)
            return ((1.0, 0.0, 0.0), (0.0, math.cos(t), -math.sin(t)), (0.0, math.sin(t), math.cos(t)))

        def mul(p, q):
            return tuple(tuple(sum(p[r][k] * q[k][col] for k in range(3)) for col in range(3))
                         for r in range(3))

        m = mul(mul(rz(a), rx(b)), rz(c))  # Fanuc's Euler Z-X-Z, rows
        self.rot = tuple(tuple(m[r][col] for r in range(3)) for col in range(3))
        self.origin = (x, y, z)
        # bc-trunnion: the tool on the part is Rz(-C)·Ry(-B)·z = (-sin B cos C, sin B sin C, cos B).
        d = self.rot[2]
        b_angle = math.degrees(math.acos(max(-1.0, min(1.0, d[2]))))
        c_angle = math.degrees(math.atan2(d[1], -d[0])) if abs(d[2]) < 1 - 1e-12 else 0.0
        self.lines.append(f"G0 B{fmt(b_angle)} C{fmt(c_angle)}")
        self.lines.append("G254")
        self.w = None

    def arc(self, ccw, u1, v1, i, j, feed):
        cu, cv = self.u + i, self.v + j
        r = math.hypot(i, j)
        a0 = math.atan2(self.v - cv, self.u - cu)
        a1 = math.atan2(v1 - cv, u1 - cu)
        sweep = a1 - a0
        if ccw and sweep <= 1e-12:
            sweep += 2 * math.pi
        if not ccw and sweep >= -1e-12:
            sweep -= 2 * math.pi
        step = 2 * math.acos(1 - self.ARC_TOLERANCE / r)
        n = max(1, math.ceil(abs(sweep) / step))
        for k in range(1, n + 1):
            t = a0 + sweep * k / n
            self.u, self.v = (u1, v1) if k == n else (cu + r * math.cos(t), cv + r * math.sin(t))
            self.write("G1", feed if k == 1 else None)

    def emit(self, text):
        words = text.split()
        if text.startswith("(") or not words:
            self.lines.append(text)
            return
        value = {}
        codes = []
        for word in words:
            if word[0] == "G":
                codes.append(word)
            else:
                value[word[0]] = word[1:]
        if codes[:1] == ["G68.2"]:
            self.set_plane(*(float(value[k]) for k in "XYZIJK"))
            return
        if codes == ["G53.1"]:
            return
        if codes == ["G69"]:
            self.lines.append("G255")
            self.origin = (0.0, 0.0, 0.0)
            self.rot = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
            return
        if codes[:2] == ["G28", "G91"]:
            self.lines.append(text)
            self.w = None
            return
        motion = [c for c in codes if c in ("G0", "G1", "G2", "G3")]
        if motion:
            self.motion = motion[0]
        feed = value.get("F")
        if self.motion in ("G2", "G3") and motion:
            self.arc(self.motion == "G3", float(value["X"]), float(value["Y"]), float(value["I"]),
                     float(value["J"]), feed)
            return
        if not any(k in value for k in "XYZ"):
            self.lines.append(text)
            return
        if "G43" in codes:  # G43 Z H: the length offset on its own line, then the position
            self.lines.append(f"G43 H{value['H']}")
        self.u = float(value.get("X", self.u if self.u is not None else 0.0))
        self.v = float(value.get("Y", self.v if self.v is not None else 0.0))
        if "Z" in value:
            self.w = float(value["Z"])
        if self.w is None:
            return  # still far along the tool: the move that gives Z writes the position
        self.write(self.motion, feed)


def top(post):
    """+Z: facing, Z-level roughing, semi-finishing and finishing rasters, an engraved rose."""
    clear = 55.0
    post.operation("+Z FACE TOP AT Z48 AND ROUGH THE DOME, 10 MM FLAT END", 1, None, clear)
    y, forward = -3.0, True
    post.rapid_to(-8.0, y)
    post.plunge(48.0, 400, 51.0)
    while True:
        post.move("G1", X=108.0 if forward else -8.0, F=FEED[1])
        forward = not forward
        if y >= 83.0:
            break
        y = min(83.0, y + 7.0)
        post.move("G1", Y=y)
    # Z-level roughing: keep 1 mm above the highest point of the surface under the flat disc.
    def disc_max(x, y):
        pts = [(0, 0)] + [(r * math.cos(a), r * math.sin(a)) for r in (2.5, 5.0)
                          for a in (k * math.pi / 6 for k in range(12))]
        return max(surface(x + dx, y + dy) for dx, dy in pts)
    above = 49.0
    for level in (45.0, 42.0, 39.0):
        y = -2.0
        while y <= 82.0:
            xs = [x * 1.0 for x in range(-2, 103)]
            ok = [disc_max(x, y) + 1.0 < level for x in xs]
            k = 0
            while k < len(xs):
                if not ok[k]:
                    k += 1
                    continue
                start = k
                while k < len(xs) and ok[k]:
                    k += 1
                post.rapid_to(xs[start], y)
                post.plunge(level, 400, above)
                post.move("G1", X=xs[k - 1], F=FEED[1])
            y += 6.0
        above = level + 1.0
    post.end_operation()

    post.operation("+Z SEMI-FINISH RASTER ALONG X, 8 MM BALL END", 2, None, clear)
    y, forward = -4.0, True
    while y <= 84.0:
        xs = [x * 1.0 for x in range(-10, 111)]
        if not forward:
            xs.reverse()
        post.rapid_to(xs[0], y)
        post.plunge(surface(xs[0], y) + 0.4, 500, surface(xs[0], y) + 2.0)
        for x in xs[1:]:
            post.move("G1", X=x, Z=surface(x, y) + 0.4)
        forward = not forward
        y += 2.0
    post.end_operation()

    post.operation("+Z FINISH RASTER ALONG Y, 4 MM BALL END", 3, None, clear)
    x, forward = -2.0, True
    while x <= 102.0:
        ys = [-6.0 + 0.8 * k for k in range(116)]
        if not forward:
            ys.reverse()
        post.rapid_to(x, ys[0])
        post.plunge(surface(x, ys[0]), 500, surface(x, ys[0]) + 2.0)
        for y in ys[1:]:
            post.move("G1", Y=y, Z=surface(x, y))
        forward = not forward
        x = round(x + 0.8, 4)
    post.end_operation()

    post.operation("+Z ENGRAVE A ROSE ON THE DOME, 2 MM BALL END", 4, None, clear)
    pts = []
    for k in range(361):
        a = math.radians(k)
        r = 14.0 + 4.0 * math.sin(5 * a)
        pts.append((50.0 + r * math.cos(a), 40.0 + r * math.sin(a)))
    post.rapid_to(*pts[0])
    post.plunge(surface(*pts[0]) - 0.6, 300, surface(*pts[0]) + 1.0)
    for px, py in pts[1:]:
        post.move("G1", X=px, Y=py, Z=surface(px, py) - 0.6)
    post.end_operation()


def side(post, name, plane, region, clearance, bevel=None):
    """Four operations on one side, in feature coordinates (u, v) of the tilted plane; the
    material lies at feature z < 0."""
    u0, u1, v0, v1 = region
    w, h = u1 - u0, v1 - v0
    if bevel is not None:
        # The tilted direction first faces its plane (z = 0): a 20-degree bevel on the +X edge.
        post.operation(f"{name} FACE THE BEVEL, 10 MM FLAT END", 1, plane, clearance)
        bu0, bu1, bv0, bv1 = bevel
        v, forward = bv0, True
        post.rapid_to(bu0, v)
        post.plunge(0.0, 400, 2.0)
        while True:
            post.move("G1", X=bu1 if forward else bu0, F=FEED[1])
            forward = not forward
            if v >= bv1:
                break
            v = min(bv1, v + 7.0)
            post.move("G1", Y=v)
        post.end_operation()
    # A rounded rectangular pocket, 3 mm deep: zigzag clearing, then the contour with G3 arcs
    # (corner radius 6 mm, so the 5 mm tool's centre turns on 1 mm arcs).
    post.operation(f"{name} POCKET, 10 MM FLAT END", 1, plane, clearance)
    pu0, pu1, pv0, pv1 = u0, u0 + 0.35 * w, v0, v1
    r, depth, c = 5.0, -3.0, 1.0
    a0, a1, b0, b1 = pu0 + r, pu1 - r, pv0 + r, pv1 - r
    post.rapid_to(a0 + c, b0 + c)
    post.plunge(depth, 300, 1.0)
    b, forward = b0 + c, True
    while True:
        post.move("G1", X=a1 - c if forward else a0 + c, F=FEED[1])
        forward = not forward
        if b >= b1 - c:
            break
        b = min(b1 - c, b + 6.0)
        post.move("G1", Y=b)
    post.move("G1", X=a0 + c, Y=b0)
    post.move("G1", X=a1 - c)
    post.emit(f"G3 X{fmt(a1)} Y{fmt(b0 + c)} I0. J{fmt(c)}")
    post.move("G1", Y=b1 - c)
    post.emit(f"G3 X{fmt(a1 - c)} Y{fmt(b1)} I{fmt(-c)} J0.")
    post.move("G1", X=a0 + c)
    post.emit(f"G3 X{fmt(a0)} Y{fmt(b1 - c)} I0. J{fmt(-c)}")
    post.move("G1", Y=b0 + c)
    post.emit(f"G3 X{fmt(a0 + c)} Y{fmt(b0)} I{fmt(c)} J0.")
    post.end_operation()

    # A ball-end slot: a straight run and a ramp down a diagonal.
    post.operation(f"{name} SLOT, 8 MM BALL END", 2, plane, clearance)
    su0, su1, sv = u0 + 0.42 * w, u0 + 0.74 * w, v0 + 0.72 * h
    post.rapid_to(su0, sv)
    post.plunge(-2.5, 300, 1.0)
    post.move("G1", X=su1, F=FEED[2])
    post.move("G1", X=su1 - 0.1 * w, Y=v0 + 0.45 * h, Z=-1.5)
    post.end_operation()

    # A circular groove: two G2 half circles (I, J relative to the start).
    post.operation(f"{name} CIRCULAR GROOVE, 4 MM BALL END", 3, plane, clearance)
    cu, cv = u0 + 0.87 * w, v0 + 0.5 * h
    rad = min(0.09 * w, 0.34 * h)
    post.rapid_to(cu + rad, cv)
    post.plunge(-1.5, 300, 1.0)
    post.emit(f"G2 X{fmt(cu - rad)} Y{fmt(cv)} I{fmt(-rad)} J0. F{FEED[3]}")
    post.emit(f"G2 X{fmt(cu + rad)} Y{fmt(cv)} I{fmt(rad)} J0.")
    post.end_operation()

    # An engraved wave.
    post.operation(f"{name} ENGRAVE A WAVE, 2 MM BALL END", 4, plane, clearance)
    wu0, wu1, wv = u0 + 0.42 * w, u0 + 0.74 * w, v0 + 0.2 * h
    n = 80
    pts = [(wu0 + (wu1 - wu0) * k / n, wv + 0.1 * h * math.sin(4 * math.pi * k / n)) for k in range(n + 1)]
    post.rapid_to(*pts[0])
    post.plunge(-0.8, 200, 1.0)
    for pu, pv in pts[1:]:
        post.move("G1", X=pu, Y=pv, F=FEED[4])
    post.end_operation()


def program(post, title):
    post.emit("%")
    post.emit(title)
    post.emit("(STOCK X0 Y0 Z0 TO X100 Y80 Z50, WORK OFFSET G54 AT THE STOCK CORNER)")
    for number, tool in TOOLS.items():
        post.emit(f"(T{number} D={fmt(tool['diameter'])} {tool['description'].upper()})")
    post.emit("G21 G17 G40 G49 G80 G90")
    top(post)
    # Directions and their feature planes (G68.2 Euler Z-X-Z angles a, b, c; tool axis
    # (sin a sin b, -cos a sin b, cos b)). Regions are (u0, u1, v0, v1) in the feature plane.
    tilt = 70.0  # b = 70 degrees: the spindle 20 degrees above horizontal, pointing to +X
    # The bevel's top edge, where it meets the mold surface, lies 13.9-16.1 mm up the bevel
    # (v); its features stop below 13 mm so that none cuts through that edge.
    side(post, "+X TILTED 20 DEG", ((100.0, 40.0, 22.0), (90.0, tilt, 0.0)),
         (-36.0, 36.0, 0.5, 12.5), 15.0, bevel=(-45.0, 45.0, 0.0, 32.0))
    side(post, "+Y", ((50.0, 80.0, 18.0), (180.0, 90.0, 0.0)), (-42.0, 42.0, -13.0, 13.0), 10.0)
    side(post, "-X", ((0.0, 40.0, 18.0), (-90.0, 90.0, 0.0)), (-32.0, 32.0, -13.0, 13.0), 10.0)
    side(post, "-Y", ((50.0, 0.0, 18.0), (0.0, 90.0, 0.0)), (-42.0, 42.0, -13.0, 13.0), 10.0)
    post.emit("G28 G91 Z0.")
    post.emit("G90")
    post.emit("G69")
    post.emit("M30")
    post.emit("%")
    return "\n".join(post.lines) + "\n"


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    out_dir = os.path.join(here, "..", "gcode", "examples")
    with open(os.path.join(out_dir, "mold_3plus2.nc"), "w", newline="\n") as f:
        f.write(program(Post(), "O3201 (TRIDEX 3+2 EXAMPLE: MOLD TOP AND FOUR SIDES)"))
    with open(os.path.join(out_dir, "mold_3plus2_bc.nc"), "w", newline="\n") as f:
        f.write(program(RotaryPost(), "O3202 (TRIDEX 3+2 EXAMPLE, ROTARY-INDEXED TWIN: B/C TABLE, HAAS DWO G254)"))
    with open(os.path.join(out_dir, "mold_3plus2_bc.machine.json"), "w", newline="\n") as f:
        json.dump({"kinematics": "bc-trunnion"}, f, indent=2)
        f.write("\n")

    table = {str(n): {"units": "mm", "shape": t["shape"], "length": t["length"],
                      "diameter": t["diameter"], "description": t["description"]}
             for n, t in TOOLS.items()}
    with open(os.path.join(out_dir, "mold_3plus2.tools.json"), "w", newline="\n") as f:
        json.dump(table, f, indent=2)
        f.write("\n")
    project = {"units": "metric", "tools": table, "files": ["mold_3plus2.nc"],
               "workpiece": {"automatic": False, "margin": 0,
                             "bounds": {"min": list(STOCK[:3]), "max": list(STOCK[3:])}}}
    with open(os.path.join(out_dir, "mold_3plus2.camotics"), "w", newline="\n") as f:
        json.dump(project, f, indent=2)
        f.write("\n")


if __name__ == "__main__":
    main()
