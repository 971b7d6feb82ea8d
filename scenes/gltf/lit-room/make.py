#!/usr/bin/env python3
"""Writes lit-room.gltf, lit-room.bin and checker.png beside this script (deterministic; run it
again rather than editing those files by hand).

A small room made for irad's glTF import tests (tests/gltf_import.rs): a checker-textured
floor, a wall, a gold box under a parent node, a mirrored copy of the box, an emissive ceiling
panel (KHR_materials_emissive_strength), a point, a spot and a directional light
(KHR_lights_punctual) and two perspective cameras.
"""

import json
import math
import struct
import zlib
from pathlib import Path

HERE = Path(__file__).resolve().parent


def png(width, height, rows):
    """An 8-bit RGB PNG of `rows` (lists of (r, g, b))."""
    raw = b"".join(b"\0" + bytes(c for px in row for c in px) for row in rows)

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


class Buffer:
    def __init__(self):
        self.data = bytearray()
        self.views = []
        self.accessors = []

    def add(self, fmt, items, kind, component, target, minmax=False):
        while len(self.data) % 4:
            self.data.append(0)
        offset = len(self.data)
        for item in items:
            self.data += struct.pack("<" + fmt, *(item if isinstance(item, tuple) else (item,)))
        self.views.append({"buffer": 0, "byteOffset": offset,
                           "byteLength": len(self.data) - offset, "target": target})
        accessor = {"bufferView": len(self.views) - 1, "componentType": component,
                    "count": len(items), "type": kind}
        if minmax:
            accessor["min"] = [min(v[k] for v in items) for k in range(3)]
            accessor["max"] = [max(v[k] for v in items) for k in range(3)]
        self.accessors.append(accessor)
        return len(self.accessors) - 1

    def mesh(self, positions, normals, indices, uvs=None):
        attributes = {
            "POSITION": self.add("3f", positions, "VEC3", 5126, 34962, minmax=True),
            "NORMAL": self.add("3f", normals, "VEC3", 5126, 34962),
        }
        if uvs:
            attributes["TEXCOORD_0"] = self.add("2f", uvs, "VEC2", 5126, 34962)
        return attributes, self.add("H", indices, "SCALAR", 5123, 34963)


def quad(corners, normal):
    return corners, [normal] * 4, [0, 1, 2, 0, 2, 3]


def cube():
    positions, normals, indices = [], [], []
    for axis in range(3):
        for sign in (1.0, -1.0):
            n = [0.0, 0.0, 0.0]
            n[axis] = sign
            u, v = [0.0] * 3, [0.0] * 3
            u[(axis + 1) % 3] = 1.0
            v[(axis + 2) % 3] = 1.0
            if sign < 0:
                u, v = v, u
            base = len(positions)
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                positions.append(tuple(0.5 * (n[k] + a * u[k] + b * v[k]) for k in range(3)))
                normals.append(tuple(n))
            indices += [base, base + 1, base + 2, base, base + 2, base + 3]
    return positions, normals, indices


def about_x(degrees):
    h = math.radians(degrees) / 2
    return [math.sin(h), 0.0, 0.0, math.cos(h)]


def about_y(degrees):
    h = math.radians(degrees) / 2
    return [0.0, math.sin(h), 0.0, math.cos(h)]


