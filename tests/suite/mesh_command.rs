//! `aerial mesh`: the report on a small model whose counts are known by
//! construction.

use crate::common;

use std::path::Path;

/// Two objects, each a unit square of two triangles, side by side and
/// sharing the edge x = 1 through duplicated vertices (2 boundary points).
/// The second object's UVs run backwards in u (mirrored), and a third
/// object holds one triangle with all three UVs equal (zero UV area).
fn write_model(path: &Path) {
    let text = "\
o left
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
f 1/1 2/2 3/3
f 1/1 3/3 4/4
o right
v 1 0 0
v 2 0 0
v 2 1 0
v 1 1 0
vt 1 0
vt 0 0
vt 0 1
vt 1 1
f 5/5 6/6 7/7
f 5/5 7/7 8/8
o flat_uv
v 5 0 0
v 6 0 0
v 5 1 0
vt 0.5 0.5
f 9/9 10/9 11/9
";
    std::fs::write(path, text).unwrap();
}

#[test]
fn mesh_reports_counts_known_by_construction() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("m.obj");
    let json = dir.path().join("m.json");
    write_model(&model);
    common::succeed(
        common::aerial()
            .arg("mesh")
            .arg(&model)
            .arg("--json")
            .arg(&json),
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["objects"], 3);
    assert_eq!(report["triangles"], 5);
    assert_eq!(report["corners"], 15);
    // Each square's four corners become four vertices; the flat-UV
    // triangle three.
    assert_eq!(report["vertices"], 11);
    assert_eq!(report["welded_boundary_points"], 2);
    assert_eq!(report["mirrored_triangles"], 2);
    // The flat-UV triangle has zero UV area; none has zero area, and every
    // object has texture coordinates.
    assert_eq!(report["zero_uv_area_triangles"], 1);
    assert_eq!(report["collapsed_triangles"], 0);
    assert_eq!(report["triangles_without_uvs"], 0);
    assert_eq!(report["non_finite_attributes"], 0);
    assert!(report["max_orthonormality_error"].as_f64().unwrap() < 1e-5);
    for stage in ["load", "smoothing", "tangents"] {
        for kind in ["seconds", "cpu_seconds"] {
            let s = report[kind][stage].as_f64().unwrap();
            assert!((0.0..10.0).contains(&s), "{kind} {stage}: {s}");
        }
    }

    // A missing file and a bad option are errors (exit 2) naming the cause.
    for (args, needle) in [
        (
            vec![dir.path().join("none.obj").display().to_string()],
            "none.obj",
        ),
        (
            vec![model.display().to_string(), "--crease".into(), "200".into()],
            "--crease",
        ),
    ] {
        let out = common::aerial().arg("mesh").args(&args).output().unwrap();
        assert_eq!(out.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&out.stderr).contains(needle));
    }
}

/// Endless inputs stop at the memory budget with a message naming the
/// file: `/dev/zero` as the model is refused (exit 2), as its MTL library
/// a warning (the default material), an error under `--strict`.
#[test]
fn mesh_reads_of_endless_inputs_stop_at_the_budget() {
    let out = common::aerial()
        .args(["mesh", "/dev/zero"])
        .env("AERIAL_MEMORY_BUDGET", "64M")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("/dev/zero") && stderr.contains("memory budget"),
        "{stderr}"
    );

    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("m.obj");
    std::fs::write(
        &model,
        "mtllib zero.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("zero.mtl")).unwrap();
    for (strict, code) in [(false, 0), (true, 2)] {
        let mut command = common::aerial();
        command
            .arg("mesh")
            .arg(&model)
            .env("AERIAL_MEMORY_BUDGET", "64M");
        if strict {
            command.arg("--strict");
        }
        let out = command.output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{stderr}");
        assert!(
            stderr.contains("zero.mtl") && stderr.contains("memory budget"),
            "{stderr}"
        );
    }
}

/// A model without texture coordinates is not "degenerate": its triangles
/// are counted as without UVs, none as of zero UV area; triangles of zero
/// area (collapsed, left out) and of zero UV area are counted apart, each
/// only for what it is. Before, every triangle of a model without UVs was
/// reported as degenerate (69,666 on the Stanford bunny).
#[test]
fn mesh_counts_zero_area_zero_uv_area_and_missing_uvs_apart() {
    let dir = tempfile::tempdir().unwrap();
    let report = |name: &str, text: &str| -> (serde_json::Value, String) {
        let model = dir.path().join(format!("{name}.obj"));
        let json = dir.path().join(format!("{name}.json"));
        std::fs::write(&model, text).unwrap();
        let out = common::succeed(
            common::aerial()
                .arg("mesh")
                .arg(&model)
                .arg("--json")
                .arg(&json),
        );
        let report = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        (report, String::from_utf8_lossy(&out.stdout).into_owned())
    };
    let counts = |r: &serde_json::Value| {
        [
            "collapsed_triangles",
            "zero_uv_area_triangles",
            "triangles_without_uvs",
        ]
        .map(|k| r[k].as_u64().unwrap())
    };
    // A tetrahedron without UVs (or normals): nothing wrong with it.
    let tetrahedron = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    let (r, stdout) = report("no_uvs", tetrahedron);
    assert_eq!(counts(&r), [0, 0, 4]);
    assert!(stdout.contains("triangles without UVs      4"), "{stdout}");
    assert!(!stdout.contains("degenerate"), "{stdout}");
    // With normals but no UVs, and a polygon split into triangles: the same.
    let (r, _) = report(
        "normals_no_uvs",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n",
    );
    assert_eq!(counts(&r), [0, 0, 2]);
    // A collapsed triangle (three points on a line) among good ones, with
    // UVs: zero area, and not also counted as zero UV area.
    let (r, _) = report(
        "collapsed",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
         f 1/1 2/2 3/3\nf 1/1 2/2 4/3\n",
    );
    assert_eq!(counts(&r), [1, 0, 0]);
    // UVs all equal on one triangle, spread on the other.
    let (r, _) = report(
        "flat_uvs",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0.5 0.5\nvt 1 0\nvt 0 1\nvt 1 1\n\
         f 1/1 2/1 3/1\nf 2/2 4/4 3/3\n",
    );
    assert_eq!(counts(&r), [0, 1, 0]);
}
