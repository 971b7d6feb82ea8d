#!/usr/bin/env python3
"""Generates the many-light warehouse scenes.

    python3 scripts/generate-many-lights.py --out DIR [--lights N] [--seed S]
    python3 scripts/generate-many-lights.py --overwrite-shipped

writes, under DIR (the second form: the repository's scenes/, the shipped scenes):

    many-lights/scene.toml       the hall, closed by its ceiling
    many-lights/hall.obj         floor, four walls, shelf rows, shelf lights
    many-lights/ceiling.obj      ceiling and ceiling lights
    many-lights/many-lights.mtl  the materials of both OBJs
    many-lights-sky/scene.toml   the same hall and shelf lights without the ceiling, under
                                 glossy-env's sky.exr

It never writes the shipped scenes without --overwrite-shipped, which with the defaults
reproduces them byte for byte. Standard library only and deterministic (random.Random(seed)):
running it twice gives the same bytes.

The shipped layout (metres, +Y up, right-handed): a hall x in [0, 10.4], z in [0, 16], 4 high.
Five rows of shelf units run along z (z in [1.5, 14.5], 13 bays of 1 m): one single-sided row
against each side wall and three double-sided rows between them, each with a back panel down
its middle, so each of the four aisles (1.6 wide) is closed off from the next. A unit has a
plinth and five boards; the underside of every board carries 8 small emissive quads (6-10 cm)
facing down into the compartment below. The ceiling carries 128 more over the aisles (two
strips of one per metre along each aisle): 4288 lights. Each light takes one of 16 emission
materials at random, whose Ke (largest channel) is log-spaced from 0.2 to 200 in four colours.
Every face is counter-clockwise seen from the side it faces.

--lights N asks for N lights (emissive quads, two triangles each; 1 to 2^20): the hall grows
(or shrinks) in double rows and bays, in the shipped proportions, to the smallest that holds
N, and the lights beyond N are left out at random, spread over the hall.
"""

import argparse
import os
import random
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHIPPED = os.path.join(ROOT, "scenes")
SKY = os.path.join(SHIPPED, "glossy-env", "sky.exr")
MAX_LIGHTS = 1 << 20

# ---- layout ---------------------------------------------------------------------------------
HALL_H = 4.0
ROW_Z0 = 1.5                                    # shelf rows start here along z, bays of 1 m
END_GAP = 1.5                                   # and end this far from the far wall
PANEL_T = 0.025                                 # side panel thickness (along z)
BACK_T = 0.02                                   # back panel thickness (along x)
UNIT_H = 2.60                                   # top of side and back panels
PLINTH_H = 0.12
BOARD_T = 0.03
BOARD_BOTTOMS = [0.55, 1.05, 1.55, 2.05, 2.55]  # each board's underside carries lights
INSET = 0.01                                    # boards' front edges behind the panels'
LIGHT_GAP = 0.002                               # lights hang this far below a board
WALL_ROW_D, DOUBLE_ROW_D, AISLE_W = 0.5, 1.0, 1.6
SHIPPED_DOUBLE_ROWS, SHIPPED_BAYS = 3, 13       # 4288 lights
LIGHTS_Z, LIGHTS_X = 4, 2                       # lights per board underside per bay and side
LIGHT_SIZE = (0.06, 0.10)


class Layout:
    """The hall: a single-sided row against each side wall and `double_rows` double-sided rows
    between them, aisles between the rows, `bays` bays of 1 m along z."""

    def __init__(self, double_rows, bays):
        self.double_rows, self.bays = double_rows, bays
        # Rows: (x0, x1, open sides): -1 opens toward -x, +1 toward +x. Wall rows touch a wall.
        # Rounded, so the shipped layout's numbers are exactly the literals it was written with.
        self.rows = [(0.0, WALL_ROW_D, [+1])]
        x = WALL_ROW_D + AISLE_W
        for _ in range(double_rows):
            self.rows.append((round(x, 6), round(x + DOUBLE_ROW_D, 6), [-1, +1]))
            x += DOUBLE_ROW_D + AISLE_W
        self.width = round(x + WALL_ROW_D, 6)
        self.rows.append((round(x, 6), self.width, [-1]))
        self.aisle_centres = [round(self.rows[i][1] + AISLE_W / 2, 6)
                              for i in range(double_rows + 1)]
        self.row_z1 = ROW_Z0 + bays
        self.length = self.row_z1 + END_GAP
        self.ceiling_per_strip = int(self.length)  # one light per metre along each aisle

    def shelf_sides(self):
        return 2 + 2 * self.double_rows

    def capacity(self):
        shelf = self.shelf_sides() * self.bays * len(BOARD_BOTTOMS) * LIGHTS_Z * LIGHTS_X
        return shelf + len(self.aisle_centres) * 2 * self.ceiling_per_strip


