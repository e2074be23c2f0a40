"""Mitsuba 3's time to its first sample on a scene exported by `lumagraph export`: what
lumagraph's `first sample at` line is set beside (docs/benchmarks.md, "Time to the first
sample").

    lumagraph export SCENE.ron --out EXPORT
    python mitsuba_first.py EXPORT [--variant llvm_ad_rgb] [--obj MESH.obj]

One process, as a user would run it: import Mitsuba, load the scene (the exported OBJ and
PNG files, mapped onto plugins by scripts/references/make.py as in the reference suite),
then render 1 sample per pixel and wait for it (the kernels' compilation, from Dr.Jit's
kernel cache where an earlier run left them). `--obj` has Mitsuba read the scene's one mesh
from the OBJ file the scene file names rather than from the export (which writes every
triangle's corners in full: a file 4 times the size, 8 s of loading for 1.3 M triangles),
so that both renderers parse the same file. Prints one JSON line: `import_s`, `load_s`
(loading), `first_s` (compiling and rendering the 1-spp image) and `total_s` (from the
interpreter's start, as `time.perf_counter` measures it, to the image).
"""
import argparse
import json
import os
import sys
import time

T0 = time.perf_counter()
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "references"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("export_dir")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--obj", help="the OBJ file the scene's one mesh is read from")
    a = ap.parse_args()
    import mitsuba as mi
    mi.set_variant(a.variant)
    import drjit as dr
    import make
    imported = time.perf_counter()
    d, _, _ = make.mitsuba_scene(a.export_dir, 1, 0)
    if a.obj:
        meshes = [v for v in d.values() if isinstance(v, dict) and v.get("type") == "obj"]
        if len(meshes) != 1:
            sys.exit("--obj: the scene has %d meshes, not one" % len(meshes))
        meshes[0]["filename"] = os.path.abspath(a.obj)
    t = time.perf_counter()
    scene = mi.load_dict(d)
    loaded = time.perf_counter()
    img = mi.render(scene, spp=1, seed=0)
    dr.eval(img)
    dr.sync_thread()
    done = time.perf_counter()
    print(json.dumps({"renderer": "mitsuba %s %s" % (mi.__version__, a.variant), "import_s": imported - T0,
                      "load_s": loaded - t, "first_s": done - loaded, "total_s": done - T0}))


if __name__ == "__main__":
    main()
