#!/usr/bin/env python3
"""Generates the many-light warehouse scenes.

Run from anywhere:

    python3 scripts/generate-many-lights.py

It (over)writes, relative to the repository root:

    scenes/many-lights/scene.toml       the hall, closed by its ceiling
    scenes/many-lights/hall.obj         floor, four walls, shelf rows, shelf lights
    scenes/many-lights/ceiling.obj      ceiling and ceiling lights
    scenes/many-lights/many-lights.mtl  the materials of both OBJs
    scenes/many-lights-sky/scene.toml   the same hall and shelf lights without the ceiling,
                                        under ../glossy-env/sky.exr

Standard library only and deterministic (random.Random(1)): running it twice gives the same
bytes. The layout (metres, +Y up, right-handed): a hall x in [0, 10.4], z in [0, 16], 4 high.
Five rows of shelf units run along z (z in [1.5, 14.5], 13 bays of 1 m): one single-sided row
against each side wall and three double-sided rows between them, each with a back panel down
its middle, so each of the four aisles (1.6 wide) is closed off from the next. A unit has a
plinth and five boards; the underside of every board carries 8 small emissive quads (6-10 cm)
facing down into the compartment below. The ceiling carries 128 more over the aisles. Each
light takes one of 16 emission materials at random, whose Ke (largest channel) is log-spaced
from 0.2 to 200 in four colours. Every face is counter-clockwise seen from the side it faces.
"""

import math
import os
import random

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "scenes", "many-lights")
OUT_SKY = os.path.join(ROOT, "scenes", "many-lights-sky")

# ---- layout ---------------------------------------------------------------------------------
HALL_W, HALL_L, HALL_H = 10.4, 16.0, 4.0
ROW_Z0, ROW_Z1, BAYS = 1.5, 14.5, 13           # shelf rows' extent along z, bays of 1 m
PANEL_T = 0.025                                 # side panel thickness (along z)
BACK_T = 0.02                                   # back panel thickness (along x)
UNIT_H = 2.60                                   # top of side and back panels
PLINTH_H = 0.12
BOARD_T = 0.03
BOARD_BOTTOMS = [0.55, 1.05, 1.55, 2.05, 2.55]  # each board's underside carries lights
INSET = 0.01                                    # boards' front edges behind the panels'
LIGHT_GAP = 0.002                               # lights hang this far below a board
# Rows: (x0, x1, open sides): -1 opens toward -x, +1 toward +x. Wall rows touch a wall.
ROWS = [
    (0.0, 0.5, [+1]),
    (2.1, 3.1, [-1, +1]),
    (4.7, 5.7, [-1, +1]),
    (7.3, 8.3, [-1, +1]),
    (9.9, 10.4, [-1]),
]
AISLE_CENTRES = [1.3, 3.9, 6.5, 9.1]
LIGHTS_Z, LIGHTS_X = 4, 2                       # lights per board underside per bay and side
LIGHT_SIZE = (0.06, 0.10)

# ---- materials -------------------------------------------------------------------------------
SURFACES = [
    ("wall", "Kd 0.55 0.55 0.52", "painted walls"),
    ("floor", "Kd 0.45 0.45 0.45\nKs 0.1 0.1 0.1\nNs 20", "sealed concrete, slightly glossy"),
    ("ceiling", "Kd 0.6 0.6 0.6", None),
    ("panel", "Kd 0.3 0.4 0.55", "painted steel: side panels"),
    ("back", "Kd 0.5 0.5 0.5", "back panels"),
    ("board", "Kd 0.6 0.5 0.35", "shelf boards"),
    ("plinth", "Kd 0.3 0.3 0.3", None),
]
EMISSION_LEVELS = 16
KE_MIN, KE_MAX = 0.2, 200.0
# Level i takes COLOURS[i % 4]: the brightest level (15) is warm white, the tints sit lower.
COLOURS = [
    ("teal", (0.35, 1.0, 0.75)),
    ("amber", (1.0, 0.55, 0.2)),
    ("cool white", (0.8, 0.9, 1.0)),
    ("warm white", (1.0, 0.82, 0.6)),
]
EMITTER_KD = "Kd 0.5 0.5 0.5"


def ke_scale(i):
    return KE_MIN * (KE_MAX / KE_MIN) ** (i / (EMISSION_LEVELS - 1))


def light_name(i):
    return "light%02d" % i


