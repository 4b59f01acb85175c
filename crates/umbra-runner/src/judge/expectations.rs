//! Run statuses and expectations, after Mesa's deqp-runner.
//!
//! [`Status`] is one exhaustive enum. A raw outcome (Pass, Fail, Crash, Timeout, Skip) meets
//! the checked-in expectations (`expectations/*.txt`) and becomes the final status: an
//! expected failure is `ExpectedFail`, an expected failure that passed is `UnexpectedPass`
//! (which fails the run until the baseline is updated, as in deqp-runner), and a failure that
//! passes on its rerun is `Flake`.
//!
//! Expectation files hold one line per pattern: `GLOB,STATUS,REASON`, where GLOB matches the
//! full run name (`backend/case@sweep`), STATUS is `Crash`, `Timeout`, `Skip` or a failure
//! with its signature, and REASON is required (a baseline without a reason is an error). `#`
//! starts a comment.
//!
//! An expected failure says *what* fails, as wgpu's `FailureCase` names the reasons it
//! expects: `Fail:CHECK<=N[+CHECK<=N]...`, each CHECK one of the judge's checks (`value`,
//! `nan`, `coverage`, `colour`, `map`, `interior`, `twin:NAME`, `golden`, `falls-along`,
//! `memory`, `render`, `card`: `umbra_report::check::FIXED`) and N the most pixels (texels
//! for `map`, 1 for the others) it may fail on. A run that fails a
//! check not listed, or more pixels than the bound, fails *differently* and is a regression;
//! one that fails less is still the expected failure. Every failing run's reason ends with
//! its signature (`failed: value=29+twin:bias-order=29`), ready to copy.
//!
//! Expectations may name the drivers they apply to, as wgpu's per-driver failure cases do:
//! a line `@applies TERM...` makes the lines after it (to the next `@applies`, or the end of
//! the file) apply only to backends whose driver matches every term. A term is
//! `mesa>=22.3`, `mesa<22.4`, `mesa=25.0.7` (also `<=`, `>`; `=` matches a version prefix,
//! so `mesa=22.3` is any 22.3.x) against the Mesa version the driver reports, or
//! `renderer=GLOB` against its renderer string. `@applies all` lifts the condition. A
//! backend with no Mesa version (the reference) matches no `mesa` term.
//!
//! **Expectations by cause.** A name glob pins a deviation to the cases someone has seen it
//! on; a user's new case with the same technique would report it as a bare regression. A
//! line `@when TERM...` makes the lines after it (to the next `@when`, or `@when any`) match
//! only runs whose case point satisfies every term ([`Condition`]): `PATH=VALUE`,
//! `PATH!=VALUE`, `PATH<VALUE`, `PATH>VALUE` (also `<=`, `>=`) over the point's JSON, dotted
//! as sweeps are (`shadow.bias.polygon_offset[1]!=0`, `shadow.format=depth16`,
//! `light.point!=null`). And the status `Deviation:NAME` expects the failure that a modelled
//! driver deviation explains ([`umbra_case::Deviation`]): the run is judged again with the
//! deviation's freedom added, and it is the expected failure only if that judgement passes
//! every check; anything the deviation does not explain is still a regression. Under
//! `@when`, a run that passes is a pass (a technique that can show a deviation does not
//! show it on every scene); only a name-pinned expectation turns a pass into
//! `UnexpectedPass`.

use std::fmt;
use std::path::Path;

use umbra_report::Status;
use umbra_report::check::Check;

/// What an expectation expects of a run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Expected {
    /// A failure of these checks, each on at most so many pixels.
    Fail(Vec<Bound>),
    /// The worker dies.
    Crash,
    /// The run does not finish in time.
    Timeout,
    /// The backend cannot run it.
    Skip,
    /// A failure that the modelled deviation explains completely: judged again with its
    /// freedom added, the run passes every check.
    Deviation(umbra_case::Deviation),
}

/// One check of an expected failure and the most pixels it may fail on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Bound {
    /// The check (`value`, `map`, `twin:bias-order`, ...).
    pub check: Check,
    /// The most pixels (or texels, or 1) it may fail on.
    pub max: u64,
}

impl Expected {
    /// Parses the STATUS field of an expectation line.
    pub fn parse(s: &str) -> Result<Expected, String> {
        match s {
            "Crash" => return Ok(Expected::Crash),
            "Timeout" => return Ok(Expected::Timeout),
            "Skip" => return Ok(Expected::Skip),
            _ if s.starts_with("Deviation:") => {
                let name = &s["Deviation:".len()..];
                return umbra_case::Deviation::parse(name)
                    .map(Expected::Deviation)
                    .ok_or_else(|| {
                        let known: Vec<&str> = umbra_case::Deviation::ALL
                            .iter()
                            .map(|d| d.name())
                            .collect();
                        format!(
                            "unknown deviation {name:?}; the modelled deviations are {}",
                            known.join(", ")
                        )
                    });
            }
            "Fail" => {
                return Err(
                    "an expected failure must say what fails: Fail:CHECK<=N[+CHECK<=N]... (copy it from the run's `failed:` signature)"
                        .into(),
                );
            }
            _ => {}
        }
        let Some(sig) = s.strip_prefix("Fail:") else {
            return Err(format!(
                "status {s:?} is not one of Fail:CHECK<=N[+...], Deviation:NAME, Crash, Timeout, Skip"
            ));
        };
        let mut bounds = Vec::new();
        for item in sig.split('+') {
            let Some((check, max)) = item.split_once("<=") else {
                return Err(format!("{item:?} is not CHECK<=N"));
            };
            let check = Check::parse(check)?;
            let max = max
                .trim()
                .parse()
                .map_err(|_| format!("{max:?} in {item:?} is not a whole number"))?;
            bounds.push(Bound { check, max });
        }
        Ok(Expected::Fail(bounds))
    }

    /// The raw status this expectation is about.
    fn status(&self) -> &'static str {
        match self {
            Expected::Fail(_) | Expected::Deviation(_) => "Fail",
            Expected::Crash => "Crash",
            Expected::Timeout => "Timeout",
            Expected::Skip => "Skip",
        }
    }
}

impl fmt::Display for Expected {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Expected::Fail(b) => {
                let parts: Vec<String> = b
                    .iter()
                    .map(|b| format!("{}<={}", b.check, b.max))
                    .collect();
                write!(f, "Fail:{}", parts.join("+"))
            }
            Expected::Deviation(d) => write!(f, "Deviation:{}", d.name()),
            other => f.write_str(other.status()),
        }
    }
}

/// A failing run's signature, as an expectation would spell it with exact bounds.
pub fn signature(failed: &[umbra_report::FailedCheck]) -> String {
    failed
        .iter()
        .map(|c| format!("{}={}", c.check, c.count))
        .collect::<Vec<_>>()
        .join("+")
}

/// One expectation line.
#[derive(Clone, Debug, PartialEq)]
pub struct Expectation {
    /// Glob over the run name.
    pub pattern: String,
    /// What the run is expected to do.
    pub expected: Expected,
    /// Why.
    pub reason: String,
    /// `file:line`, for messages.
    pub source: String,
    /// The file it came from.
    pub file: String,
    /// The drivers it applies to (from the `@applies` line above it; empty: all).
    pub applies: Selector,
    /// The case points it applies to (from the `@when` line above it; empty: all).
    pub when: Condition,
}

