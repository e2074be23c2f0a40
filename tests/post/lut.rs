//! LUT against its CPU reference (`render::nodes::lut::Lut::apply`) on the HDR test chart,
//! both interpolations, with a LUT whose domain cuts through the chart's values; the
//! shipped example LUT; and bad `.cube` files refused with their line.
//!
//! Tolerance per channel: (1e-5 + 4e-7 × (size − 1)) × the largest |entry| + 1e-7: the
//! f32 interpolation (a few roundings of values up to the largest entry) and the f32 grid
//! coordinate, off by ~1e-7 of the grid's size, times a slope of at most about the
//! largest entry per cell. Measured worst printed per case as a fraction of the bound.

use crate::common;

use common::{assert_within, map_pixels, run_node};
use lumagraph::graph::ParamValue;
use lumagraph::render::image_io;
use lumagraph::render::nodes::lut::Lut;

const CHART: &str = "assets/test_chart.exr";

/// A 5³ LUT with a twisted, non-monotone look over the domain [-0.25, 2].
fn twisted_cube() -> String {
    let n = 5;
    let mut s = String::from(
        "# a test LUT\nTITLE \"twisted\"\nLUT_3D_SIZE 5\nDOMAIN_MIN -0.25 -0.25 -0.25\nDOMAIN_MAX 2 2 2\n",
    );
    for b in 0..n {
        for g in 0..n {
            for r in 0..n {
                let (x, y, z) = (f64::from(r) / 4.0, f64::from(g) / 4.0, f64::from(b) / 4.0);
                let v = [
                    (x * 2.0 + 0.3 * y).sin().abs(),
                    0.5 * x + y * y - 0.2 * z,
                    1.5 * z - 0.4 * x * y,
                ];
                s.push_str(&format!("{:.6} {:.6} {:.6}\n", v[0], v[1], v[2]));
            }
        }
    }
    s
}

#[test]
fn lut_matches_cpu() {
    let image = image_io::load(&common::repo(CHART)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let twisted = dir.path().join("twisted.cube");
    std::fs::write(&twisted, twisted_cube()).unwrap();
    let shipped = common::repo("assets/luts/film.cube");
    for path in [twisted.as_path(), shipped.as_path()] {
        let lut = Lut::load(path).unwrap();
        let peak = lut
            .table
            .iter()
            .flatten()
            .fold(0.0_f64, |m, v| m.max(f64::from(v.abs())));
        let bound = (1e-5 + 4e-7 * (lut.size - 1) as f64) * peak + 1e-7;
        for interpolation in ["trilinear", "tetrahedral"] {
            let params = [
                ("path", ParamValue::Str(path.to_str().unwrap().into())),
                ("interpolation", ParamValue::Str(interpolation.into())),
            ];
            let Some(got) = run_node("LUT", &params, &[("color", CHART)]) else {
                return;
            };
            let want = map_pixels(&image, |_, p| {
                let v = lut.apply([p[0], p[1], p[2]], interpolation == "tetrahedral");
                [v[0], v[1], v[2], p[3]]
            });
            let name = path.file_name().unwrap().to_string_lossy();
            assert_within(
                &format!("LUT {name} {interpolation}"),
                &got,
                &want,
                |_, _| bound,
            );
        }
    }
}

/// An identity LUT gives back its input (clamped to the domain), with either interpolation
/// (both are exact on a linear table).
#[test]
fn identity_lut_is_exact_on_the_cpu() {
    let n = 9;
    let mut s = format!("LUT_3D_SIZE {n}\n");
    for b in 0..n {
        for g in 0..n {
            for r in 0..n {
                s.push_str(&format!(
                    "{} {} {}\n",
                    f64::from(r) / 8.0,
                    f64::from(g) / 8.0,
                    f64::from(b) / 8.0
                ));
            }
        }
    }
    let lut = Lut::parse(&s, std::path::Path::new("id.cube")).unwrap();
    for rgb in [[0.1, 0.5, 0.9], [0.33, 0.33, 0.34], [1.5, -0.2, 0.7]] {
        for tetra in [false, true] {
            let v = lut.apply(rgb, tetra);
            for c in 0..3 {
                assert!(
                    (v[c] - rgb[c].clamp(0.0, 1.0)).abs() < 1e-6,
                    "{rgb:?} {tetra}: {v:?}"
                );
            }
        }
    }
}

/// Bad files: each refused with the file and the line, from the parser and from a render.
#[test]
fn bad_cube_files_name_their_line() {
    let p = std::path::Path::new("bad.cube");
    let cases = [
        (
            "LUT_3D_SIZE 2\n0 0 0\n1 0\n",
            "line 3",
            "2 numbers where 3 belong",
        ),
        ("LUT_1D_SIZE 16\n", "line 1", "1D LUTs are not supported"),
        ("0 0 0\n", "line 1", "entries before LUT_3D_SIZE"),
        ("LUT_3D_SIZE 1\n", "line 1", "LUT_3D_SIZE must be 2 to 256"),
        (
            "LUT_3D_SIZE 2\n0 0 0\n",
            "line 2",
            "1 entries; LUT_3D_SIZE 2 needs 8",
        ),
        (
            "LUT_3D_SIZE 2\nLUT_FANCY 3\n",
            "line 2",
            "unknown keyword \"LUT_FANCY\"",
        ),
        (
            "LUT_3D_SIZE 2\n0 0 nan\n",
            "line 2",
            "is not three finite numbers",
        ),
    ];
    for (text, line, what) in cases {
        let e = Lut::parse(text, p).unwrap_err().to_string();
        assert!(
            e.contains("bad.cube") && e.contains(line) && e.contains(what),
            "{text:?}: {e}"
        );
    }
    // Through a render: the error names the node and the file's line; nothing panics.
    let Some(ctx) = common::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.cube");
    std::fs::write(&bad, cases[0].0).unwrap();
    let mut g = lumagraph::graph::Graph::new();
    g.nodes = vec![
        lumagraph::graph::Node::new("in", "ImageInput").with("path", ParamValue::Str(CHART.into())),
        lumagraph::graph::Node::new("look", "LUT")
            .with("path", ParamValue::Str(bad.to_str().unwrap().into())),
    ];
    g.edges = vec![lumagraph::graph::Edge::new("in.color", "look.color")];
    let plan = lumagraph::pathtrace::library::compile(&g, &["look.color".into()], None).unwrap();
    let resources = lumagraph::render::Resources {
        base_dir: common::root(),
        ..Default::default()
    };
    let e = lumagraph::pathtrace::library::executor(ctx, plan, &resources)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("look") && e.contains("bad.cube") && e.contains("line 3"),
        "{e}"
    );
}