def layout_for(lights):
    """The smallest hall in the shipped proportions (3 double rows to 13 bays) that holds
    `lights`; for the shipped 4288, the shipped hall."""
    k = 1
    while True:
        s = k / 20.0
        layout = Layout(max(1, round(SHIPPED_DOUBLE_ROWS * s)), max(4, round(SHIPPED_BAYS * s)))
        if layout.capacity() >= lights:
            return layout
        k += 1


class Lights:
    """Hands out the hall's light slots in order, keeping `count` of them: the rest are left
    out at random (their random draws still made, so the kept lights are those of the full
    hall)."""

    def __init__(self, capacity, count, seed):
        self.slot = 0
        drop_rng = random.Random("many-lights: lights left out, seed %d" % seed)
        self.dropped = set(drop_rng.sample(range(capacity), capacity - count)) \
            if count < capacity else set()

    def keep(self):
        kept = self.slot not in self.dropped
        self.slot += 1
        return kept


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
        # Lines as they will be written, not tuples and lists: a hall of 2^20 lights holds
        # 4 million vertices.
        self.vertices = []  # "v x y z"
        self.index = {}
        self.faces = {}  # material -> ["f i j k l"]

    def vertex(self, p):
        line = "v %s %s %s" % tuple(fmt(c) for c in p)
        if line not in self.index:
            self.vertices.append(line)
            self.index[line] = len(self.vertices)
        return self.index[line]

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
                self.vertices.append("v %s %s %s" % tuple(fmt(c) for c in p))
                idx.append(len(self.vertices))
        self.faces.setdefault(material, []).append("f " + " ".join(str(i) for i in idx))

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
        with open(path, "w", newline="\n") as f:
            f.write("\n".join(lines) + "\n")
            f.writelines(v + "\n" for v in self.vertices)
            for m in order:
                if m in self.faces:
                    f.write("usemtl " + m + "\n")
                    f.writelines(face + "\n" for face in self.faces[m])


def pick_light(rng):
    return light_name(rng.randrange(EMISSION_LEVELS))


def shelf_row(obj, lay, x0, x1, sides, rng, slots, lights):
    """One row of shelf units: plinth, boards, side panels, back panel, and the lights under
    the boards on each open side that `slots` keeps. Appends each light's material to
    `lights`."""
    row_z1, bays = lay.row_z1, lay.bays
    wall_row = len(sides) == 1
    # Board and plinth extent along x: inset behind the open front(s), flush with a wall.
    bx0 = x0 + (INSET if -1 in sides else 0.0)
    bx1 = x1 - (INSET if +1 in sides else 0.0)
    zin0, zin1 = ROW_Z0 + PANEL_T, row_z1 - PANEL_T
    fronts = ["-x" if s < 0 else "+x" for s in sides]
    # Plinth, recessed a little more (a kick plate).
    px0 = x0 + (2 * INSET if -1 in sides else 0.0)
    px1 = x1 - (2 * INSET if +1 in sides else 0.0)
    obj.box("plinth", (px0, 0.0, zin0), (px1, PLINTH_H, zin1), ["+y"] + fronts)
    # Boards span the row between its end panels and cross the interior panels.
    for b in BOARD_BOTTOMS:
        obj.box("board", (bx0, b, zin0), (bx1, b + BOARD_T, zin1), ["-y", "+y"] + fronts)
    # Side panels at every bay boundary (the end ones flush with the row's ends).
    for k in range(bays + 1):
        zc = ROW_Z0 + k * (row_z1 - ROW_Z0) / bays
        z0 = min(max(zc - PANEL_T / 2, ROW_Z0), row_z1 - PANEL_T)
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
        for k in range(bays):
            bz0 = ROW_Z0 + k * (row_z1 - ROW_Z0) / bays + PANEL_T / 2
            bz1 = bz0 + (row_z1 - ROW_Z0) / bays - PANEL_T
            if k == 0:
                bz0 = ROW_Z0 + PANEL_T
            if k == bays - 1:
                bz1 = row_z1 - PANEL_T
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
                        if not slots.keep():
                            continue
                        obj.rect(m, 1, y, (cx - h, 0, cz - h), (cx + h, 0, cz + h), -1,
                                 shared=False)
                        lights.append(m)