/// The case points an expectation applies to (`@when TERM...`): every term must hold. An
/// expectation under a condition, `always` included, names a cause rather than cases.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Condition {
    /// `(path, operator, value)`.
    pub terms: Vec<(String, String, serde_json::Value)>,
    /// `@when always`: a cause that can show on any case point.
    pub always: bool,
}

impl Condition {
    /// Parses the terms of a `@when` line (`any` alone: no condition; `always`: every case
    /// point, as a cause).
    pub fn parse(text: &str) -> Result<Condition, String> {
        let mut terms = Vec::new();
        let mut always = false;
        for t in text.split_whitespace() {
            if t == "any" {
                continue;
            }
            if t == "always" {
                always = true;
                continue;
            }
            // The operator is the first operator character and what follows it (`<=`), so
            // `a>>0` is `a` `>` `>0`, and `>0` is then refused as a value.
            let Some(at) = t.find(['!', '<', '>', '=']) else {
                return Err(format!(
                    "@when term {t:?} is not PATH=VALUE (or !=, <, >, <=, >=), e.g. shadow.bias.polygon_offset[1]!=0"
                ));
            };
            let op = ["!=", "<=", ">=", "=", "<", ">"]
                .into_iter()
                .find(|op| t[at..].starts_with(op))
                .ok_or_else(|| {
                    format!(
                        "@when term {t:?}: {:?} is not an operator (=, !=, <, >, <=, >=)",
                        &t[at..at + 1]
                    )
                })?;
            let (path, value) = (&t[..at], &t[at + op.len()..]);
            if path.is_empty() || value.is_empty() {
                return Err(format!("@when term {t:?} needs a path and a value"));
            }
            // A value is JSON where it parses (0, 1.5, null, "x", [0,0]), else a bare word
            // (an enum's name: depth16, linear).
            let value = match serde_json::from_str(value) {
                Ok(v) => v,
                Err(_) if value.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') => {
                    serde_json::Value::String(value.to_string())
                }
                Err(_) => {
                    return Err(format!(
                        "@when term {t:?}: {value:?} is neither JSON (0.5, \"x\", [0,0], null) nor a bare word (depth16)"
                    ));
                }
            };
            umbra_case::schema::check_term(path, op, &value)
                .map_err(|e| format!("@when term {t:?}: {e}"))?;
            terms.push((path.to_string(), op.to_string(), value));
        }
        Ok(Condition { terms, always })
    }

    /// Whether case point `case` (as JSON, defaults included) satisfies every term; a path the
    /// case lacks (another variant's, an absent option) reads as null. Numbers compare at the
    /// case's f32 precision ([`umbra_case::schema::compare_numbers`]).
    pub fn holds(&self, case: &serde_json::Value) -> bool {
        use std::cmp::Ordering;
        self.terms.iter().all(|(path, op, want)| {
            let have = umbra_case::get_path(case, path).unwrap_or(&serde_json::Value::Null);
            let order = match (have.as_f64(), want.as_f64()) {
                (Some(a), Some(b)) => umbra_case::schema::compare_numbers(a, b),
                _ => same(have, want).then_some(Ordering::Equal),
            };
            match op.as_str() {
                "=" => order == Some(Ordering::Equal),
                "!=" => order != Some(Ordering::Equal),
                "<" => order == Some(Ordering::Less),
                ">" => order == Some(Ordering::Greater),
                "<=" => matches!(order, Some(Ordering::Less | Ordering::Equal)),
                _ => matches!(order, Some(Ordering::Greater | Ordering::Equal)),
            }
        })
    }

    /// Whether there is no condition (the expectation names cases, not a cause).
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty() && !self.always
    }
}

/// JSON equality with numbers compared by value (`0` is `0.0`), so `[0, 0]` matches a case's
/// `[0.0, 0.0]`.
fn same(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => match (x.as_f64(), y.as_f64()) {
            (Some(x), Some(y)) => {
                umbra_case::schema::compare_numbers(x, y).is_some_and(|o| o.is_eq())
            }
            _ => false,
        },
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| same(p, q))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same(v, w)))
        }
        _ => a == b,
    }
}

impl fmt::Display for Condition {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.terms.is_empty() {
            return f.write_str(if self.always { "always" } else { "any" });
        }
        let parts: Vec<String> = self
            .terms
            .iter()
            .map(|(p, op, v)| match v {
                serde_json::Value::String(s) => format!("{p}{op}{s}"),
                v => format!("{p}{op}{v}"),
            })
            .collect();
        f.write_str(&parts.join(" "))
    }
}

/// What a backend's driver is, for `@applies` ([`Selector`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DriverFacts {
    /// The Mesa version the driver reports (`22.3.6`, `25.0.7-2~bpo12+1`), if it is Mesa.
    pub mesa: Option<String>,
    /// The renderer string.
    pub renderer: String,
}

impl DriverFacts {
    /// From what a driver reports: its version and renderer strings and its other notes.
    pub fn from_driver(version: &str, renderer: &str, notes: &[String]) -> DriverFacts {
        let (version, renderer) = (version.to_string(), renderer.to_string());
        // wgpu reports the driver's version among its notes ("driver_info Mesa 22.3.6 ...").
        let notes: Vec<&str> = notes.iter().map(String::as_str).collect();
        DriverFacts {
            mesa: reported_version(
                [version.as_str(), renderer.as_str()]
                    .into_iter()
                    .chain(notes.iter().copied()),
            ),
            renderer,
        }
    }
}

/// The drivers an expectation applies to: every term must match (none: every driver).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Selector(pub Vec<Term>);

/// One condition of a [`Selector`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Term {
    /// The Mesa version compared with `op` (`>=`, `<=`, `>`, `<`, `=`) to these components.
    Mesa(String, Vec<u32>),
    /// A glob over the renderer string.
    Renderer(String),
}

impl Selector {
    /// Parses the terms of an `@applies` line.
    pub fn parse(text: &str) -> Result<Selector, String> {
        let mut terms = Vec::new();
        for t in text.split_whitespace() {
            if t == "all" {
                continue;
            }
            if let Some(glob) = t.strip_prefix("renderer=") {
                if glob.is_empty() {
                    return Err(format!(
                        "@applies term {t:?} has an empty glob (e.g. renderer=*zink*)"
                    ));
                }
                if let Some(why) = crate::glob::unpaired(glob) {
                    return Err(format!(
                        "@applies term {t:?} can never match a renderer: {why}"
                    ));
                }
                terms.push(Term::Renderer(glob.to_string()));
                continue;
            }
            let Some(rest) = t.strip_prefix("mesa") else {
                return Err(format!(
                    "@applies term {t:?} is neither mesa<OP>VERSION nor renderer=GLOB (e.g. mesa>=22.3 mesa<22.4, renderer=*zink*)"
                ));
            };
            let op = [">=", "<=", ">", "<", "="]
                .into_iter()
                .find(|op| rest.starts_with(op))
                .ok_or_else(|| format!("@applies term {t:?} needs one of >= <= > < ="))?;
            let parts = crate::version::reviewed(&rest[op.len()..])
                .map_err(|e| format!("@applies term {t:?}: {e}"))?;
            terms.push(Term::Mesa(op.to_string(), parts));
        }
        let selector = Selector(terms);
        if let Some(why) = selector.never_holds() {
            return Err(format!(
                "@applies {}: no Mesa version is {why}; the lines under it would never apply (write the range you mean, e.g. mesa>=22.3 mesa<22.4)",
                text.trim()
            ));
        }
        Ok(selector)
    }

