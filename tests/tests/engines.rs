//! The engine peers stay what `cases/engines.md` records (issue 59): a peer case writes one
//! engine's defaults at one release, and that file pins each of its numbers to a line of the
//! release's source. Here every row's value is held to the case's value at the row's field,
//! every number and name under the case's `camera`, `light` and `shadow` must have a row (an
//! engine's line, or `umbra:` and why), each section names its release and commit, and each
//! peer case's `about` names its release. An engine update is then one reviewed change to
//! that file, the case and its goldens; a case edited alone fails here, naming the field.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::Value;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// One row of the pack: a field of a peer case and where its value comes from.
#[derive(Debug)]
struct Row {
    line: usize,
    engine: String,
    case: String,
    field: String,
    value: Value,
    source: String,
}

/// One engine's section: its release line (`release: ENGINE TAG PIN`) and rows.
#[derive(Debug, Default)]
struct Section {
    release: Option<(String, String)>,
    rows: Vec<Row>,
}

/// The pack, by engine (the `## ` heading), every malformed line an error naming it.
fn parse(text: &str) -> Result<BTreeMap<String, Section>, Vec<String>> {
    let mut sections: BTreeMap<String, Section> = BTreeMap::new();
    let mut errors = Vec::new();
    let mut engine: Option<String> = None;
    for (k, line) in text.lines().enumerate() {
        let n = k + 1;
        if let Some(h) = line.strip_prefix("## ") {
            let name = h.trim().to_string();
            // Only an engine's heading opens a section (the prose headings hold no rows).
            engine = (!name.contains(' ')).then_some(name);
            continue;
        }
        let Some(e) = engine.clone() else { continue };
        if let Some(r) = line.strip_prefix("release: ") {
            let words: Vec<&str> = r.split_whitespace().collect();
            match words.as_slice() {
                [name, tag, pin] if *name == e && is_pin(pin) => {
                    sections.entry(e).or_default().release =
                        Some((tag.to_string(), pin.to_string()));
                }
                _ => errors.push(format!(
                    "cases/engines.md:{n}: a release line is `release: {e} TAG PIN`, PIN the 40-digit commit the tag names or `npm:PACKAGE@VERSION#sha1=SHASUM` (the registry's 40-digit shasum of the release's tarball), not `{line}`"
                )),
            }
            continue;
        }
        if !line.starts_with("| ") || line.starts_with("| case ") || line.starts_with("|---") {
            continue;
        }
        let cells: Vec<&str> = line
            .trim_matches('|')
            .split(" | ")
            .map(|c| c.trim())
            .collect();
        if cells.len() != 5 {
            errors.push(format!(
                "cases/engines.md:{n}: a row has 5 cells (case, field, value, source, how), this one {}",
                cells.len()
            ));
            continue;
        }
        let literal = cells[2].trim_matches('`');
        let value = match serde_json::from_str::<Value>(literal) {
            Ok(v) => v,
            Err(err) => {
                errors.push(format!(
                    "cases/engines.md:{n}: value `{literal}` is not JSON ({err}); write it as the case does, strings quoted"
                ));
                continue;
            }
        };
        let source = cells[3].to_string();
        if !source.starts_with("umbra:") && !is_path_line(&source) {
            errors.push(format!(
                "cases/engines.md:{n}: source `{source}` is neither PATH:LINE in the release's tree nor `umbra:` with a reason"
            ));
        }
        sections.entry(e.clone()).or_default().rows.push(Row {
            line: n,
            engine: e,
            case: cells[0].to_string(),
            field: cells[1].to_string(),
            value,
            source,
        });
    }
    if errors.is_empty() {
        Ok(sections)
    } else {
        Err(errors)
    }
}

/// What pins a release's tree: the 40-digit git commit its tag names, or, where the tree was
/// read from a package registry's tarball (three.js's npm package: its repository is too
/// large to fetch here), `npm:PACKAGE@VERSION#sha1=SHASUM` with the registry's shasum.
fn is_pin(pin: &str) -> bool {
    let hex40 = |h: &str| h.len() == 40 && h.chars().all(|c| c.is_ascii_hexdigit());
    match pin.strip_prefix("npm:") {
        Some(rest) => rest.split_once("#sha1=").is_some_and(|(package, sum)| {
            package.rsplit_once('@').is_some_and(|(name, version)| {
                !name.is_empty() && !version.is_empty() && hex40(sum)
            })
        }),
        None => hex40(pin),
    }
}

