"""The Python package against the command line: the same files for the same graph, scene
and spp; arrays of the scene's size in float32; a param change that re-runs only what is
downstream of it; errors that name the file and line.

Run by `bash scripts/python.sh test` (and `bash scripts/test.sh`), which sets LUMAGRAPH_BIN
to the command line built from the same checkout."""

import os
import subprocess

import numpy as np
import pytest

import lumagraph as lg

from common import GRAPH, ROOT, SCENE, cli


def test_a_render_from_python_is_byte_identical_to_the_cli(tmp_path):
    theirs, ours = tmp_path / "cli", tmp_path / "python"
    subprocess.run(
        [cli(), "render", str(GRAPH), "--scene", str(SCENE), "--spp", "16", "--out", str(theirs)],
        check=True, cwd=ROOT, capture_output=True,
    )
    s = lg.Session(str(GRAPH), str(SCENE), out=str(ours), write_outputs=True)
    s.render(16)
    assert s.spp == 16
    for name in ["render.exr", "render.png"]:
        assert (theirs / name).read_bytes() == (ours / name).read_bytes(), name


def test_outputs_are_float32_arrays_of_the_scenes_size(tmp_path):
    s = lg.Session(str(GRAPH), str(SCENE), out=str(tmp_path), keep=["pathtrace.color"])
    images = s.render(8)
    assert sorted(images) == ["exr", "png"]
    for name, a in images.items():
        assert a.shape == (256, 256, 4), name
        assert a.dtype == np.float32, name
        assert np.isfinite(a).all() and a[..., :3].mean() > 0.01, name
    # Nothing written unless asked.
    assert not any(tmp_path.iterdir())
    raw = s.read("pathtrace.color")
    assert raw.shape == (256, 256, 4) and raw.dtype == np.float32
    with pytest.raises(lg.LumagraphError, match="pathtrace.albedo"):
        s.read("pathtrace.albedo")


def test_a_param_change_reruns_only_what_is_downstream(tmp_path):
    s = lg.Session(str(GRAPH), str(SCENE), out=str(tmp_path))
    before = s.render(8)
    hdr = s.read("accumulate.color")
    ran = s.set_param("exposure.ev", "1.0")
    assert ran == ["exposure", "tonemap", "png"]
    np.testing.assert_array_equal(s.read("accumulate.color"), hdr)
    after = s.read("tonemap.color")
    assert after[..., 1].sum() > 1.2 * before["png"][..., 1].sum()
    with pytest.raises(lg.LumagraphError, match="nope"):
        s.set_param("exposure.nope", "1")


def test_a_bad_graph_raises_an_error_naming_file_and_line(tmp_path):
    bad = tmp_path / "broken.ron"
    bad.write_text('(\n    version: 1,\n    nodes: [\n        (id: "a" kind: "Tonemap"),\n    ],\n)\n')
    with pytest.raises(lg.LumagraphError, match=r"broken\.ron:4:"):
        lg.Session(str(bad))


def test_a_graph_built_in_code_saves_a_file_the_cli_renders_identically(tmp_path):
    g = lg.Graph()
    g.add_node("PathTrace", "pathtrace", samples_per_frame=4)
    g.add_node("Accumulate", "accumulate")
    g.add_node("Exposure", "exposure", ev=0.5)
    g.add_node("Tonemap", "tonemap", operator="aces")
    g.add_node("Output", "png", path="render.png")
    g.add_node("Output", "exr", path="render.exr")
    for a, b in [
        ("pathtrace.color", "accumulate.color"),
        ("accumulate.color", "exposure.color"),
        ("exposure.color", "tonemap.color"),
        ("tonemap.color", "png.color"),
        ("accumulate.color", "exr.color"),
    ]:
        g.connect(a, b)
    assert g.nodes == ["pathtrace", "accumulate", "exposure", "tonemap", "png", "exr"]
    with pytest.raises(lg.LumagraphError, match="already"):
        g.add_node("Tonemap", "tonemap")
    path = tmp_path / "built.ron"
    g.save(str(path))
    assert lg.Graph.load(str(path)).to_ron() == g.to_ron()
    theirs, ours = tmp_path / "cli", tmp_path / "python"
    subprocess.run(
        [cli(), "render", str(path), "--scene", str(SCENE), "--spp", "8", "--out", str(theirs)],
        check=True, cwd=ROOT, capture_output=True,
    )
    lg.Session(g, str(SCENE), out=str(ours), write_outputs=True).render(8)
    for name in ["render.exr", "render.png"]:
        assert (theirs / name).read_bytes() == (ours / name).read_bytes(), name