    /// Why the `mesa` terms admit no version at all (`mesa>=22.4 mesa<22.4`, `mesa>=25
    /// mesa<22`, `mesa=22 mesa=23`), or `None` when some version satisfies them all. Each term
    /// is a bound on versions compared part by part with missing parts as 0 (as
    /// [`Selector::matches`] compares); `mesa=22.3` is the prefix range [22.3, 22.4).
    fn never_holds(&self) -> Option<String> {
        // (version, inclusive); versions compare as padded vectors.
        type Bound = (Vec<u32>, bool);
        let pad = |v: &[u32]| {
            let mut v = v.to_vec();
            v.resize(4, 0);
            v
        };
        let mut low: Option<(Bound, String)> = None;
        let mut high: Option<(Bound, String)> = None;
        let raise = |b: Bound, t: String, low: &mut Option<(Bound, String)>| {
            let tighter = low
                .as_ref()
                .is_none_or(|((v, inc), _)| b.0 > *v || (b.0 == *v && *inc && !b.1));
            if tighter {
                *low = Some((b, t));
            }
        };
        let lower = |b: Bound, t: String, high: &mut Option<(Bound, String)>| {
            let tighter = high
                .as_ref()
                .is_none_or(|((v, inc), _)| b.0 < *v || (b.0 == *v && *inc && !b.1));
            if tighter {
                *high = Some((b, t));
            }
        };
        for term in &self.0 {
            let Term::Mesa(op, want) = term else { continue };
            let text = term_text(term);
            let v = pad(want);
            match op.as_str() {
                ">=" => raise((v, true), text, &mut low),
                ">" => raise((v, false), text, &mut low),
                "<=" => lower((v, true), text, &mut high),
                "<" => lower((v, false), text, &mut high),
                _ => {
                    // `=22.3` holds on [22.3, 22.4): the next value of its last part.
                    let mut next = want.clone();
                    if let Some(last) = next.last_mut() {
                        *last = last.saturating_add(1);
                    }
                    raise((v, true), text.clone(), &mut low);
                    lower((pad(&next), false), text, &mut high);
                }
            }
        }
        let (((lv, linc), lt), ((hv, hinc), ht)) = (low?, high?);
        let empty = lv > hv || (lv == hv && !(linc && hinc));
        empty.then(|| format!("both {lt} and {ht}"))
    }

    /// The release that closed this selector's range for driver `d`: where every term
    /// matches `d` but an upper bound (`mesa<25.2`, `mesa<=25.1`) that `d`'s version is past,
    /// that bound's version (`25.2`). The deviation the lines below it describe was fixed
    /// by then, and on `d` their runs must pass ([`Expectations::closed_for`]).
    pub fn closed_at(&self, d: &DriverFacts) -> Option<String> {
        let mut closed = None;
        for t in &self.0 {
            let one = Selector(vec![t.clone()]);
            if one.matches(d) {
                continue;
            }
            match t {
                Term::Mesa(op, want) if (op == "<" || op == "<=") && d.mesa.is_some() => {
                    closed = Some(
                        want.iter()
                            .map(u32::to_string)
                            .collect::<Vec<_>>()
                            .join("."),
                    );
                }
                _ => return None,
            }
        }
        closed
    }

    /// Whether a driver matches every term.
    pub fn matches(&self, d: &DriverFacts) -> bool {
        self.0.iter().all(|t| match t {
            Term::Renderer(g) => crate::glob::matches(g, &d.renderer),
            Term::Mesa(op, want) => {
                let Some(have) = d.mesa.as_deref().map(crate::version::parts) else {
                    return false;
                };
                if op == "=" {
                    return have.len() >= want.len() && have[..want.len()] == want[..];
                }
                let n = have.len().max(want.len());
                let pad = |v: &[u32]| {
                    (0..n)
                        .map(|i| v.get(i).copied().unwrap_or(0))
                        .collect::<Vec<_>>()
                };
                let (h, w) = (pad(&have), pad(want));
                match op.as_str() {
                    ">=" => h >= w,
                    "<=" => h <= w,
                    ">" => h > w,
                    _ => h < w,
                }
            }
        })
    }
}

/// One term as it is written (`mesa>=22.3`, `renderer=*zink*`).
fn term_text(t: &Term) -> String {
    match t {
        Term::Renderer(g) => format!("renderer={g}"),
        Term::Mesa(op, v) => format!(
            "mesa{op}{}",
            v.iter().map(u32::to_string).collect::<Vec<_>>().join(".")
        ),
    }
}

impl fmt::Display for Selector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_empty() {
            return f.write_str("all");
        }
        let parts: Vec<String> = self.0.iter().map(term_text).collect();
        f.write_str(&parts.join(" "))
    }
}

/// Every expectation of a directory, in file and line order.
#[derive(Clone, Debug, Default)]
pub struct Expectations(pub Vec<Expectation>);

impl Expectations {
    /// The lines that match no run at all: no `BACKEND/POINT` of `ids` × `points` (each
    /// point's id and JSON) matches the line's pattern with its `@when` holding. Against the
    /// whole catalogue and every backend of the build, such a line is stale (its case was
    /// renamed or removed) or mistyped: it expects nothing, and says nothing, until reported.
    pub fn stale(
        &self,
        ids: &[&str],
        points: &[(String, &serde_json::Value)],
    ) -> Vec<&Expectation> {
        self.0
            .iter()
            .filter(|e| {
                !ids.iter().any(|b| {
                    points.iter().any(|(id, case)| {
                        crate::glob::matches(&e.pattern, &format!("{b}/{id}")) && e.when.holds(case)
                    })
                })
            })
            .collect()
    }

    /// Reads `dir/*.txt`. A directory that is not there is an error (a mistyped
    /// `--expectations` would turn every expected failure into a regression); an empty one
    /// means no expectations.
    pub fn load(dir: &Path) -> Result<Expectations, String> {
        let mut files: Vec<_> = match std::fs::read_dir(dir) {
            Ok(rd) => rd
                .filter_map(|e| e.ok().map(|e| e.path()))
                .map(|p| expectation_file(&p).map(|read| read.then_some(p)))
                .filter_map(Result::transpose)
                .collect::<Result<_, _>>()?,
            Err(e) => {
                return Err(format!(
                    "--expectations {}: {e}; give the directory of expectation files (expectations/*.txt), or an empty directory for none",
                    dir.display()
                ));
            }
        };
        files.sort();
        let mut out = Vec::new();
        for f in files {
            let text = std::fs::read_to_string(&f).map_err(|e| format!("{}: {e}", f.display()))?;
            let mut applies = Selector::default();
            let mut when = Condition::default();
            for (n, line) in text.lines().enumerate() {
                let line = line.trim();
                if line.is_empty() || line.starts_with('#') {
                    continue;
                }
                let source = format!("{}:{}", f.display(), n + 1);
                if let Some(rest) = line.strip_prefix("@applies") {
                    applies = Selector::parse(rest).map_err(|e| format!("{source}: {e}"))?;
                    continue;
                }
                if let Some(rest) = line.strip_prefix("@when") {
                    when = Condition::parse(rest).map_err(|e| format!("{source}: {e}"))?;
                    continue;
                }
                let mut parts = line.splitn(3, ',');
                let (pattern, status, reason) = (
                    parts.next().unwrap_or("").trim(),
                    parts.next().unwrap_or("").trim(),
                    parts.next().unwrap_or("").trim(),
                );
                let expected = Expected::parse(status)
                    .map_err(|e| format!("{source}: {e}; write GLOB,STATUS,REASON"))?;
                if reason.is_empty() || pattern.is_empty() {
                    return Err(format!(
                        "{source}: every expectation needs a pattern and a reason; write GLOB,STATUS,REASON"
                    ));
                }
                out.push(Expectation {
                    pattern: pattern.into(),
                    expected,
                    reason: reason.into(),
                    source,
                    file: f.display().to_string(),
                    applies: applies.clone(),
                    when: when.clone(),
                });
            }
        }
        Ok(Expectations(out))
    }

