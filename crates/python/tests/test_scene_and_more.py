"""Scene edits, checkpoints, converge and images for Jupyter, from Python.

Run by `bash scripts/python.sh test` (and `bash scripts/test.sh`), which sets LUMAGRAPH_BIN
to the command line built from the same checkout."""

import csv
import shutil
import subprocess

import numpy as np
import pytest

import lumagraph as lg

from common import GRAPH, ROOT, SCENE, cli


def test_scene_values_read_and_set_by_path():
    sc = lg.Scene.load(str(SCENE))
    assert sc.fields() == ["camera", "materials", "environment", "render"]
    assert sc.materials == ["green", "red", "white"]
    assert sc.get("camera.fov_y") == pytest.approx(39.3077)
    assert sc.get("camera.position") == (0.0, 0.0, 3.9)
    assert sc.get("render.width") == 256
    assert sc.get("camera.focus_distance") is None
    assert sc.get("camera").startswith("Perspective(")
    sc.set("camera.fov_y", 30)
    sc.set("materials.red.base_color", (0.1, 0.1, 0.8))
    sc.set("materials.red.base_color", np.array([0.1, 0.1, 0.7]))
    sc.set("environment", "Constant((0.2, 0.2, 0.2))")
    sc.set("materials.gold", "(metallic: 1, roughness: 0.2)")
    sc.set("materials.gold.conductor", "Au")  # a plain string is quoted
    assert sc.get("camera.fov_y") == 30.0
    assert sc.get("materials.red.base_color") == pytest.approx((0.1, 0.1, 0.7))
    assert sc.get("materials.gold.conductor") == "Au"
    for path, value, says in [
        ("camera.fov", 1, "no field `fov`"),
        ("render.width", "wide", "does not fit"),
        ("materials.blue.roughness", 0.5, 'no material "blue"'),
        ("shapes", "[]", "not edited by path"),
    ]:
        with pytest.raises(lg.LumagraphError, match=says):
            sc.set(path, value)


def test_an_edited_scene_saves_with_its_comments(tmp_path):
    sc = lg.Scene.load(str(SCENE))
    sc.set("render.spp", 64)
    text = sc.to_ron()
    original = SCENE.read_text()
    assert "spp: 64" in text
    # Every comment line of the file is still there.
    comments = [line for line in original.splitlines() if line.strip().startswith("//")]
    assert comments and all(c in text for c in comments)
    sc.save(str(tmp_path / "edited.ron"))
    assert (tmp_path / "edited.ron").read_text() == text
    assert SCENE.read_text() == original


def test_a_session_renders_an_edited_scene_as_the_cli_renders_the_edited_file(tmp_path):
    # The edited file goes beside the original so that its relative paths still hold.
    work = tmp_path / "assets"
    shutil.copytree(ROOT / "assets", work, ignore=shutil.ignore_patterns("*.exr", "*.hdr"))
    sc = lg.Scene.load(str(work / "cornell.ron"))
    s = lg.Session(str(GRAPH), sc, out=str(tmp_path / "python"), write_outputs=True)
    s.render(4)
    edited = s.scene
    edited.set("camera.position", (0.3, 0.1, 3.6))
    assert s.set_scene(edited) == "camera"
    assert s.spp == 0
    edited.set("materials.red.base_color", (0.1, 0.1, 0.8))
    assert s.set_scene(edited) == "scene"
    assert s.set_scene(edited) is None
    s.render(8)
    edited.save(str(work / "edited.ron"))
    subprocess.run(
        [cli(), "render", str(GRAPH), "--scene", str(work / "edited.ron"), "--spp", "8",
         "--out", str(tmp_path / "cli")],
        check=True, cwd=ROOT, capture_output=True,
    )
    for name in ["render.exr", "render.png"]:
        a = (tmp_path / "cli" / name).read_bytes()
        b = (tmp_path / "python" / name).read_bytes()
        assert a == b, name


def test_a_checkpoint_resumes_to_the_uninterrupted_render(tmp_path):
    ck = str(tmp_path / "at8.checkpoint")
    first = lg.Session(str(GRAPH), str(SCENE))
    first.render(8)
    first.checkpoint(ck)
    straight = lg.Session(str(GRAPH), str(SCENE)).render(16)
    resumed = lg.Session(str(GRAPH), str(SCENE))
    resumed.resume(ck)
    assert resumed.spp == 8
    images = resumed.render(16)
    assert np.array_equal(images["exr"], straight["exr"])
    other = lg.Session(str(GRAPH), str(ROOT / "assets" / "cornell_spheres.ron"))
    with pytest.raises(lg.LumagraphError, match="at8.checkpoint"):
        other.resume(ck)


def test_converge_returns_the_table_the_cli_writes(tmp_path):
    rows = lg.converge(str(GRAPH), str(SCENE), reference_spp=32, seconds=1.0,
                       out=str(tmp_path))
    assert rows and {r["output"] for r in rows} == {"accumulate"}
    spp = [r["spp"] for r in rows]
    assert spp[:3] == [1, 2, 4] and spp == sorted(spp)
    assert rows[-1]["relmse"] < rows[0]["relmse"]
    with open(tmp_path / "converge.csv") as f:
        written = list(csv.DictReader(f))
    assert [int(r["spp"]) for r in written] == spp
    for ours, theirs in zip(rows, written):
        assert float(theirs["relmse"]) == pytest.approx(ours["relmse"], rel=1e-5)
    with pytest.raises(lg.LumagraphError, match="reference"):
        lg.converge(str(GRAPH), str(SCENE))


def png_size(data):
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


def test_images_show_in_jupyter_as_png(tmp_path):
    s = lg.Session(str(GRAPH), str(SCENE), out=str(tmp_path), write_outputs=True)
    s.render(4)
    # The session shows its first output (the PNG of the graph) as that file holds it.
    shown = s._repr_png_()
    assert png_size(shown) == (256, 256)
    assert shown == (tmp_path / "render.png").read_bytes()
    img = s.image("exr")
    assert png_size(img._repr_png_()) == (256, 256)
    assert img.array.shape == (256, 256, 4)
    # A linear array: sRGB-encoded and clipped for display only.
    a = np.zeros((2, 3, 3), np.float32)
    a[0, 0] = (0.5, 2.0, -1.0)
    im = lg.Image(a)
    assert png_size(im._repr_png_()) == (3, 2)
    assert im.array[0, 0, 1] == 2.0 and im.array[0, 0, 3] == 1.0
    with pytest.raises(lg.LumagraphError, match="shape"):
        lg.Image(np.zeros((4, 4), np.float32))


def test_a_graph_loaded_edited_and_saved_keeps_its_comments(tmp_path):
    g = lg.Graph.load(str(GRAPH))
    g.add_node("Blur", "soften", sigma=2.0)
    g.connect("tonemap.color", "soften.color")
    out = tmp_path / "edited.ron"
    g.save(str(out))
    text = out.read_text()
    original = GRAPH.read_text()
    comments = [line for line in original.splitlines() if line.strip().startswith("//")]
    assert comments and all(c in text for c in comments)
    assert '(id: "soften", kind: "Blur"' in text
    again = lg.Graph.load(str(out))
    assert again.nodes[-1] == "soften"