def hall(lay, rng, slots, lights):
    obj = Obj()
    W, L, H = lay.width, lay.length, HALL_H
    obj.rect("floor", 1, 0.0, (0, 0, 0), (W, 0, L), 1)
    obj.rect("wall", 0, 0.0, (0, 0, 0), (0, H, L), 1)
    obj.rect("wall", 0, W, (0, 0, 0), (0, H, L), -1)
    obj.rect("wall", 2, 0.0, (0, 0, 0), (W, H, 0), 1)
    obj.rect("wall", 2, L, (0, 0, 0), (W, H, 0), -1)
    for (x0, x1, sides) in lay.rows:
        shelf_row(obj, lay, x0, x1, sides, rng, slots, lights)
    return obj


def ceiling(lay, rng, slots, lights):
    obj = Obj()
    W, L, H = lay.width, lay.length, HALL_H
    obj.rect("ceiling", 1, H, (0, 0, 0), (W, 0, L), -1)
    y = H - LIGHT_GAP
    for xc in lay.aisle_centres:
        for dx in (-0.3, 0.3):
            for k in range(lay.ceiling_per_strip):
                size = rng.uniform(*LIGHT_SIZE)
                cx = xc + dx + rng.uniform(-0.05, 0.05)
                cz = 0.5 + k + rng.uniform(-0.1, 0.1)
                h = size / 2
                m = pick_light(rng)
                if not slots.keep():
                    continue
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


def camera(lay):
    """Looking down the second aisle from near the far wall."""
    x = fmt(lay.aisle_centres[1])
    return ("[camera]\n"
            "position = [%s, 1.6, %s]\n"
            "look_at = [%s, 1.0, 3.0]\n"
            "up = [0.0, 1.0, 0.0]\n"
            "fov_y = 60.0\n"
            "resolution = [256, 192]\n" % (x, fmt(lay.length - 0.4), x))


def count_words(n):
    return {5: "five"}.get(n, str(n))


def parse_args(argv):
    parser = argparse.ArgumentParser(
        prog="generate-many-lights.py",
        description="Generates the many-light warehouse scenes (many-lights/ and "
        "many-lights-sky/) into a folder; the hall grows to hold the lights asked for.",
        epilog="Without --out it writes nothing: the shipped scenes (the repository's scenes/) "
        "are rewritten only with --overwrite-shipped, which with the defaults reproduces them "
        "byte for byte.")
    parser.add_argument("-o", "--out", metavar="DIR",
                        help="folder to write many-lights/ and many-lights-sky/ into (created)")
    parser.add_argument("--overwrite-shipped", action="store_true",
                        help="write into the repository's scenes/, replacing the shipped scenes")
    parser.add_argument("--lights", type=int, metavar="N",
                        help="emissive quads (two triangles each), 1 to %d (2^20); the hall "
                        "grows to hold them (default: the shipped hall's 4288)" % MAX_LIGHTS)
    parser.add_argument("--seed", type=int, default=1,
                        help="seed of the lights' sizes, places and emissions (default: 1)")
    args = parser.parse_args(argv)
    if args.lights is not None and not 1 <= args.lights <= MAX_LIGHTS:
        parser.error("--lights %d: the number of lights is 1 to %d (2^20)"
                     % (args.lights, MAX_LIGHTS))
    shipped = os.path.realpath(SHIPPED)
    if args.out is None:
        if not args.overwrite_shipped:
            parser.error("no --out DIR: name the folder to write the scenes into (the shipped "
                         "scenes in %s are rewritten only with --overwrite-shipped)" % SHIPPED)
        args.out = SHIPPED
    elif os.path.realpath(args.out) == shipped and not args.overwrite_shipped:
        parser.error("--out %s: that is the shipped scenes' folder; pass --overwrite-shipped to "
                     "rewrite them" % args.out)
    elif args.overwrite_shipped and os.path.realpath(args.out) != shipped:
        parser.error("--overwrite-shipped writes into %s, not --out %s" % (SHIPPED, args.out))
    return args