def test_the_node_list_has_every_kind_with_its_ports_and_params():
    kinds = {k["kind"]: k for k in lg.nodes()}
    assert {"PathTrace", "Accumulate", "Tonemap", "Output", "Difference"} <= set(kinds)
    tonemap = kinds["Tonemap"]
    assert [p["name"] for p in tonemap["inputs"]] == ["color"]
    assert any(p["name"] == "operator" and p["default"] == "aces" for p in tonemap["params"])
    assert all(k["doc"] for k in kinds.values())


def test_measurements_and_timings_after_a_render(tmp_path):
    # A Difference node measures the accumulation against the raw frame.
    g = lg.Graph()
    g.add_node("PathTrace", "pathtrace", samples_per_frame=4)
    g.add_node("Accumulate", "accumulate")
    g.add_node("Difference", "diff", metric="relmse")
    g.add_node("Output", "out", path="diff.png")
    g.connect("pathtrace.color", "accumulate.color")
    g.connect("accumulate.color", "diff.color")
    g.connect("pathtrace.color", "diff.reference")
    g.connect("diff.heat", "out.color")
    s = lg.Session(g, str(SCENE), out=str(tmp_path))
    s.render(8)
    m = s.measurements
    assert list(m) == ["diff.relmse"], m
    assert m["diff.relmse"] > 0
    t = s.timings
    assert t is None or ("pathtrace" in t and all(v >= 0 for v in t.values())), t


def test_ctrl_c_stops_a_long_render_and_the_session_goes_on(tmp_path):
    import signal
    import time

    s = lg.Session(str(GRAPH), str(SCENE), out=str(tmp_path))
    # Ctrl-C as a terminal sends it: SIGINT from outside, one second in (a thread could not
    # send it: the render holds the interpreter).
    killer = subprocess.Popen(["sh", "-c", f"sleep 1; kill -INT {os.getpid()}"])
    start = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            s.render(1 << 16)  # minutes on lavapipe: stopped long before
    finally:
        killer.wait()
    assert time.monotonic() - start < 30
    stopped_at = s.spp  # the frames run before the stop, 4 samples each
    assert stopped_at % 4 == 0 and stopped_at < 1 << 16
    images = s.render(stopped_at + 8)
    assert images["png"].shape == (256, 256, 4)
    assert s.spp == stopped_at + 8


def test_scene_warnings_are_printed_and_kept(tmp_path, capfd):
    # A glTF triangle whose file uses an extension lumagraph does not read: said, not ignored.
    import base64
    import json
    import struct

    data = struct.pack("<9f", -1, -1, 0, 1, -1, 0, 0, 1, 0)
    gltf = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_materials_anisotropy"],
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
        "bufferViews": [{"buffer": 0, "byteLength": len(data)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [-1, -1, 0], "max": [1, 1, 0]}],
    }
    (tmp_path / "tri.gltf").write_text(json.dumps(gltf))
    scene = tmp_path / "tri.ron"
    scene.write_text(
        "(\n    version: 2,\n"
        "    camera: Perspective(position: (0, 0, 4), target: (0, 0, 0), up: (0, 1, 0), fov_y: 40),\n"
        '    shapes: [Mesh(name: "tri", path: "tri.gltf")],\n'
        "    environment: Constant((1, 1, 1)),\n"
        "    render: (width: 32, height: 32),\n)\n"
    )
    s = lg.Session(str(GRAPH), str(scene), out=str(tmp_path / "out"))
    assert any("KHR_materials_anisotropy" in w for w in s.warnings), s.warnings
    assert "scene warning:" in capfd.readouterr().err
    assert s.render(4)["png"].shape == (32, 32, 4)
