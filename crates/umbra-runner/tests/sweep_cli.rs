//! `umbra sweep` end to end on the reference: a small spot-light scene (no frustum axis), one
//! timed render per point. Checks the outputs exist, hold every technique, and that the front
//! and the plots are there; the numbers themselves are the sweep's business, not a test's.

mod common;

use std::process::Command;

#[test]
fn sweep_writes_csv_plots_and_report() {
    let dir = common::scratch("sweep");
    let case = dir.join("small.json");
    std::fs::write(
        &case,
        r#"{ "name": "small", "about": "a small scene for the sweep test",
            "scene": { "objects": [ { "plane": { "point": [0, 0, 0], "half_extent": 4 } },
                                    { "box": { "center": [0, 1, 0], "size": [1, 2, 1] } } ] },
            "camera": { "eye": [0, 6, 6], "target": [0, 0, 0], "size": [48, 48] },
            "light": { "spot": { "position": [3, 8, 2], "target": [0, 0, 0], "fov_y_deg": 50 } },
            "shadow": { "size": [512, 512], "bias": { "polygon_offset": [2.0, 4.0] } } }"#,
    )
    .expect("case");
    let out = dir.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args(["sweep", "--backend", "ref", "--repeat", "1", "--scene"])
        .arg(&case)
        .arg("--out")
        .arg(&out)
        // Its own cache, not target/umbra/cache/judge under the crate's directory (the
        // test's working directory).
        .arg("--judge-cache")
        .arg(dir.join("cache"))
        .output()
        .expect("run umbra sweep");
    let text = common::text(&o);
    assert!(o.status.success(), "{text}");
    assert!(
        text.contains("34 points measured, 0 skipped, 0 errors"),
        "{text}"
    );
    let csv = std::fs::read_to_string(out.join("sweep.csv")).expect("sweep.csv");
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 34, "{csv}");
    assert!(
        rows.iter()
            .all(|r| r.starts_with("ref,") && r.contains(",ok,"))
    );
    assert!(
        rows.iter()
            .any(|r| r.contains(",4096,") && r.contains(",pcf5,"))
    );
    assert!(
        rows.iter().any(|r| r.ends_with("true,")),
        "no point on the front"
    );
    let png = std::fs::read(out.join("pareto.png")).expect("pareto.png");
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let svg = std::fs::read_to_string(out.join("pareto.svg")).expect("pareto.svg");
    assert!(svg.contains("<svg") && svg.contains("ref (front)"));
    let html = std::fs::read_to_string(out.join("report.html")).expect("report.html");
    assert!(html.contains("Pareto front per backend"));
}

#[test]
fn sweep_refuses_an_unknown_backend() {
    let o = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args(["sweep", "--backend", "gl99/nothing"])
        .output()
        .expect("run umbra sweep");
    // Could not run: 125, as every command says it (issue 36 closed the class).
    assert_eq!(o.status.code(), Some(125));
    assert!(common::text(&o).contains("unknown backend"));
}
