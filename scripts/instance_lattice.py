#!/usr/bin/env python3
"""Writes a scene of many instances of one large mesh, for measuring instancing.

    scripts/instance_lattice.py OUT_DIR [--side N] [--count K] [--instancing Auto|On|Off]

OUT_DIR/wavy.ply is a wavy square of 2 N^2 triangles (N = 224: 100 352), and
OUT_DIR/lattice.ron places it K times (default 1000) on a 10-wide lattice, each turned
about y, under a constant sky: the scene of docs/benchmarks.md's "Instances" figures.
Render it with `lumagraph render graphs/pathtrace.ron --scene OUT_DIR/lattice.ron`.
No dependencies beyond Python 3.
"""
import argparse
import math
import os
import struct


def wavy_ply(n):
    head = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {(n + 1) ** 2}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {2 * n * n}\nproperty list uchar int vertex_indices\nend_header\n"
    ).encode()
    verts = bytearray()
    for j in range(n + 1):
        for i in range(n + 1):
            x, y = i / n - 0.5, j / n - 0.5
            z = 0.05 * math.sin(12.0 * x) * math.cos(9.0 * y)
            verts += struct.pack("<3f", x, y, z)
    faces = bytearray()
    at = lambda i, j: j * (n + 1) + i
    for j in range(n):
        for i in range(n):
            faces += struct.pack("<B3i", 3, at(i, j), at(i + 1, j), at(i + 1, j + 1))
            faces += struct.pack("<B3i", 3, at(i, j), at(i + 1, j + 1), at(i, j + 1))
    return head + bytes(verts) + bytes(faces)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("out")
    p.add_argument("--side", type=int, default=224)
    p.add_argument("--count", type=int, default=1000)
    p.add_argument("--instancing", default="Auto", choices=["Auto", "On", "Off"])
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "wavy.ply"), "wb") as f:
        f.write(wavy_ply(a.side))
    places = []
    for k in range(a.count):
        x, y, z = k % 10, (k // 10) % 10, k // 100
        places.append(
            f"(translate: ({2 * x}, {2 * y}, {-2 * z}), "
            f"rotate: [(axis: (0, 1, 0), degrees: {7 * k})])"
        )
    scene = f"""(
    version: 2,
    camera: Perspective(position: (9, 9, 14), target: (9, 9, -9), up: (0, 1, 0), fov_y: 60),
    materials: {{ "grey": (base_color: (0.6, 0.6, 0.6)) }},
    shapes: [Mesh(path: "wavy.ply", material: "grey", instances: [
        {(", " + chr(10) + "        ").join(places)}
    ])],
    environment: Constant((1, 1, 1)),
    render: (width: 512, height: 512, max_bounces: 8, spp: 64),
    instancing: {a.instancing},
)
"""
    with open(os.path.join(a.out, "lattice.ron"), "w") as f:
        f.write(scene)
    print(f"wrote {a.out}/wavy.ply ({2 * a.side * a.side} triangles) and "
          f"{a.out}/lattice.ron ({a.count} instances)")


if __name__ == "__main__":
    main()
