# The mesh benchmark scene and its Mitsuba 3 timing (--variant, --width, --height switches for GPU variants and larger images).
"""A mesh benchmark scene and its Mitsuba 3 timing, for side-by-side paths/s on one machine.

    python mesh_env.py make blob.obj             # 81 920-triangle displaced sphere, vertex normals
    python mesh_env.py make blob.obj --level 8   # 20 * 4^level triangles (3: 1 280 ... 8: 1 310 720)
    python mesh_env.py mitsuba blob.obj [--spp 64] [--runs 3]

The scene (assets/bench/mesh_env.ron; docs/benchmarks.md): the blob, diffuse 0.8 grey, centred at (0, 1, 0) with radius
about 1, on a diffuse 0.5 grey ground square of half-size 5 in y = 0, lit only by
assets/hdri/venice_sunset_1k.hdr (scale 1, Mitsuba orientation: the image's centre column
faces +z, u = 0.25 faces +x); camera at (-3.6, 2.0, -3.0) looking at (0, 0.9, 0), up +y,
vertical fov 35 degrees, 256 x 256, box filter; path depth 20 bounces (Mitsuba max_depth 21,
rr_depth 5). `mitsuba` prints one JSON line: paths per second of the best of `--runs` timed
renders after an untimed warm-up (kernel compilation), Mitsuba's llvm_ad_rgb variant.
Needs `pip install mitsuba==3.9.1` and, on Debian bookworm, `apt-get install libllvm19`.
"""
import argparse
import json
import math
import os
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def make(path, level=6):
    t = (1 + 5 ** 0.5) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
             (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in verts]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5),
             (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        cache, nf = {}, []

        def mid(a, b):
            k = (min(a, b), max(a, b))
            if k not in cache:
                m = [(verts[a][i] + verts[b][i]) / 2 for i in range(3)]
                n = math.sqrt(sum(x * x for x in m))
                verts.append(tuple(x / n for x in m))
                cache[k] = len(verts) - 1
            return cache[k]

        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = nf

    def radius(v):
        x, y, z = v
        return 1 + 0.12 * math.sin(7 * x + 1.3) * math.sin(6 * y + 0.7) * math.sin(8 * z + 2.1) \
            + 0.05 * math.sin(23 * x * y + 17 * z)

    pos = [tuple(c * radius(v) + o for c, o in zip(v, (0, 1, 0))) for v in verts]
    normals = [[0.0, 0.0, 0.0] for _ in pos]
    for a, b, c in faces:
        e1 = [pos[b][i] - pos[a][i] for i in range(3)]
        e2 = [pos[c][i] - pos[a][i] for i in range(3)]
        n = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
        for i in (a, b, c):
            for k in range(3):
                normals[i][k] += n[k]
    with open(path, "w") as f:
        f.write("# displaced icosphere, %d triangles (mesh_env.py make)\n" % len(faces))
        for p in pos:
            f.write("v %.6f %.6f %.6f\n" % p)
        for n in normals:
            length = math.sqrt(sum(x * x for x in n)) or 1.0
            f.write("vn %.6f %.6f %.6f\n" % tuple(x / length for x in n))
        for a, b, c in faces:
            f.write("f %d//%d %d//%d %d//%d\n" % (a + 1, a + 1, b + 1, b + 1, c + 1, c + 1))
    print("wrote %s: %d vertices, %d triangles" % (path, len(pos), len(faces)))


def mitsuba(obj, spp, runs, variant="llvm_ad_rgb", width=256, height=256):
    import mitsuba as mi
    mi.set_variant(variant)
    import drjit as dr
    T = mi.ScalarTransform4f
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 21, "rr_depth": 5},
        "sensor": {"type": "perspective", "fov": 35, "fov_axis": "y",
                   "to_world": T().look_at(origin=[-3.6, 2.0, -3.0], target=[0, 0.9, 0], up=[0, 1, 0]),
                   "sampler": {"type": "independent", "sample_count": spp},
                   "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"}}},
        "blob": {"type": "obj", "filename": os.path.abspath(obj), "face_normals": False,
                 "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.8, 0.8]}}},
        "ground": {"type": "rectangle", "to_world": T([[5, 0, 0, 0], [0, 0, 5, 0], [0, -5, 0, 0], [0, 0, 0, 1]]),
                   "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}}},
        "env": {"type": "envmap", "filename": os.path.join(HERE, "..", "..", "assets", "hdri", "venice_sunset_1k.hdr")},
    })

    def once(seed):
        t = time.perf_counter()
        img = mi.render(scene, spp=spp, seed=seed)
        dr.eval(img)
        dr.sync_thread()
        return time.perf_counter() - t

    once(0)
    best = min(once(1 + r) for r in range(runs))
    print(json.dumps({"renderer": "mitsuba %s %s" % (mi.__version__, variant), "width": width, "height": height, "spp": spp,
                      "seconds": best, "paths_per_s": width * height * spp / best}))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("cmd", choices=["make", "mitsuba"])
    ap.add_argument("obj")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--width", type=int, default=256)
    ap.add_argument("--height", type=int, default=256)
    ap.add_argument("--level", type=int, default=6, help="subdivisions of the icosahedron (make)")
    a = ap.parse_args()
    make(a.obj, a.level) if a.cmd == "make" else mitsuba(a.obj, a.spp, a.runs, a.variant, a.width, a.height)


if __name__ == "__main__":
    main()