/// `path/to/file.ext:LINE`, the line a positive number.
fn is_path_line(s: &str) -> bool {
    s.rsplit_once(':').is_some_and(|(path, line)| {
        path.contains('/')
            && path.contains('.')
            && !path.contains(' ')
            && line.parse::<u32>().is_ok_and(|l| l > 0)
    })
}

/// Every leaf (number, string, bool) under `v`, with its JSON pointer.
fn leaves(v: &Value, at: String, out: &mut Vec<(String, Value)>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                leaves(x, format!("{at}/{k}"), out);
            }
        }
        // Item by item: a row that names the array whole covers them (`drift`'s `named`).
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                leaves(x, format!("{at}/{i}"), out);
            }
        }
        _ => out.push((at, v.clone())),
    }
}

/// Two JSON values as a case means them: numbers by value (`45` is `45.0`), else equal.
fn same(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => x.as_f64() == y.as_f64(),
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| same(p, q))
        }
        _ => a == b,
    }
}

/// What is wrong with the pack against the cases it names, one line each.
fn drift(sections: &BTreeMap<String, Section>, cases: &Path) -> Vec<String> {
    let mut errors = Vec::new();
    let mut by_case: BTreeMap<&str, Vec<&Row>> = BTreeMap::new();
    for (engine, s) in sections {
        if s.release.is_none() {
            errors.push(format!(
                "cases/engines.md: the {engine} section has no `release: {engine} TAG PIN` line"
            ));
        }
        for r in &s.rows {
            by_case.entry(&r.case).or_default().push(r);
        }
    }
    for (case, rows) in by_case {
        let path = cases.join(case);
        let doc: Value = match std::fs::read_to_string(&path)
            .map_err(|e| e.to_string())
            .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()))
        {
            Ok(d) => d,
            Err(e) => {
                errors.push(format!(
                    "cases/engines.md:{}: case {case} cannot be read: {e}",
                    rows[0].line
                ));
                continue;
            }
        };
        for r in &rows {
            match doc.pointer(&r.field) {
                Some(v) if same(v, &r.value) => {}
                Some(v) => errors.push(format!(
                    "cases/{case} {}: the case has {v}, cases/engines.md:{} records {} ({}); change both together, with the source line",
                    r.field, r.line, r.value, r.source
                )),
                None => errors.push(format!(
                    "cases/engines.md:{}: cases/{case} has no field {}",
                    r.line, r.field
                )),
            }
        }
        // Every number and name the engine's shadows are made of has a row: a row may name
        // an array whole (`/camera/eye`) or item by item (`/shadow/size/0`).
        let named = |p: &str| {
            rows.iter().any(|r| {
                r.field == p
                    || p.strip_prefix(r.field.as_str())
                        .is_some_and(|rest| rest.starts_with('/'))
            })
        };
        let mut all = Vec::new();
        for part in ["camera", "light", "shadow"] {
            if let Some(v) = doc.get(part) {
                leaves(v, format!("/{part}"), &mut all);
            }
        }
        for (p, v) in all {
            if !named(&p) {
                errors.push(format!(
                    "cases/{case} {p} = {v} has no row in cases/engines.md: add its source line (or `umbra:` and why umbra chose it)"
                ));
            }
        }
        // The case says which release it is.
        let about = doc.get("about").and_then(Value::as_str).unwrap_or("");
        if let Some(r) = rows.first() {
            if let Some((tag, _)) = sections.get(&r.engine).and_then(|s| s.release.as_ref()) {
                let named = format!("{} {tag}", r.engine);
                if !about.contains(&named) {
                    errors.push(format!(
                        "cases/{case}: its `about` does not name the release it is pinned to, \"{named}\""
                    ));
                }
            }
        }
    }
    errors
}

fn pack() -> BTreeMap<String, Section> {
    let text = std::fs::read_to_string(root().join("cases/engines.md"))
        .expect("cases/engines.md: the engine peers' pack");
    parse(&text).unwrap_or_else(|e| panic!("{}", e.join("\n")))
}