    /// Checks the lines against the runs they are for (`runs`: each planned run's name and
    /// case point, `backends`: every backend id): a name glob that no run name can match,
    /// a backend part one or two edits from this build's ids (a misspelling; another
    /// machine's device ids are kept), and two lines that both claim one run when neither is a
    /// `Deviation:` (the second would never apply, silently) are errors naming the lines and
    /// the fix.
    pub fn validate(
        &self,
        backends: &[&str],
        runs: &[(String, &serde_json::Value)],
    ) -> Result<(), String> {
        for e in &self.0 {
            // A line for a device this machine lacks (`gl33/radeonsi/*`) is kept for the
            // machines that have it.
            let mut parts = e.pattern.splitn(3, '/');
            let device = match (parts.next(), parts.next()) {
                (Some(a), Some(b)) => Some(format!("{a}/{b}")).filter(|id| {
                    umbra_gl::parse_device_id(id).is_some()
                        || umbra_wgpu::Target::parse(id).is_some()
                }),
                _ => None,
            };
            if let Some(near) = device.as_deref().and_then(|d| near_miss(d, backends)) {
                return Err(format!(
                    "{}: the pattern {:?} names {:?}, which is no backend of this build and looks like a misspelling of {near:?}; fix the id (a device of another machine keeps its own name, `umbra backends` lists them)",
                    e.source,
                    e.pattern,
                    device.as_deref().unwrap_or("")
                ));
            }
            let mut backends: Vec<&str> = backends.to_vec();
            backends.extend(device.as_deref());
            if let Some(why) = crate::glob::never_matches(&e.pattern, &backends) {
                return Err(format!(
                    "{}: the pattern {:?} can never match a run: {why}",
                    e.source, e.pattern
                ));
            }
        }
        let plain: Vec<&Expectation> = self
            .0
            .iter()
            .filter(|e| !matches!(e.expected, Expected::Deviation(_)))
            .collect();
        for (name, case) in runs {
            let mut claimed: Option<&Expectation> = None;
            for e in &plain {
                if !(crate::glob::matches(&e.pattern, name) && e.when.holds(case)) {
                    continue;
                }
                match claimed {
                    Some(first)
                        if first.applies == e.applies
                            || first.applies.0.is_empty()
                            || e.applies.0.is_empty() =>
                    {
                        return Err(format!(
                            "{} and {} both match run {name} (for the same drivers): the second would never apply; narrow one pattern or remove one line",
                            first.source, e.source
                        ));
                    }
                    Some(_) => {}
                    None => claimed = Some(e),
                }
            }
        }
        Ok(())
    }

    /// The expectations whose pattern can match a run of `backend` (a run name starts with
    /// `BACKEND/`): what drivers.txt counts per backend, so gl33/llvmpipe's line does not
    /// count softpipe's or zink's lines.
    pub fn for_backend(&self, backend: &str) -> Expectations {
        self.keep(|e| crate::glob::never_matches(&e.pattern, &[backend]).is_none())
    }

    /// The expectations `keep` holds for, in their order.
    fn keep(&self, keep: impl Fn(&Expectation) -> bool) -> Expectations {
        Expectations(self.0.iter().filter(|e| keep(e)).cloned().collect())
    }

    /// The expectations that apply to a backend with driver `d`.
    pub fn for_driver(&self, d: &DriverFacts) -> Expectations {
        self.keep(|e| e.applies.matches(d))
    }

    /// The expectations whose range a release before driver `d`'s closed (the deviation was
    /// fixed: [`Selector::closed_at`]): on `d` their runs must pass. A run of `d` that fails
    /// where one of them matches is a deviation come back, and its reason says which
    /// ([`Expectations::come_back`]).
    pub fn closed_for(&self, d: &DriverFacts) -> Expectations {
        self.keep(|e| e.applies.closed_at(d).is_some())
    }

    /// For a run that failed on a driver where these closed expectations (from
    /// [`Expectations::closed_for`]) no longer apply: the one that matches it, as words for
    /// its reason.
    pub fn come_back(&self, name: &str, case: &serde_json::Value) -> Option<String> {
        let e = self.find(name, case)?;
        Some(format!(
            "a deviation that Mesa {} fixed matches this failure, {} ({}): it may be back",
            e.applies
                .0
                .iter()
                .find_map(|t| match t {
                    Term::Mesa(op, v) if op.starts_with('<') => Some(format!(
                        "{}{}",
                        if op == "<" { "" } else { "after " },
                        v.iter().map(u32::to_string).collect::<Vec<_>>().join(".")
                    )),
                    _ => None,
                })
                .unwrap_or_default(),
            e.reason,
            e.source
        ))
    }

    /// [`Expectations::files`] as drivers.txt and report.json name them: `FILE (LINES)`.
    pub fn file_counts(&self) -> Vec<String> {
        self.files()
            .iter()
            .map(|(f, n)| format!("{f} ({n})"))
            .collect()
    }

    /// The files these expectations come from, each with how many of its lines are here.
    pub fn files(&self) -> Vec<(String, usize)> {
        let mut out: Vec<(String, usize)> = Vec::new();
        for e in &self.0 {
            match out.iter_mut().find(|(f, _)| *f == e.file) {
                Some((_, n)) => *n += 1,
                None => out.push((e.file.clone(), 1)),
            }
        }
        out
    }

    /// The first expectation whose pattern matches `name` and whose `@when` condition holds
    /// for its case point `case` (JSON).
    pub fn find(&self, name: &str, case: &serde_json::Value) -> Option<&Expectation> {
        self.0
            .iter()
            .find(|e| crate::glob::matches(&e.pattern, name) && e.when.holds(case))
    }

    /// The deviations a run must be judged under as well, when the expectation that matches
    /// it names one: that one and every other `Deviation:` expectation that matches the run
    /// (a run can show two known deviations at once). Empty otherwise; the worker is asked to
    /// judge a run again only then.
    pub fn deviations(&self, name: &str, case: &serde_json::Value) -> umbra_case::Deviations {
        if !matches!(
            self.find(name, case).map(|e| &e.expected),
            Some(Expected::Deviation(_))
        ) {
            return umbra_case::Deviations::NONE;
        }
        self.0
            .iter()
            .filter(|e| crate::glob::matches(&e.pattern, name) && e.when.holds(case))
            .filter_map(|e| match e.expected {
                Expected::Deviation(d) => Some(d),
                _ => None,
            })
            .collect()
    }

