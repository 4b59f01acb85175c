//! The discrimination matrix: for every pair of distinct settings of a technique knob the case
//! format expresses, some point of the catalogue, rendered by the reference with one setting,
//! must be *illegal* under the judge of the other (in either direction): its pixels, or where
//! no point separates them by pixels, its shadow map (what the judge reads back on GL 3.3 and
//! wgpu's copyable formats; the table says which). Otherwise a driver
//! that implements one as the other passes the whole catalogue, and the catalogue is blind to
//! that mistake.
//!
//! Each knob lists its values and the cases to try first (the ones built for it); after those,
//! the rest of the catalogue is tried until one separates every pair (bounded, see
//! `MAX_POINTS`). On a point, every value is rendered once plainly and once judged, so all
//! pairs of the knob are settled with 2·n renders. An exception (a pair no catalogue point
//! can separate) needs its reason in `EXCEPTIONS`; an exception that turns out separable is
//! an error too, so the list stays true. Run with `--nocapture` for the table.

use std::collections::BTreeMap;

use rayon::prelude::*;
use serde_json::{Value, json};
use umbra_case::{CasePoint, ClipDepth, Prepared, Profile};

/// How many catalogue points a knob may try beyond its preferred cases.
const MAX_POINTS: usize = 12;

/// One technique knob: the dotted path, its values, and the cases built for it.
struct Knob {
    path: &'static str,
    values: Vec<Value>,
    prefer: &'static [&'static str],
}

fn knobs() -> Vec<Knob> {
    vec![
        Knob {
            path: "shadow.format",
            values: vec![
                json!("unsized"),
                json!("depth16"),
                json!("depth24"),
                json!("depth32f"),
            ],
            prefer: &["contact", "far-clamp", "near-far", "formats"],
        },
        Knob {
            path: "shadow.filter",
            values: vec![
                json!("nearest"),
                json!("linear"),
                json!({"pcf": 2}),
                json!({"pcf": 3}),
                json!({"pcf": 5}),
            ],
            prefer: &["filters-magnified", "filters"],
        },
        Knob {
            path: "shadow.depth_clamp",
            values: vec![json!(false), json!(true)],
            prefer: &["pancake", "near-crossing"],
        },
        Knob {
            path: "shadow.compare",
            values: vec![json!("hardware"), json!("manual")],
            prefer: &["far-clamp", "beyond-far"],
        },
        Knob {
            path: "shadow.bias",
            values: vec![
                json!({}),
                json!({"constant": 0.0002}),
                json!({"constant": 0.0005}),
                json!({"slope": {"scale": 0.0002, "max": 0.01}}),
                json!({"normal_offset": 0.0016}),
                json!({"polygon_offset": [0.5, 0.0]}),
                json!({"polygon_offset": [2.0, 4.0]}),
                json!({"polygon_offset": [0.0, 800.0]}),
                json!({"polygon_offset": [0.0, 1600.0]}),
                json!({"polygon_offset": [4.0, 0.0]}),
                json!({"polygon_offset": [4.0, 0.0], "polygon_offset_clamp": 0.00005}),
                json!({"n_dot_l": {"scale": 0.0011, "min": 0.00005}}),
                json!({"n_dot_l": {"scale": 0.0, "min": 0.00005}}),
            ],
            prefer: &["bias-forms-magnified", "contact", "acne-remedies"],
        },
        Knob {
            path: "shadow.outside",
            values: vec![
                json!("lit"),
                json!("border"),
                json!("clamp_to_edge"),
                json!("repeat"),
            ],
            prefer: &["outside"],
        },
        Knob {
            path: "shadow.guard_behind_light",
            values: vec![json!(true), json!(false)],
            prefer: &["guard-magnified", "behind-spot"],
        },
        Knob {
            path: "shadow.size",
            values: vec![json!([512, 512]), json!([1024, 1024]), json!([1280, 960])],
            prefer: &["filters-magnified", "contact", "resolution"],
        },
        Knob {
            path: "shadow.bias_matrix",
            values: vec![json!("before_divide"), json!("after_divide")],
            prefer: &["bias-matrix", "contact"],
        },
        Knob {
            path: "shadow.depth_order",
            values: vec![json!("forward"), json!("reversed")],
            prefer: &["far-clamp", "near-far", "formats"],
        },
        Knob {
            path: "shadow.cull",
            values: vec![json!("none"), json!("back"), json!("front")],
            prefer: &["acne-cull-front", "contact"],
        },
        Knob {
            path: "shadow.attachments",
            values: vec![json!("depth_only"), json!("with_color")],
            prefer: &["color-attachment"],
        },
        Knob {
            path: "shadow.mipmaps",
            values: vec![
                json!(null),
                json!({"levels": 6}),
                json!({"levels": 6, "filter": "linear"}),
                json!({"levels": 3}),
                json!({"levels": 6, "source": "averaged"}),
                json!({"levels": 6, "filter": "linear", "source": "averaged"}),
            ],
            prefer: &["mip-rendered", "mip-averaged"],
        },
    ]
}