def fmt(v):
    s = ("%.4f" % v).rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


# ---- geometry --------------------------------------------------------------------------------
class Obj:
    """An OBJ under construction: vertices shared by exact position, faces grouped by material."""

    def __init__(self):
        self.vertices = []
        self.index = {}
        self.faces = {}  # material -> list of (object name, [indices])

    def vertex(self, p):
        key = tuple(fmt(c) for c in p)
        if key not in self.index:
            self.vertices.append(key)
            self.index[key] = len(self.vertices)
        return self.index[key]

    def quad(self, material, corners, normal, shared=True):
        """Adds a planar quad, its corners in order round it, counter-clockwise seen from
        `normal`'s side (the order is reversed if needed)."""
        a, b, c = corners[0], corners[1], corners[2]
        e1 = [b[k] - a[k] for k in range(3)]
        e2 = [c[k] - a[k] for k in range(3)]
        n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
             e1[0] * e2[1] - e1[1] * e2[0]]
        if sum(n[k] * normal[k] for k in range(3)) < 0:
            corners = corners[::-1]
        if shared:
            idx = [self.vertex(p) for p in corners]
        else:
            idx = []
            for p in corners:
                self.vertices.append(tuple(fmt(c) for c in p))
                idx.append(len(self.vertices))
        self.faces.setdefault(material, []).append(idx)

    def rect(self, material, axis, at, lo, hi, facing, shared=True):
        """An axis-aligned rectangle in the plane `axis` = `at`, spanning lo..hi on the other two
        axes (lo and hi are 3-vectors whose `axis` entry is ignored), facing +axis (facing = 1)
        or -axis (-1)."""
        u, v = [k for k in range(3) if k != axis]
        corners = []
        for (cu, cv) in [(lo[u], lo[v]), (hi[u], lo[v]), (hi[u], hi[v]), (lo[u], hi[v])]:
            p = [0.0, 0.0, 0.0]
            p[axis], p[u], p[v] = at, cu, cv
            corners.append(p)
        normal = [0.0, 0.0, 0.0]
        normal[axis] = facing
        self.quad(material, corners, normal, shared)

    def box(self, material, lo, hi, faces):
        """Faces of the box lo..hi, each facing out; `faces` names those wanted: '-x', '+x',
        '-y', '+y', '-z', '+z'."""
        for f in faces:
            axis = "xyz".index(f[1])
            if f[0] == "+":
                self.rect(material, axis, hi[axis], lo, hi, 1)
            else:
                self.rect(material, axis, lo[axis], lo, hi, -1)

    def write(self, path, header, mtllib, order):
        lines = ["# " + l if l else "#" for l in header]
        lines.append("mtllib " + mtllib)
        for v in self.vertices:
            lines.append("v %s %s %s" % v)
        for m in order:
            if m not in self.faces:
                continue
            lines.append("usemtl " + m)
            for idx in self.faces[m]:
                lines.append("f " + " ".join(str(i) for i in idx))
        with open(path, "w", newline="\n") as f:
            f.write("\n".join(lines) + "\n")


def pick_light(rng):
    return light_name(rng.randrange(EMISSION_LEVELS))