    /// The final status of a raw outcome for run `name` of case point `case` that failed the
    /// checks `failed` (and, judged again under the deviation its expectation names, the
    /// checks `under_deviation`), and why: the expectation's reason and, for a failure that
    /// does not match it, how it differs. `unchecked` names the checks this run did not make
    /// (`golden` under `--golden none`, as `drivers` runs the candidate): an expected failure
    /// that names only those is not applicable to the run, which keeps its own status (a
    /// pass stays a pass, not an UnexpectedPass), and the reason says so.
    pub fn apply(
        &self,
        name: &str,
        case: &serde_json::Value,
        raw: Status,
        failed: &[umbra_report::FailedCheck],
        under_deviation: Option<&[umbra_report::FailedCheck]>,
        unchecked: &[Check],
    ) -> (Status, Option<String>) {
        let Some(e) = self.find(name, case) else {
            return (raw, None);
        };
        let why = if e.when.is_empty() {
            format!("{} ({}, {})", e.reason, e.expected, e.source)
        } else {
            format!(
                "{} ({} when {}, {})",
                e.reason, e.expected, e.when, e.source
            )
        };
        match (&raw, &e.expected) {
            // A skipped run checked nothing the expectation is about: its reason is the skip's
            // own (a backend-wide deviation named beside every skip of the backend read as
            // though it were why the run was skipped).
            (Status::Skip(_), _) => (raw, None),
            (_, Expected::Fail(bounds))
                if !bounds.is_empty() && bounds.iter().all(|b| unchecked.contains(&b.check)) =>
            {
                (
                    raw,
                    Some(format!(
                        "not applicable: it names only {}, which this run did not check; {why}",
                        bounds
                            .iter()
                            .map(|b| b.check.name())
                            .collect::<Vec<_>>()
                            .join(" and ")
                    )),
                )
            }
            // A cause does not show on every scene: a pass under it is a pass.
            (Status::Pass | Status::Flake, _) if !e.when.is_empty() => (raw, None),
            (Status::Pass | Status::Flake, _) => (Status::UnexpectedPass, Some(why)),
            // A deviation models how a driver departs from the specs, which the judge's
            // intervals then allow; a picture that changed from its own golden on the release
            // it was blessed on is a change of the driver's output, which no deviation
            // explains. The judgement again under the deviation (`judge::run::judge_again`)
            // makes the judged checks only, never the golden check (made once, on the frame,
            // in `judge::answer`), so `under_deviation` cannot hold it, and a changed picture
            // read as explained: an expected failure (bevy-sun's corrected bias on softpipe,
            // issue 59, while every other backend failed).
            (Status::Fail, Expected::Deviation(d))
                if failed.iter().any(|c| c.check == Check::Golden) =>
            {
                (
                    Status::Fail,
                    Some(format!(
                        "fails differently than expected: its picture changed from its golden, which the deviation {} cannot explain (a deviation widens what the judge allows, not the driver's own picture); review the change and `cargo xtask bless`; {why}",
                        d.name()
                    )),
                )
            }
            (Status::Fail, Expected::Deviation(d)) => match under_deviation {
                Some([]) if !failed.is_empty() => (Status::ExpectedFail, Some(why)),
                Some(still) if !still.is_empty() => (
                    Status::Fail,
                    Some(format!(
                        "fails differently than expected: judged with the deviation {} (and any other that matches) allowed, it still fails {}; {why}",
                        d.name(),
                        signature(still)
                    )),
                ),
                _ => (
                    Status::Fail,
                    Some(format!(
                        "fails differently than expected: not a judged failure the deviation {} could explain; {why}",
                        d.name()
                    )),
                ),
            },
            (Status::Fail, Expected::Fail(bounds)) => {
                let outside: Vec<String> = failed
                    .iter()
                    .filter(|c| {
                        !bounds
                            .iter()
                            .any(|b| b.check == c.check && c.count <= b.max)
                    })
                    .map(|c| format!("{}={}", c.check, c.count))
                    .collect();
                if outside.is_empty() && !failed.is_empty() {
                    (Status::ExpectedFail, Some(why))
                } else {
                    let how = if failed.is_empty() {
                        "without a judged check".to_string()
                    } else {
                        outside.join("+")
                    };
                    (
                        Status::Fail,
                        Some(format!(
                            "fails differently than expected: {how} is outside {}; {why}",
                            e.expected
                        )),
                    )
                }
            }
            (Status::Crash, Expected::Crash) | (Status::Timeout, Expected::Timeout) => {
                (Status::ExpectedFail, Some(why))
            }
            _ => (raw, Some(why)),
        }
    }
}

/// The Mesa version a driver reports ("4.5 (Core Profile) Mesa 25.0.7-2~bpo12+1" →
/// "25.0.7-2~bpo12+1"), from any of the strings given.
pub fn reported_version<'a>(strings: impl IntoIterator<Item = &'a str>) -> Option<String> {
    strings.into_iter().find_map(|s| {
        let i = s.find("Mesa ")?;
        let v: String = s[i + 5..]
            .chars()
            .take_while(|c| !c.is_whitespace() && *c != ')' && *c != ',')
            .collect();
        v.chars().next().filter(char::is_ascii_digit).map(|_| v)
    })
}