/// Pairs the catalogue cannot separate, on purpose, each with why.
const EXCEPTIONS: &[(&str, &str, &str, &str)] = &[
    (
        "shadow.format",
        "\"unsized\"",
        "\"depth24\"",
        "the reference models DEPTH_COMPONENT with no size as 24 bits; what the driver chose is recorded in drivers.txt",
    ),
    (
        "shadow.bias_matrix",
        "\"before_divide\"",
        "\"after_divide\"",
        "identical in exact arithmetic; the f32 difference lies inside the coordinate's arithmetic freedom (the built-in bias-order twin holds every case on every backend to it)",
    ),
    (
        "shadow.attachments",
        "\"depth_only\"",
        "\"with_color\"",
        "identical by design: a dummy colour attachment must not change depth (the with-color twin demands bit-identical visibility)",
    ),
];

/// Which direction separated a pair, where, and by how much.
struct Separation {
    point: String,
    judged_as: String,
    rendered_as: String,
    /// Illegal pixels (what every API's judge sees).
    illegal: u64,
    /// Illegal shadow-map texels (what the judge sees where the map is read back: GL 3.3
    /// and wgpu's copyable formats); a pair told apart by the map alone is reported so.
    texels: u64,
}

impl Separation {
    fn what(&self) -> String {
        if self.illegal > 0 {
            format!("{} px illegal", self.illegal)
        } else {
            format!("{} map texels illegal (no pixel)", self.texels)
        }
    }
}

#[test]
fn every_pair_of_technique_settings_is_told_apart_by_some_catalogue_point() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut points: Vec<CasePoint> = Vec::new();
    for f in umbra_case::case_files(&root.join("cases")).expect("cases") {
        points.extend(umbra_case::load_file(&f).unwrap_or_else(|e| panic!("{e}")));
    }
    // The knobs are independent, so they are settled side by side (the test's wall time on 2
    // cores: one knob's renders and judgements alone leave a core idle); the table is printed
    // in the knobs' order, whichever finished first.
    let settled: Vec<Settled> = knobs()
        .par_iter()
        .map(|knob| settle(knob, &points))
        .collect();
    let mut all = Settled::default();
    for s in settled {
        all.table.extend(s.table);
        all.exceptions_held.extend(s.exceptions_held);
        all.stale.extend(s.stale);
        all.unseparated.extend(s.unseparated);
    }
    println!(
        "discrimination matrix ({} pairs told apart):",
        all.table.len()
    );
    for line in &all.table {
        println!("  {line}");
    }
    for line in &all.exceptions_held {
        println!("  {line}");
    }
    assert!(
        all.unseparated.is_empty(),
        "no catalogue point tells these technique settings apart (add a case that does, or an exception with its reason): {:#?}",
        all.unseparated
    );
    assert!(
        all.stale.is_empty(),
        "these exceptions are separable after all; remove them from EXCEPTIONS: {:#?}",
        all.stale
    );
    assert!(all.table.len() > 40, "only {} pairs", all.table.len());
}

/// What one knob's search found: the table's lines, the exceptions that held, the exceptions
/// some point separated after all, and the pairs nothing separated.
#[derive(Default)]
struct Settled {
    table: Vec<String>,
    exceptions_held: Vec<String>,
    stale: Vec<String>,
    unseparated: Vec<String>,
}