def shelf_row(obj, x0, x1, sides, rng, lights):
    """One row of shelf units: plinth, boards, side panels, back panel, and the lights under
    the boards on each open side. Appends (material,) per light to `lights`."""
    wall_row = len(sides) == 1
    # Board and plinth extent along x: inset behind the open front(s), flush with a wall.
    bx0 = x0 + (INSET if -1 in sides else 0.0)
    bx1 = x1 - (INSET if +1 in sides else 0.0)
    zin0, zin1 = ROW_Z0 + PANEL_T, ROW_Z1 - PANEL_T
    fronts = ["-x" if s < 0 else "+x" for s in sides]
    # Plinth, recessed a little more (a kick plate).
    px0 = x0 + (2 * INSET if -1 in sides else 0.0)
    px1 = x1 - (2 * INSET if +1 in sides else 0.0)
    obj.box("plinth", (px0, 0.0, zin0), (px1, PLINTH_H, zin1), ["+y"] + fronts)
    # Boards span the row between its end panels and cross the interior panels.
    for b in BOARD_BOTTOMS:
        obj.box("board", (bx0, b, zin0), (bx1, b + BOARD_T, zin1), ["-y", "+y"] + fronts)
    # Side panels at every bay boundary (the end ones flush with the row's ends).
    for k in range(BAYS + 1):
        zc = ROW_Z0 + k * (ROW_Z1 - ROW_Z0) / BAYS
        z0 = min(max(zc - PANEL_T / 2, ROW_Z0), ROW_Z1 - PANEL_T)
        obj.box("panel", (x0, 0.0, z0), (x1, UNIT_H, z0 + PANEL_T), ["-z", "+z", "+y"] + fronts)
    # Back panel: down the middle of a double row; a wall row's back is the wall.
    if wall_row:
        back = x0 if sides == [+1] else x1
        xc = back
    else:
        xc = (x0 + x1) / 2
        obj.box("back", (xc - BACK_T / 2, 0.0, zin0), (xc + BACK_T / 2, UNIT_H, zin1),
                ["-x", "+x", "+y"])
    # Lights under every board, facing down, on each open side.
    for s in sides:
        if wall_row:
            near, far = (bx1, x0) if s > 0 else (bx0, x1)  # near: open front; far: the wall
        else:
            near = bx1 if s > 0 else bx0
            far = xc + s * BACK_T / 2
        depth = abs(near - far)
        for k in range(BAYS):
            bz0 = ROW_Z0 + k * (ROW_Z1 - ROW_Z0) / BAYS + PANEL_T / 2
            bz1 = bz0 + (ROW_Z1 - ROW_Z0) / BAYS - PANEL_T
            if k == 0:
                bz0 = ROW_Z0 + PANEL_T
            if k == BAYS - 1:
                bz1 = ROW_Z1 - PANEL_T
            cell_z = (bz1 - bz0) / LIGHTS_Z
            cell_x = depth / LIGHTS_X
            for b in BOARD_BOTTOMS:
                y = b - LIGHT_GAP
                for i in range(LIGHTS_Z):
                    for j in range(LIGHTS_X):
                        size = rng.uniform(*LIGHT_SIZE)
                        slack_z = (cell_z - size) / 2 - 0.01
                        slack_x = (cell_x - size) / 2 - 0.01
                        cz = bz0 + (i + 0.5) * cell_z + rng.uniform(-slack_z, slack_z)
                        d = (j + 0.5) * cell_x + rng.uniform(-slack_x, slack_x)
                        cx = near - s * d
                        h = size / 2
                        m = pick_light(rng)
                        obj.rect(m, 1, y, (cx - h, 0, cz - h), (cx + h, 0, cz + h), -1,
                                 shared=False)
                        lights.append(m)


def hall(rng, lights):
    obj = Obj()
    W, L, H = HALL_W, HALL_L, HALL_H
    obj.rect("floor", 1, 0.0, (0, 0, 0), (W, 0, L), 1)
    obj.rect("wall", 0, 0.0, (0, 0, 0), (0, H, L), 1)
    obj.rect("wall", 0, W, (0, 0, 0), (0, H, L), -1)
    obj.rect("wall", 2, 0.0, (0, 0, 0), (W, H, 0), 1)
    obj.rect("wall", 2, L, (0, 0, 0), (W, H, 0), -1)
    for (x0, x1, sides) in ROWS:
        shelf_row(obj, x0, x1, sides, rng, lights)
    return obj


def ceiling(rng, lights):
    obj = Obj()
    W, L, H = HALL_W, HALL_L, HALL_H
    obj.rect("ceiling", 1, H, (0, 0, 0), (W, 0, L), -1)
    y = H - LIGHT_GAP
    for xc in AISLE_CENTRES:
        for dx in (-0.3, 0.3):
            for k in range(16):
                size = rng.uniform(*LIGHT_SIZE)
                cx = xc + dx + rng.uniform(-0.05, 0.05)
                cz = 0.5 + k + rng.uniform(-0.1, 0.1)
                h = size / 2
                m = pick_light(rng)
                obj.rect(m, 1, y, (cx - h, 0, cz - h), (cx + h, 0, cz + h), -1, shared=False)
                lights.append(m)
    return obj