/// Whether `path`, an entry of the expectations directory, is an expectation file (`*.txt`,
/// read); a dotfile or a `*.md` note beside them (not read); or neither, refused with the
/// fix: a `zink.TXT` or a subdirectory skipped without a word once turned its expected
/// failures into regressions, or, read by another tool, a reviewer's intent into nothing.
fn expectation_file(path: &Path) -> Result<bool, String> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    if name.starts_with('.') || name.ends_with(".md") {
        return Ok(false);
    }
    let is_file = std::fs::metadata(path).is_ok_and(|m| m.is_file());
    match (name.ends_with(".txt"), is_file) {
        (true, true) => Ok(true),
        (_, false) => Err(format!(
            "{}: not a file: expectations are read from the directory's own *.txt files, not from subdirectories; move its files up or out of the directory",
            path.display()
        )),
        (false, true) => Err(format!(
            "{}: not an expectation file (expectations are *.txt, lower case; notes *.md): rename it to end in .txt, or move it out of the directory",
            path.display()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions_are_read_from_driver_strings() {
        assert_eq!(
            reported_version(["4.5 (Core Profile) Mesa 25.0.7-2~bpo12+1"]).as_deref(),
            Some("25.0.7-2~bpo12+1")
        );
        assert_eq!(
            reported_version([
                "llvmpipe (LLVM 15.0.6, 256 bits)",
                "Mesa 22.3.6 (LLVM 15.0.6)"
            ])
            .as_deref(),
            Some("22.3.6")
        );
        assert_eq!(reported_version(["OpenGL ES 3.2 NVIDIA 550.1"]), None);
    }

    /// A file the loader would not read is refused, not skipped: `zink.TXT` and a subdirectory
    /// each name themselves and the fix; dotfiles and notes (`*.md`) stay beside the files.
    #[test]
    fn an_entry_that_is_not_an_expectation_file_is_refused_not_skipped() {
        let dir = std::env::temp_dir().join(format!("umbra-exp-entries-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("dir");
        std::fs::write(dir.join("a.txt"), "gl33/zink/x,Skip,a reason\n").expect("txt");
        std::fs::write(dir.join(".gitkeep"), "").expect("dotfile");
        std::fs::write(dir.join("README.md"), "notes").expect("md");
        assert!(Expectations::load(&dir).is_ok());
        std::fs::write(dir.join("zink.TXT"), "gl33/zink/y,Skip,a reason\n").expect("TXT");
        let e = Expectations::load(&dir).err().unwrap_or_default();
        assert!(
            e.contains("zink.TXT: not an expectation file") && e.contains("rename it"),
            "{e}"
        );
        std::fs::remove_file(dir.join("zink.TXT")).expect("rm");
        std::fs::create_dir_all(dir.join("zink")).expect("subdir");
        let e = Expectations::load(&dir).err().unwrap_or_default();
        assert!(
            e.contains("zink: not a file") && e.contains("subdirectories"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// `apply` for a run with no `@when` in play and no deviation judged.
    fn plain(
        e: &Expectations,
        name: &str,
        raw: Status,
        failed: &[umbra_report::FailedCheck],
    ) -> (Status, Option<String>) {
        e.apply(name, &serde_json::Value::Null, raw, failed, None, &[])
    }

    #[test]
    fn an_expectation_naming_only_a_check_the_run_did_not_make_is_not_applicable() {
        let dir = std::env::temp_dir().join(format!("umbra-exp-na-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        std::fs::write(
            dir.join("na.txt"),
            "gles2/zink/filters@*,Fail:golden<=1,zink's PCF-5 golden\n\
             gl33/zink/near-far,Fail:golden<=1+value<=35,a golden and a value\n",
        )
        .expect("write");
        let e = Expectations::load(&dir).expect("load");
        let _ = std::fs::remove_dir_all(&dir);
        // --golden none: a pass stays a pass, and says why the expectation did not apply.
        let (status, why) = e.apply(
            "gles2/zink/filters@x",
            &serde_json::Value::Null,
            Status::Pass,
            &[],
            None,
            &[Check::Golden],
        );
        assert_eq!(status, Status::Pass);
        assert!(
            why.unwrap_or_default()
                .starts_with("not applicable: it names only golden, which this run did not check"),
        );
        // With goldens checked it is the UnexpectedPass it always was.
        let (status, _) = e.apply(
            "gles2/zink/filters@x",
            &serde_json::Value::Null,
            Status::Pass,
            &[],
            None,
            &[],
        );
        assert_eq!(status, Status::UnexpectedPass);
        // A failure of another check under it is still a failure.
        let (status, _) = e.apply(
            "gles2/zink/filters@x",
            &serde_json::Value::Null,
            Status::Fail,
            &failed(&[("value", 3)]),
            None,
            &[Check::Golden],
        );
        assert_eq!(status, Status::Fail);
        // An expectation that names a check the run did make still applies.
        let (status, _) = e.apply(
            "gl33/zink/near-far",
            &serde_json::Value::Null,
            Status::Pass,
            &[],
            None,
            &[Check::Golden],
        );
        assert_eq!(status, Status::UnexpectedPass);
        // A skip is only a skip, under any expectation.
        for name in ["gles2/zink/filters@x", "gl33/zink/near-far"] {
            let skip = Status::Skip("GLES 2 lacks it".into());
            assert_eq!(plain(&e, name, skip.clone(), &[]), (skip, None));
        }
    }

    fn failed(checks: &[(&str, u64)]) -> Vec<umbra_report::FailedCheck> {
        checks
            .iter()
            .map(|(c, n)| umbra_report::FailedCheck {
                check: Check::parse(c).expect("a check"),
                count: *n,
            })
            .collect()
    }

    #[test]
    fn expectations_turn_failures_into_expected_ones_and_passes_into_unexpected() {
        let e = Expectations(vec![Expectation {
            pattern: "gles2/*/spot*".into(),
            expected: Expected::parse("Fail:value<=40+twin:bias-order<=40").expect("parse"),
            reason: "driver bug 123".into(),
            source: "x.txt:1".into(),
            file: "x.txt".into(),
            applies: Selector::default(),
            when: Condition::default(),
        }]);
        let same = failed(&[("value", 29), ("twin:bias-order", 29)]);
        assert_eq!(
            plain(&e, "gles2/zink/spot-20deg", Status::Fail, &same).0,
            Status::ExpectedFail
        );
        // Fewer pixels is still the expected failure.
        assert_eq!(
            plain(
                &e,
                "gles2/zink/spot-20deg",
                Status::Fail,
                &failed(&[("value", 3)])
            )
            .0,
            Status::ExpectedFail
        );
        assert_eq!(
            plain(&e, "gles2/zink/spot-20deg", Status::Pass, &[]).0,
            Status::UnexpectedPass
        );
        assert_eq!(
            plain(&e, "gles2/zink/spot-20deg", Status::Crash, &[]).0,
            Status::Crash
        );
        assert_eq!(
            plain(&e, "gl33/zink/spot-20deg", Status::Fail, &same).0,
            Status::Fail
        );
        assert!(Status::UnexpectedPass.is_regression() && !Status::ExpectedFail.is_regression());
    }

    #[test]
    fn a_failure_of_another_check_or_of_more_pixels_is_a_regression() {
        let e = Expectations(vec![Expectation {
            pattern: "gl33/softpipe/*".into(),
            expected: Expected::parse("Fail:map<=1000").expect("parse"),
            reason: "softpipe offset".into(),
            source: "x.txt:2".into(),
            file: "x.txt".into(),
            applies: Selector::default(),
            when: Condition::default(),
        }]);
        let (status, why) = plain(
            &e,
            "gl33/softpipe/x",
            Status::Fail,
            &failed(&[("map", 5000)]),
        );
        assert_eq!(status, Status::Fail);
        assert!(why.unwrap_or_default().contains("map=5000"));
        let (status, why) = plain(
            &e,
            "gl33/softpipe/x",
            Status::Fail,
            &failed(&[("map", 10), ("colour", 2)]),
        );
        assert_eq!(status, Status::Fail);
        assert!(why.unwrap_or_default().contains("colour=2"));
    }

    #[test]
    fn a_bare_fail_or_an_unknown_check_is_refused_with_the_fix() {
        let e = Expected::parse("Fail").expect_err("bare");
        assert!(e.contains("Fail:CHECK<=N"), "{e}");
        let e = Expected::parse("Fail:shadows<=3").expect_err("unknown");
        assert!(
            e.contains("unknown check") && e.contains("twin:NAME"),
            "{e}"
        );
        assert_eq!(
            Expected::parse("Fail:twin:bias-order<=7")
                .expect("twin")
                .to_string(),
            "Fail:twin:bias-order<=7"
        );
    }

    #[test]
    fn a_baseline_line_without_a_reason_is_refused() {
        let dir = std::env::temp_dir().join(format!("umbra-exp-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        std::fs::write(dir.join("bad.txt"), "gl33/*,Fail:value<=1,\n").expect("write");
        let err = Expectations::load(&dir).expect_err("no reason");
        assert!(
            err.contains("bad.txt:1") && err.contains("needs a pattern and a reason"),
            "{err}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_wgpu_hello_gives_its_mesa_version_from_the_driver_info() {
        let notes = [
            "backend Vulkan".to_string(),
            "driver_info Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)".to_string(),
        ];
        assert_eq!(
            DriverFacts::from_driver("", "llvmpipe (LLVM 15.0.6, 256 bits)", &notes)
                .mesa
                .as_deref(),
            Some("25.0.7-2~bpo12+1")
        );
    }

    #[test]
    fn a_range_closed_by_a_fix_is_told_apart_from_one_that_never_applied() {
        let sel = Selector::parse("mesa>=22.3 mesa<25.2").expect("parse");
        let on = |v: &str, r: &str| DriverFacts {
            mesa: Some(v.into()),
            renderer: r.into(),
        };
        assert_eq!(sel.closed_at(&on("25.0.7-2~bpo12+1", "zink")), None);
        assert_eq!(
            sel.closed_at(&on("26.2.6-1", "zink")).as_deref(),
            Some("25.2")
        );
        // Below the range it never applied: not closed.
        assert_eq!(sel.closed_at(&on("21.0.0", "zink")), None);
        // Another term that does not match: not this driver's line at all.
        let zink = Selector::parse("mesa<25.2 renderer=*zink*").expect("parse");
        assert_eq!(zink.closed_at(&on("26.2.6", "llvmpipe")), None);
        assert_eq!(
            zink.closed_at(&on("26.2.6", "zink (llvmpipe)")).as_deref(),
            Some("25.2")
        );
        // Not a Mesa driver (the reference): nothing closed.
        assert_eq!(sel.closed_at(&DriverFacts::default()), None);
    }

    #[test]
    fn a_backend_counts_only_the_lines_that_can_name_its_runs() {
        let dir = std::env::temp_dir().join(format!("umbra-exp-backend-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        std::fs::write(
            dir.join("mesa.txt"),
            "gl33/zink/*,Deviation:offset-unit-x4,zink\n\
             gl33/softpipe/beyond-far@*,Fail:value<=1,softpipe\n\
             gl33/*/grazing,Fail:value<=1,any gl33\n\
             */zink/contact,Fail:value<=1,any zink\n",
        )
        .expect("write");
        let all = Expectations::load(&dir).expect("load");
        let names = |b: &str| {
            all.for_backend(b)
                .0
                .iter()
                .map(|x| x.pattern.clone())
                .collect::<Vec<_>>()
        };
        assert_eq!(
            names("gl33/zink"),
            ["gl33/zink/*", "gl33/*/grazing", "*/zink/contact"]
        );
        assert_eq!(names("gl33/llvmpipe"), ["gl33/*/grazing", "*/zink/contact"]);
        // A wildcard before the backend id is kept (it may match): never a line lost.
        assert_eq!(names("gles3/softpipe"), ["*/zink/contact"]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn expectations_select_drivers_by_version_and_renderer() {
        let dir = std::env::temp_dir().join(format!("umbra-exp-select-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        std::fs::write(
            dir.join("mesa.txt"),
            "gl33/llvmpipe/a,Fail:value<=1,everywhere\n\
             @applies mesa>=22.3 mesa<22.4\n\
             gl33/llvmpipe/b,Fail:value<=2,22.3 only\n\
             @applies mesa=25.0 renderer=llvmpipe*\n\
             gl33/llvmpipe/c,Fail:value<=3,25.0 llvmpipe only\n\
             @applies all\n\
             gl33/llvmpipe/d,Fail:value<=4,everywhere again\n",
        )
        .expect("write");
        let all = Expectations::load(&dir).expect("load");
        let facts = |v: &str, r: &str| DriverFacts {
            mesa: reported_version([v]),
            renderer: r.into(),
        };
        let names = |e: &Expectations| e.0.iter().map(|x| x.pattern.clone()).collect::<Vec<_>>();
        let old = all.for_driver(&facts(
            "4.5 (Core Profile) Mesa 22.3.6",
            "llvmpipe (LLVM 15.0.6, 256 bits)",
        ));
        assert_eq!(
            names(&old),
            ["gl33/llvmpipe/a", "gl33/llvmpipe/b", "gl33/llvmpipe/d"]
        );
        let new = all.for_driver(&facts(
            "4.5 (Core Profile) Mesa 25.0.7-2~bpo12+1",
            "llvmpipe (LLVM 15.0.6, 256 bits)",
        ));
        assert_eq!(
            names(&new),
            ["gl33/llvmpipe/a", "gl33/llvmpipe/c", "gl33/llvmpipe/d"]
        );
        let zink = all.for_driver(&facts("Mesa 25.0.7", "zink Vulkan 1.3(llvmpipe)"));
        assert_eq!(names(&zink), ["gl33/llvmpipe/a", "gl33/llvmpipe/d"]);
        let reference = all.for_driver(&DriverFacts::default());
        assert_eq!(names(&reference), ["gl33/llvmpipe/a", "gl33/llvmpipe/d"]);
        assert_eq!(old.files().len(), 1);
        std::fs::write(dir.join("bad.txt"), "@applies mesa~22\n").expect("write");
        let e = Expectations::load(&dir).expect_err("bad term");
        assert!(e.contains("bad.txt:1") && e.contains(">="), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Integrity round three: `@applies` versions were read like a driver's version string,
    /// so `mesa>=22.4x` meant `mesa>=22` and applied on 22.3.6; a range that can never hold
    /// was accepted and silently never applied. Both are refused now, naming the line.
    #[test]
    fn applies_versions_parse_strictly_and_ranges_that_never_hold_are_refused() {
        for bad in [
            "mesa>=22.4x",
            "mesa>=22..4",
            "mesa>=22.99999999999",
            "mesa>=22.3.6.1",
            "mesa<",
            "mesa=22.3-rc1",
        ] {
            let e = Selector::parse(bad).expect_err(bad);
            assert!(e.contains("MAJOR[.MINOR[.PATCH]]"), "{bad}: {e}");
        }
        for never in [
            "mesa>=22.4 mesa<22.4",
            "mesa>=25 mesa<22",
            "mesa>22.4 mesa<=22.4",
            "mesa=22 mesa=23",
            "mesa=22.3 mesa>=22.4",
            "renderer=*zink* mesa<22.3 mesa>22.3.6",
        ] {
            let e = Selector::parse(never).expect_err(never);
            assert!(e.contains("no Mesa version is both"), "{never}: {e}");
        }
        for fine in [
            "mesa>=22.3 mesa<22.4",
            "mesa>=22.4 mesa<=22.4",
            "mesa=22.3 mesa<22.3.7",
            "mesa>=25",
            "all",
            "mesa=26",
        ] {
            assert!(Selector::parse(fine).is_ok(), "{fine}");
        }
        // The reproducer: an expectation meant for 22.4 and later is refused whole, so a
        // failing run on 22.3.6 stays a failure.
        let dir = std::env::temp_dir().join(format!("umbra-exp-strict-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        std::fs::write(
            dir.join("mesa.txt"),
            "# fixed in 22.4\n@applies mesa>=22.4x\ngl33/llvmpipe/*,Fail,a deviation\n",
        )
        .expect("write");
        let e = Expectations::load(&dir).expect_err("22.4x");
        assert!(e.contains("mesa.txt:2") && e.contains("\"22.4x\""), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// `@when` terms over a case point's JSON: numbers by value, bare words as strings,
    /// arrays element by element, a missing path as null.
    #[test]
    fn conditions_hold_on_the_case_point() {
        let case = serde_json::json!({
            "light": { "point": { "position": [0, 3, 0] } },
            "shadow": { "format": "depth16", "bias": { "polygon_offset": [2.0, 4.0] } },
        });
        let holds = |t: &str| Condition::parse(t).expect("parse").holds(&case);
        assert!(holds("shadow.bias.polygon_offset[1]!=0"));
        assert!(holds(
            "shadow.bias.polygon_offset[1]>=4 shadow.format=depth16"
        ));
        assert!(!holds("shadow.bias.polygon_offset[1]<4"));
        assert!(holds("shadow.bias.polygon_offset!=[0,0]"));
        assert!(holds("shadow.bias.polygon_offset=[2,4]"));
        assert!(holds("light.point!=null"));
        assert!(!holds("light.spot!=null"));
        assert!(!holds("shadow.format=depth24"));
        assert!(holds("always"));
        assert!(Condition::parse("any").expect("any").is_empty());
        assert!(!Condition::parse("always").expect("always").is_empty());
        let e = Condition::parse("shadow.format").expect_err("no operator");
        assert!(e.contains("PATH=VALUE"), "{e}");
        // Issue 36's probes: each once misfired silently.
        let e = Condition::parse("shadow.bais.constant>0").expect_err("mistyped path");
        assert!(e.contains("names no field"), "{e}");
        let e = Condition::parse("shadow.bias.constant>>0").expect_err("malformed term");
        assert!(e.contains("\">0\""), "{e}");
        assert!(Condition::parse("shadow.format=depth17").is_err());
        // A case's f32 0.0005 equals the decimal 0.0005 it was written as.
        let widened =
            serde_json::json!({ "shadow": { "bias": { "constant": f64::from(0.0005f32) } } });
        let on = |t: &str| Condition::parse(t).expect("parse").holds(&widened);
        assert!(on("shadow.bias.constant=0.0005") && on("shadow.bias.constant=5e-4"));
        assert!(!on("shadow.bias.constant!=0.0005") && !on("shadow.bias.constant>0.0005"));
        assert!(on("shadow.bias.constant<=0.0005") && on("shadow.bias.constant>0.0004"));
    }

    /// A line whose pattern or condition matches no point of the catalogue on any backend is
    /// stale (issue 36: such lines went unreported).
    #[test]
    fn lines_that_match_no_run_are_stale() {
        let dir = std::env::temp_dir().join(format!("umbra-exp-stale-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        std::fs::write(
            dir.join("s.txt"),
            "gl33/zink/square-occluder,Crash,live\n\
             gl33/zink/renamed-case,Crash,stale\n\
             @when shadow.format=depth16\n\
             gl33/zink/square-occluder,Crash,stale by condition\n",
        )
        .expect("write");
        let all = Expectations::load(&dir).expect("load");
        let case = serde_json::json!({ "shadow": { "format": "depth24" } });
        let stale = all.stale(&["gl33/zink", "ref"], &[("square-occluder".into(), &case)]);
        let reasons: Vec<&str> = stale.iter().map(|e| e.reason.as_str()).collect();
        assert_eq!(reasons, ["stale", "stale by condition"]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A cause expectation (`@when` … `Deviation:NAME`): the failure the deviation explains is
    /// expected, one it does not is a regression that says what is left, a pass is a pass;
    /// every deviation line that matches the run is in the set it is judged under.
    #[test]
    fn deviations_expect_what_they_explain_and_nothing_else() {
        let dir = std::env::temp_dir().join(format!("umbra-exp-dev-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        std::fs::write(
            dir.join("d.txt"),
            "gl33/zink/pinned,Fail:map<=5,a case by name\n\
             @when shadow.bias.polygon_offset[1]!=0\n\
             gl33/zink/*,Deviation:offset-unit-x4,doubled unit\n\
             @when always\n\
             gl33/zink/*,Deviation:edge-holes,holes\n\
             @when any\n",
        )
        .expect("write");
        let e = Expectations::load(&dir).expect("load");
        let _ = std::fs::remove_dir_all(&dir);
        let with_units = serde_json::json!({ "shadow": { "bias": { "polygon_offset": [0, 4] } } });
        let without = serde_json::json!({ "shadow": { "bias": { "polygon_offset": [0, 0] } } });
        let set = e.deviations("gl33/zink/new-case", &with_units);
        assert_eq!(set.names(), "offset-unit-x4+edge-holes");
        assert_eq!(
            e.deviations("gl33/zink/new-case", &without).names(),
            "edge-holes"
        );
        // A name-pinned line first: no deviation is asked for.
        assert!(e.deviations("gl33/zink/pinned", &with_units).is_empty());
        let map = failed(&[("map", 900)]);
        let (status, _) = e.apply(
            "gl33/zink/new-case",
            &with_units,
            Status::Fail,
            &map,
            Some(&[]),
            &[],
        );
        assert_eq!(status, Status::ExpectedFail);
        let left = failed(&[("value", 3)]);
        let (status, why) = e.apply(
            "gl33/zink/new-case",
            &with_units,
            Status::Fail,
            &map,
            Some(&left),
            &[],
        );
        assert_eq!(status, Status::Fail);
        assert!(why.unwrap_or_default().contains("still fails value=3"));
        // A changed picture is not a deviation's to explain, even where the judgement under
        // the deviation has nothing left.
        let (status, why) = e.apply(
            "gl33/zink/new-case",
            &with_units,
            Status::Fail,
            &failed(&[("golden", 1)]),
            Some(&[]),
            &[],
        );
        assert_eq!(status, Status::Fail);
        assert!(
            why.unwrap_or_default()
                .contains("its picture changed from its golden")
        );
        // Not judged again (a crash, say, or no judged check): not explained.
        let (status, _) = e.apply(
            "gl33/zink/new-case",
            &with_units,
            Status::Fail,
            &map,
            None,
            &[],
        );
        assert_eq!(status, Status::Fail);
        // A cause does not show on every scene.
        let (status, why) = e.apply(
            "gl33/zink/new-case",
            &with_units,
            Status::Pass,
            &[],
            None,
            &[],
        );
        assert_eq!((status, why), (Status::Pass, None));
        // By name, a pass is still news.
        let (status, _) = e.apply(
            "gl33/zink/pinned",
            &with_units,
            Status::Pass,
            &[],
            None,
            &[],
        );
        assert_eq!(status, Status::UnexpectedPass);
        let err = Expected::parse("Deviation:nope").expect_err("unknown");
        assert!(err.contains("offset-unit-x4"), "{err}");
    }
}

/// This build's id that `id` is one or two edits away from (a misspelling such as
/// `gl33/llvmpip`), if any.
fn near_miss<'a>(id: &str, known: &[&'a str]) -> Option<&'a str> {
    // Only within one API: `wgpu-gl/nvidia` is two edits from `wgpu-vk/nvidia` and both are
    // real (seen on an NVIDIA machine, where this check refused the former's line).
    let api = |s: &str| s.split('/').next().unwrap_or("").to_string();
    known
        .iter()
        .copied()
        .find(|k| *k != id && api(k) == api(id) && umbra_report::names::edits(k, id) <= 2)
}

#[cfg(test)]
mod near_miss_tests {
    use super::*;

    #[test]
    fn a_misspelt_id_is_caught_and_another_machine_s_device_is_not() {
        let known = ["gl33/llvmpipe", "gles3/softpipe", "wgpu-vk/lavapipe"];
        assert_eq!(near_miss("gl33/llvmpip", &known), Some("gl33/llvmpipe"));
        assert_eq!(near_miss("gles3/sofpipe", &known), Some("gles3/softpipe"));
        assert_eq!(near_miss("gl33/radeonsi", &known), None);
        assert_eq!(near_miss("wgpu-vk/radv", &known), None);
        assert_eq!(near_miss("wgpu-gl/nvidia", &["wgpu-vk/nvidia"]), None);
        assert_eq!(umbra_report::names::edits("kitten", "sitting"), 3);
    }
}