#[test]
fn every_engine_peer_is_what_its_pinned_release_sets() {
    let sections = pack();
    let errors = drift(&sections, &root().join("cases"));
    assert!(errors.is_empty(), "{}", errors.join("\n"));
    // Bevy's peer is in the pack, with its normal bias as Bevy computes it (×√2 in f32).
    let bevy = &sections["Bevy"];
    let bias = bevy
        .rows
        .iter()
        .find(|r| r.field == "/shadow/bias/normal_offset_texels")
        .expect("Bevy's normal bias has a row");
    let expected = 1.8f32 * std::f32::consts::SQRT_2;
    assert_eq!(bias.value.as_f64().map(|v| v as f32), Some(expected));
    // three.js's peer is in the pack, under its current PCF filter.
    let three = &sections["three.js"];
    assert!(
        three
            .rows
            .iter()
            .any(|r| r.field == "/shadow/filter" && r.value == "vogel5"),
        "three.js's filter has a row"
    );
}

/// The check fails where it should: a value changed in the case, a field left without a
/// row, and an `about` that does not name the release, each said with the field.
#[test]
fn a_peer_case_edited_without_the_pack_fails_naming_the_field() {
    let sections = pack();
    let src = root().join("cases/cascades/bevy-sun.json");
    let mut doc: Value =
        serde_json::from_str(&std::fs::read_to_string(&src).expect("bevy-sun")).expect("json");
    let dir = std::env::temp_dir().join(format!("umbra-engines-{}", std::process::id()));
    // Every other peer the pack names, copied as it is.
    let named: std::collections::BTreeSet<&str> = sections
        .values()
        .flat_map(|s| s.rows.iter().map(|r| r.case.as_str()))
        .collect();
    for case in named {
        let to = dir.join(case);
        std::fs::create_dir_all(to.parent().expect("a case's folder")).expect("dir");
        std::fs::copy(root().join("cases").join(case), to).expect("copy");
    }
    let write = |doc: &Value| {
        std::fs::create_dir_all(dir.join("cascades")).expect("dir");
        std::fs::write(
            dir.join("cascades/bevy-sun.json"),
            serde_json::to_string(doc).expect("json"),
        )
        .expect("write");
        drift(&sections, &dir)
    };
    assert!(write(&doc).is_empty(), "the copy is the case");

    doc["shadow"]["bias"]["normal_offset_texels"] = Value::from(1.8);
    let e = write(&doc);
    assert!(
        e.iter()
            .any(|l| l.contains("/shadow/bias/normal_offset_texels")),
        "{e:?}"
    );

    doc["shadow"]["bias"]["normal_offset_texels"] = Value::from(2.5455842);
    doc["shadow"]["compare"] = Value::from("manual");
    let e = write(&doc);
    assert!(
        e.iter()
            .any(|l| l.contains("/shadow/compare") && l.contains("no row")),
        "{e:?}"
    );

    doc["shadow"]
        .as_object_mut()
        .expect("object")
        .remove("compare");
    doc["about"] = Value::from("Bevy's default shadows");
    let e = write(&doc);
    assert!(e.iter().any(|l| l.contains("Bevy v0.19.1")), "{e:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_malformed_pack_line_is_named() {
    let bad = "## Bevy\n\nrelease: Bevy v1 abc\n\n| a.json | /x | `nope | src/x.rs:1 | how |\n| a.json | /y | `1` | somewhere | how |\n";
    let e = parse(bad).expect_err("three bad lines");
    assert_eq!(e.len(), 3, "{e:?}");
    let sum = "face29ee2de9bcc31a1b573a76f224e35e0b2894";
    assert!(is_pin(sum) && is_pin(&format!("npm:three@0.187.0#sha1={sum}")));
    assert!(!is_pin("npm:three@0.187.0") && !is_pin(&format!("npm:three#sha1={sum}")));
    assert!(e[0].contains(":3:") && e[0].contains("release"), "{e:?}");
    assert!(e[1].contains(":5:") && e[1].contains("not JSON"), "{e:?}");
    assert!(e[2].contains(":6:") && e[2].contains("PATH:LINE"), "{e:?}");
}