def mtl_text():
    lines = [
        "# many-lights materials (generated by scripts/generate-many-lights.py; do not edit).",
        "# Surfaces diffuse (one slightly glossy floor), Kd + Ks <= 1. Emitters light00..light15:",
        "# Ke's largest channel log-spaced from %g to %g (factor %.4f apart), colours cycling"
        % (KE_MIN, KE_MAX, (KE_MAX / KE_MIN) ** (1 / (EMISSION_LEVELS - 1))),
        "# " + ", ".join(c for c, _ in COLOURS) + "; each light quad took one at random.",
    ]
    for name, body, comment in SURFACES:
        lines.append("")
        if comment:
            lines.append("# " + comment)
        lines.append("newmtl " + name)
        lines.extend(body.split("\n"))
    for i in range(EMISSION_LEVELS):
        cname, c = COLOURS[i % len(COLOURS)]
        s = ke_scale(i)
        lines.append("")
        lines.append("# %s, %.4g" % (cname, s))
        lines.append("newmtl " + light_name(i))
        lines.append(EMITTER_KD)
        lines.append("Ke " + " ".join(fmt(s * v) for v in c))
    return "\n".join(lines) + "\n"


CAMERA = """[camera]
position = [3.9, 1.6, 15.6]
look_at = [3.9, 1.0, 3.0]
up = [0.0, 1.0, 0.0]
fov_y = 60.0
resolution = [256, 192]
"""


def main():
    rng = random.Random(1)
    hall_lights, ceiling_lights = [], []
    h = hall(rng, hall_lights)
    c = ceiling(rng, ceiling_lights)
    order = [m for m, _, _ in SURFACES] + [light_name(i) for i in range(EMISSION_LEVELS)]
    os.makedirs(OUT, exist_ok=True)
    os.makedirs(OUT_SKY, exist_ok=True)
    with open(os.path.join(OUT, "many-lights.mtl"), "w", newline="\n") as f:
        f.write(mtl_text())
    gen = "Generated by scripts/generate-many-lights.py (python3 scripts/generate-many-lights.py);"
    h.write(os.path.join(OUT, "hall.obj"), [
        "many-lights hall: floor, four walls, five rows of shelf units and %d small emissive"
        % len(hall_lights),
        "quads under the shelf boards, facing down. %s do not edit." % gen,
        "+Y up; counter-clockwise is the front; walls face into the hall, lights face down.",
    ], "many-lights.mtl", order)
    c.write(os.path.join(OUT, "ceiling.obj"), [
        "many-lights ceiling (facing down) and %d small emissive quads under it, facing down."
        % len(ceiling_lights),
        "%s do not edit." % gen,
    ], "many-lights.mtl", order)
    n_hall, n_ceil = len(hall_lights), len(ceiling_lights)
    with open(os.path.join(OUT, "scene.toml"), "w", newline="\n") as f:
        f.write(
            "# many-lights: a closed warehouse hall (10.4 x 16, 4 high) with five rows of tall shelf\n"
            "# units closed at the back, so each aisle is walled off from the next, lit only by %d\n"
            "# small emissive quads (%d triangles): %d under the shelf boards facing down into the\n"
            "# compartments, %d on the ceiling over the aisles. Their Ke spans three orders of\n"
            "# magnitude (16 levels, 0.2 to 200, four colours, assigned at random), and most lights\n"
            "# are hidden from most points: a test of many-light sampling. The camera looks down the\n"
            "# second aisle. Generated by `python3 scripts/generate-many-lights.py`; do not edit.\n"
            % (n_hall + n_ceil, 2 * (n_hall + n_ceil), n_hall, n_ceil)
        )
        f.write(CAMERA)
        f.write('\n[[mesh]]\nobj = "hall.obj"\n\n[[mesh]]\nobj = "ceiling.obj"\n')
    with open(os.path.join(OUT_SKY, "scene.toml"), "w", newline="\n") as f:
        f.write(
            "# many-lights-sky: many-lights' hall and its %d shelf lights (%d triangles) without the\n"
            "# ceiling (or its lights), open to ../glossy-env/sky.exr (a sky with a small sun), so\n"
            "# the environment map comes in from above and competes with the many small lights.\n"
            "# Same camera. Generated by `python3 scripts/generate-many-lights.py`; do not edit.\n"
            % (n_hall, 2 * n_hall)
        )
        f.write(CAMERA)
        f.write('\n[[mesh]]\nobj = "../many-lights/hall.obj"\n\n'
                '[environment]\nexr = "../glossy-env/sky.exr"\nscale = 1.0\n')
    print("hall.obj: %d shelf lights; ceiling.obj: %d ceiling lights; %d quads, %d triangles"
          % (n_hall, n_ceil, n_hall + n_ceil, 2 * (n_hall + n_ceil)))


if __name__ == "__main__":
    main()