def main(argv):
    args = parse_args(argv)
    shipped = Layout(SHIPPED_DOUBLE_ROWS, SHIPPED_BAYS).capacity()
    count = args.lights if args.lights is not None else shipped
    lay = layout_for(count)
    out = os.path.join(args.out, "many-lights")
    out_sky = os.path.join(args.out, "many-lights-sky")
    # Regeneration as the files say; the shipped scenes' own words are kept as they were.
    command = "python3 scripts/generate-many-lights.py"
    if (count, args.seed) != (shipped, 1):
        command += " --lights %d --seed %d" % (count, args.seed)
    rng = random.Random(args.seed)
    slots = Lights(lay.capacity(), count, args.seed)
    hall_lights, ceiling_lights = [], []
    h = hall(lay, rng, slots, hall_lights)
    c = ceiling(lay, rng, slots, ceiling_lights)
    order = [m for m, _, _ in SURFACES] + [light_name(i) for i in range(EMISSION_LEVELS)]
    os.makedirs(out, exist_ok=True)
    os.makedirs(out_sky, exist_ok=True)
    with open(os.path.join(out, "many-lights.mtl"), "w", newline="\n") as f:
        f.write(mtl_text())
    gen = "Generated by scripts/generate-many-lights.py (%s);" % command
    rows = count_words(len(lay.rows))
    h.write(os.path.join(out, "hall.obj"), [
        "many-lights hall: floor, four walls, %s rows of shelf units and %d small emissive"
        % (rows, len(hall_lights)),
        "quads under the shelf boards, facing down. %s do not edit." % gen,
        "+Y up; counter-clockwise is the front; walls face into the hall, lights face down.",
    ], "many-lights.mtl", order)
    c.write(os.path.join(out, "ceiling.obj"), [
        "many-lights ceiling (facing down) and %d small emissive quads under it, facing down."
        % len(ceiling_lights),
        "%s do not edit." % gen,
    ], "many-lights.mtl", order)
    n_hall, n_ceil = len(hall_lights), len(ceiling_lights)
    cam = camera(lay)
    with open(os.path.join(out, "scene.toml"), "w", newline="\n") as f:
        f.write(
            "# many-lights: a closed warehouse hall (%s x %s, 4 high) with %s rows of tall shelf\n"
            "# units closed at the back, so each aisle is walled off from the next, lit only by %d\n"
            "# small emissive quads (%d triangles): %d under the shelf boards facing down into the\n"
            "# compartments, %d on the ceiling over the aisles. Their Ke spans three orders of\n"
            "# magnitude (16 levels, 0.2 to 200, four colours, assigned at random), and most lights\n"
            "# are hidden from most points: a test of many-light sampling. The camera looks down the\n"
            "# second aisle. Generated by `%s`; do not edit.\n"
            % (fmt(lay.width), fmt(lay.length), rows, n_hall + n_ceil, 2 * (n_hall + n_ceil),
               n_hall, n_ceil, command)
        )
        f.write(cam)
        f.write('\n[[mesh]]\nobj = "hall.obj"\n\n[[mesh]]\nobj = "ceiling.obj"\n')
    # The sky as the sky scene's folder reaches it: relative inside the repository
    # (../glossy-env/sky.exr when shipped), absolute outside it.
    here = os.path.realpath(out_sky)
    if os.path.commonpath([here, os.path.realpath(ROOT)]) == os.path.realpath(ROOT):
        sky = os.path.relpath(os.path.realpath(SKY), here).replace(os.sep, "/")
    else:
        sky = os.path.realpath(SKY).replace(os.sep, "/")
    with open(os.path.join(out_sky, "scene.toml"), "w", newline="\n") as f:
        f.write(
            "# many-lights-sky: many-lights' hall and its %d shelf lights (%d triangles) without the\n"
            "# ceiling (or its lights), open to %s (a sky with a small sun), so\n"
            "# the environment map comes in from above and competes with the many small lights.\n"
            "# Same camera. Generated by `%s`; do not edit.\n"
            % (n_hall, 2 * n_hall, sky, command)
        )
        f.write(cam)
        f.write('\n[[mesh]]\nobj = "../many-lights/hall.obj"\n\n'
                '[environment]\nexr = "%s"\nscale = 1.0\n' % sky)
    print("%s: hall.obj: %d shelf lights; ceiling.obj: %d ceiling lights; %d quads, %d triangles"
          % (out, n_hall, n_ceil, n_hall + n_ceil, 2 * (n_hall + n_ceil)))


if __name__ == "__main__":
    main(sys.argv[1:])
