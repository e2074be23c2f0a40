//! PLY import (`Mesh(path: "….ply")`): ASCII and binary files of either byte order give the
//! same triangles, with their normals and vertex colours; polygons are fanned; what is not
//! read is named in a warning; broken files are one error naming the file and what is wrong.

use crate::common;

use std::path::Path;

use glam::{Mat4, Vec3};
use lumagraph::scene::import::{ImportedMesh, import_mesh};

fn import(dir: &Path, name: &str, bytes: &[u8]) -> Result<ImportedMesh, String> {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    import_mesh(&path, Mat4::IDENTITY).map_err(|e| e.to_string())
}

/// The quad and the triangle make three triangles, the quad fanned about its first corner;
/// every corner keeps its position, normal and colour (bytes as written, alpha 255); the
/// three encodings give the same triangles bit for bit; the unread `confidence` property and
/// `edge` element are named; one default material.
#[test]
fn ascii_and_binary_plys_give_the_same_triangles() {
    let dir = tempfile::tempdir().unwrap();
    let ascii = import(dir.path(), "a.ply", &common::ply_bytes("ascii")).unwrap();
    assert_eq!(ascii.triangles.len(), 3);
    assert_eq!(ascii.materials.len(), 1);
    let t = &ascii.triangles;
    assert_eq!(
        t[0].positions,
        [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)]
    );
    assert_eq!(
        t[1].positions,
        [
            Vec3::ZERO,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.5)
        ]
    );
    assert_eq!(t[2].positions, t[1].positions);
    let n = t[1].normals.expect("normals kept");
    assert!((n[2] - Vec3::new(0.0, 0.6, 0.8)).length() < 1e-6, "{n:?}");
    assert_eq!(
        t[0].colors,
        Some([[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255]])
    );
    let warnings = ascii.report.warnings.join("\n");
    assert!(warnings.contains("confidence"), "{warnings}");
    assert!(warnings.contains("\"edge\""), "{warnings}");
    for format in ["binary_little_endian", "binary_big_endian"] {
        let binary = import(dir.path(), "b.ply", &common::ply_bytes(format)).unwrap();
        assert_eq!(binary.triangles.len(), 3, "{format}");
        for (a, b) in ascii.triangles.iter().zip(&binary.triangles) {
            assert_eq!(a.positions, b.positions, "{format}");
            assert_eq!(a.normals, b.normals, "{format}");
            assert_eq!(a.colors, b.colors, "{format}");
        }
    }
}

/// Broken files: each is one error naming the file and what is wrong, never a panic.
#[test]
fn broken_plys_are_named_errors() {
    let dir = tempfile::tempdir().unwrap();
    let good = String::from_utf8(common::ply_bytes("ascii")).unwrap();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("not a PLY", b"hello\n".to_vec(), "header"),
        (
            "an index past the vertices",
            good.replacen("3 0 2 3", "3 0 2 9", 1).into_bytes(),
            "face 1: vertex index 9 refers to no vertex (the file has 4)",
        ),
        (
            "a negative index",
            good.replacen("3 0 2 3", "3 0 -2 3", 1).into_bytes(),
            "face 1: vertex index -2",
        ),
        (
            "no vertex element",
            b"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"
                .to_vec(),
            "no \"vertex\" element",
        ),
        (
            "vertices without z",
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n"
                .to_vec(),
            "no x, y and z",
        ),
        (
            "a truncated binary file",
            {
                let mut b = common::ply_bytes("binary_little_endian");
                b.truncate(b.len() - 30);
                b
            },
            "element",
        ),
    ];
    for (what, bytes, expected) in cases {
        let err = import(dir.path(), "broken.ply", &bytes).expect_err(what);
        println!("{what}: {err}");
        assert!(
            err.contains("broken.ply"),
            "{what}: the file is not named: {err}"
        );
        assert!(err.contains(expected), "{what}: {err}");
    }
}