def main():
    buf = Buffer()
    floor = buf.mesh(*quad([(-2, 0, 2), (2, 0, 2), (2, 0, -2), (-2, 0, -2)], (0, 1, 0)),
                     uvs=[(0, 0), (4, 0), (4, 4), (0, 4)])
    wall = buf.mesh(*quad([(-2, 0, -2), (2, 0, -2), (2, 2.5, -2), (-2, 2.5, -2)], (0, 0, 1)))
    panel = buf.mesh(*quad([(-0.5, 2.4, -0.5), (0.5, 2.4, -0.5), (0.5, 2.4, 0.5),
                            (-0.5, 2.4, 0.5)], (0, -1, 0)))
    box = buf.mesh(*cube())
    meshes = []
    for name, (attributes, indices), material in (("floor", floor, 0), ("wall", wall, 1),
                                                  ("panel", panel, 3), ("box", box, 2)):
        meshes.append({"name": name, "primitives": [
            {"attributes": attributes, "indices": indices, "material": material}]})
    checker = [[(200, 60, 40) if (i + j) % 2 else (230, 230, 220) for i in range(8)]
               for j in range(8)]
    (HERE / "checker.png").write_bytes(png(8, 8, checker))
    (HERE / "lit-room.bin").write_bytes(bytes(buf.data))
    doc = {
        "asset": {"version": "2.0", "generator": "irad scenes/gltf/lit-room/make.py"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "warm", "type": "point", "color": [1.0, 0.8, 0.6], "intensity": 2.0},
            {"name": "spot", "type": "spot", "color": [0.6, 0.8, 1.0], "intensity": 6.0,
             "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.5}},
            {"name": "sun", "type": "directional", "intensity": 3.0},
        ]}},
        "scene": 0,
        "scenes": [{"name": "room", "nodes": [0, 1, 2, 3, 5, 6, 7, 8, 9, 10]}],
        "nodes": [
            {"name": "floor", "mesh": 0},
            {"name": "wall", "mesh": 1},
            {"name": "panel", "mesh": 2},
            {"name": "table", "translation": [0.0, 0.1, 0.0], "children": [4]},
            {"name": "box", "mesh": 3, "translation": [-0.6, 0.3, -0.3],
             "rotation": about_y(30), "scale": [0.8, 0.6, 0.8]},
            {"name": "mirrored box", "mesh": 3,
             "matrix": [-0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 0.8, 0.25, 0.4, 1]},
            {"name": "warm light", "translation": [1.2, 1.5, 1.0],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "spot light", "translation": [0.8, 2.2, -0.8], "rotation": about_x(-90),
             "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"name": "sun", "rotation": about_x(-60),
             "extensions": {"KHR_lights_punctual": {"light": 2}}},
            {"name": "main camera", "camera": 0, "translation": [0.0, 1.4, 4.2],
             "rotation": about_x(-10)},
            {"name": "top camera", "camera": 1, "translation": [0.0, 6.0, 0.0],
             "rotation": about_x(-90)},
        ],
        "cameras": [
            {"name": "main", "type": "perspective",
             "perspective": {"yfov": 0.9, "aspectRatio": 4 / 3, "znear": 0.05}},
            {"name": "top", "type": "perspective",
             "perspective": {"yfov": 0.7, "aspectRatio": 1.0, "znear": 0.05}},
        ],
        "meshes": meshes,
        "materials": [
            {"name": "floor", "pbrMetallicRoughness": {
                "baseColorTexture": {"index": 0}, "metallicFactor": 0.0,
                "roughnessFactor": 0.9}},
            {"name": "wall", "pbrMetallicRoughness": {
                "baseColorFactor": [0.7, 0.7, 0.65, 1.0], "metallicFactor": 0.0}},
            {"name": "gold", "pbrMetallicRoughness": {
                "baseColorFactor": [1.0, 0.766, 0.336, 1.0], "metallicFactor": 1.0,
                "roughnessFactor": 0.5}},
            {"name": "panel", "emissiveFactor": [1.0, 0.9, 0.7],
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 3.0}},
             "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0],
                                      "metallicFactor": 0.0}},
        ],
        "textures": [{"sampler": 0, "source": 0}],
        "samplers": [{"wrapS": 10497, "wrapT": 10497}],
        "images": [{"uri": "checker.png"}],
        "buffers": [{"uri": "lit-room.bin", "byteLength": len(buf.data)}],
        "bufferViews": buf.views,
        "accessors": buf.accessors,
    }
    (HERE / "lit-room.gltf").write_text(json.dumps(doc, indent=1) + "\n")


if __name__ == "__main__":
    main()