/// Searches the catalogue for a point that tells each pair of `knob`'s values apart.
fn settle(knob: &Knob, points: &[CasePoint]) -> Settled {
    let n = knob.values.len();
    let mut sep: BTreeMap<(usize, usize), Separation> = BTreeMap::new();
    // Exceptions are tried too (one that some point separates is stale), but the search
    // stops once every other pair is told apart by pixels (a map-only separation keeps
    // the search going for a pixel one).
    let all_done = |sep: &BTreeMap<(usize, usize), Separation>| {
        (0..n).all(|a| {
            (a + 1..n).all(|b| {
                is_exception(knob, a, b) || sep.get(&(a, b)).is_some_and(|s| s.illegal > 0)
            })
        })
    };
    // Preferred cases first (first point of each sweep value set), then the rest.
    let mut order: Vec<&CasePoint> = Vec::new();
    for name in knob.prefer {
        order.extend(points.iter().filter(|p| p.case.name == *name));
    }
    let rest: Vec<&CasePoint> = points
        .iter()
        .filter(|p| !knob.prefer.contains(&p.case.name.as_str()))
        .step_by(7)
        .take(MAX_POINTS)
        .collect();
    order.extend(rest);
    for p in order {
        if all_done(&sep) {
            break;
        }
        separate_on(knob, p, &mut sep);
    }
    let mut out = Settled::default();
    for a in 0..n {
        for b in a + 1..n {
            let (va, vb) = (knob.values[a].to_string(), knob.values[b].to_string());
            match (sep.get(&(a, b)), is_exception(knob, a, b)) {
                (Some(s), true) => out.stale.push(format!(
                    "{} {va} vs {vb}: {} on {}",
                    knob.path,
                    s.what(),
                    s.point
                )),
                (Some(s), false) => out.table.push(format!(
                    "{:<28} {va} vs {vb}: {} when {} is rendered for {} on {}",
                    knob.path,
                    s.what(),
                    s.rendered_as,
                    s.judged_as,
                    s.point
                )),
                (None, true) => out.exceptions_held.push(format!(
                    "{:<28} {va} vs {vb}: exception: {}",
                    knob.path,
                    reason(knob, a, b)
                )),
                (None, false) => out.unseparated.push(format!("{} {va} vs {vb}", knob.path)),
            }
        }
    }
    out
}

/// Every value of `knob` on point `p`, rendered plainly and judged; each pair not yet told
/// apart by pixels is judged both ways, and a better separation replaces the one in `sep`.
fn separate_on(knob: &Knob, p: &CasePoint, sep: &mut BTreeMap<(usize, usize), Separation>) {
    let n = knob.values.len();
    // Every value on this point: its plain frame and its judged render.
    let variants: Vec<Option<(umbra_case::Frame, umbra_ref::Judged)>> = knob
        .values
        .iter()
        .map(|v| {
            let set = BTreeMap::from([(knob.path.to_string(), v.clone())]);
            let point = umbra_case::twin::with_values(p, &set, "discrimination").ok()?;
            let run = Prepared::new(point);
            let judged = umbra_ref::render_judged(&run, ClipDepth::MinusOneToOne, Profile::GL);
            Some((judged.frame.clone(), judged))
        })
        .collect();
    for a in 0..n {
        for b in 0..n {
            // A pixel separation settles a pair; one by the map alone may still be
            // bettered by a later point.
            if a == b
                || sep
                    .get(&(a.min(b), a.max(b)))
                    .is_some_and(|s: &Separation| s.illegal > 0)
            {
                continue;
            }
            let (Some((_, judged_a)), Some((frame_b, _))) = (&variants[a], &variants[b]) else {
                continue;
            };
            let (r, _) = umbra_compare::reference::judge(judged_a, frame_b);
            let better = sep
                .get(&(a.min(b), a.max(b)))
                .is_none_or(|s| r.illegal > 0 && s.illegal == 0);
            if (r.illegal > 0 || r.illegal_map > 0) && better {
                sep.insert(
                    (a.min(b), a.max(b)),
                    Separation {
                        point: p.id(),
                        judged_as: knob.values[a].to_string(),
                        rendered_as: knob.values[b].to_string(),
                        illegal: r.illegal,
                        texels: r.illegal_map,
                    },
                );
            }
        }
    }
}

fn is_exception(knob: &Knob, a: usize, b: usize) -> bool {
    !reason(knob, a, b).is_empty()
}

fn reason(knob: &Knob, a: usize, b: usize) -> &'static str {
    let (va, vb) = (knob.values[a].to_string(), knob.values[b].to_string());
    EXCEPTIONS
        .iter()
        .find(|(path, x, y, _)| {
            *path == knob.path && ((*x == va && *y == vb) || (*x == vb && *y == va))
        })
        .map_or("", |e| e.3)
}
