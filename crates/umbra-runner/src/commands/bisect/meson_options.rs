//! The meson options of one Mesa commit, derived from that commit's own option file.
//!
//! Mesa's options change between releases: `-Dgallium-drivers=swrast` became `llvmpipe` and
//! `softpipe` (24.3 added them, 25.0 removed `swrast`), `glvnd` went from a boolean to a
//! feature (24.1), osmesa, gallium-nine, gallium-opencl, gallium-xa and dri3 were removed
//! (25.0), gallium-vdpau later (26.x), and `shared-glapi` became a deprecated no-op. meson
//! refuses an option a tree does not declare, and a value outside its choices, so one fixed
//! list configures one range of releases only, and a bisection across a rename would call
//! every commit on the far side "does not build".
//!
//! So umbra states what it wants ([`WANTED`]: the drivers it runs, EGL through glvnd,
//! nothing else) and [`derive`] writes it in the words of the tree's `meson.options` (or
//! `meson_options.txt`): each option's type decides the value's form (`true`, `enabled`, a
//! combo's own `disabled`), an option the tree lacks or has deprecated is left out with a
//! note, and a required driver the tree cannot name is an error. [`check`] then holds any
//! option list (the user's `--meson-option`s too) against the tree's declarations, as meson
//! would, before a build is spent on it. The parser reads meson's option DSL (`option('name',
//! type : 'combo', choices : [...], ...)`): strings, arrays, dicts, booleans, numbers and
//! comments; the tests hold it against real option files of Mesa 22.3 to 26.2
//! (`tests/fixtures/meson-options/`, with their sources).

use std::collections::BTreeMap;

/// One declared option.
#[derive(Clone, Debug, PartialEq)]
pub struct Declared {
    /// `boolean`, `feature`, `combo`, `array`, `string` or `integer`.
    pub kind: String,
    /// A combo's or an array's choices (empty: any value).
    pub choices: Vec<String>,
    /// `deprecated : true`: the option does nothing and meson warns of it.
    pub deprecated: bool,
}

/// The options a tree declares, by name.
pub type Tree = BTreeMap<String, Declared>;

/// A meson literal.
#[derive(Clone, Debug, PartialEq)]
enum Lit {
    Str(String),
    Bool(bool),
    Num(i64),
    Array(Vec<Lit>),
    Dict(Vec<(Lit, Lit)>),
}

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
}

impl Parser<'_> {
    fn skip_space(&mut self) {
        while self.i < self.s.len() {
            match self.s[self.i] {
                b'#' => {
                    while self.i < self.s.len() && self.s[self.i] != b'\n' {
                        self.i += 1;
                    }
                }
                c if c.is_ascii_whitespace() => self.i += 1,
                _ => break,
            }
        }
    }

    fn line(&self) -> usize {
        1 + self.s[..self.i.min(self.s.len())]
            .iter()
            .filter(|&&c| c == b'\n')
            .count()
    }

    fn error<T>(&self, what: &str) -> Result<T, String> {
        Err(format!("line {}: {what}", self.line()))
    }

    fn eat(&mut self, c: u8) -> bool {
        self.skip_space();
        if self.s.get(self.i) == Some(&c) {
            self.i += 1;
            true
        } else {
            false
        }
    }

    fn ident(&mut self) -> String {
        self.skip_space();
        let start = self.i;
        while self
            .s
            .get(self.i)
            .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_')
        {
            self.i += 1;
        }
        String::from_utf8_lossy(&self.s[start..self.i]).into_owned()
    }

    fn string(&mut self) -> Result<String, String> {
        // At the opening quote; meson's strings are single-quoted, `'''` for multi-line.
        let triple = self.s[self.i..].starts_with(b"'''");
        self.i += if triple { 3 } else { 1 };
        let mut out = Vec::new();
        loop {
            match self.s.get(self.i) {
                None => return self.error("unterminated string"),
                Some(b'\'') if triple && self.s[self.i..].starts_with(b"'''") => {
                    self.i += 3;
                    break;
                }
                Some(b'\'') if !triple => {
                    self.i += 1;
                    break;
                }
                Some(b'\\') if !triple => {
                    out.push(*self.s.get(self.i + 1).unwrap_or(&b'\\'));
                    self.i += 2;
                }
                Some(&c) => {
                    out.push(c);
                    self.i += 1;
                }
            }
        }
        Ok(String::from_utf8_lossy(&out).into_owned())
    }

    fn list(&mut self, close: u8) -> Result<Vec<Lit>, String> {
        let mut items = Vec::new();
        loop {
            if self.eat(close) {
                return Ok(items);
            }
            items.push(self.value()?);
            if !self.eat(b',') {
                if self.eat(close) {
                    return Ok(items);
                }
                return self.error("expected ',' or the list's end");
            }
        }
    }

    /// A value, and any `+` concatenations after it (`'a ' + 'b'`, `[x] + [y]`).
    fn value(&mut self) -> Result<Lit, String> {
        let mut v = self.atom()?;
        while self.eat(b'+') {
            v = match (v, self.atom()?) {
                (Lit::Str(a), Lit::Str(b)) => Lit::Str(a + &b),
                (Lit::Array(mut a), Lit::Array(b)) => {
                    a.extend(b);
                    Lit::Array(a)
                }
                _ => return self.error("'+' joins two strings or two arrays"),
            };
        }
        Ok(v)
    }

    fn atom(&mut self) -> Result<Lit, String> {
        self.skip_space();
        match self.s.get(self.i) {
            Some(b'\'') => self.string().map(Lit::Str),
            Some(b'[') => {
                self.i += 1;
                self.list(b']').map(Lit::Array)
            }
            Some(b'{') => {
                self.i += 1;
                let mut pairs = Vec::new();
                loop {
                    if self.eat(b'}') {
                        return Ok(Lit::Dict(pairs));
                    }
                    let k = self.value()?;
                    if !self.eat(b':') {
                        return self.error("expected ':' in a dict");
                    }
                    pairs.push((k, self.value()?));
                    if !self.eat(b',') && !self.eat(b'}') {
                        return self.error("expected ',' or '}'");
                    } else if self.s.get(self.i - 1) == Some(&b'}') {
                        return Ok(Lit::Dict(pairs));
                    }
                }
            }
            Some(c) if c.is_ascii_digit() || *c == b'-' => {
                let start = self.i;
                self.i += 1;
                while self.s.get(self.i).is_some_and(u8::is_ascii_digit) {
                    self.i += 1;
                }
                let t = String::from_utf8_lossy(&self.s[start..self.i]).into_owned();
                t.parse()
                    .map(Lit::Num)
                    .or_else(|_| self.error("bad number"))
            }
            _ => match self.ident().as_str() {
                "true" => Ok(Lit::Bool(true)),
                "false" => Ok(Lit::Bool(false)),
                "" => self.error("expected a value"),
                other => self.error(&format!("unexpected {other:?}")),
            },
        }
    }

    /// One `option(...)` call's arguments: its name and keyword arguments.
    fn option(&mut self) -> Result<(String, BTreeMap<String, Lit>), String> {
        let Lit::Str(name) = self.value()? else {
            return self.error("an option's first argument is its name, a string");
        };
        let mut kw = BTreeMap::new();
        loop {
            if self.eat(b')') {
                return Ok((name, kw));
            }
            if !self.eat(b',') {
                return self.error("expected ',' or ')'");
            }
            if self.eat(b')') {
                return Ok((name, kw));
            }
            let key = self.ident();
            if key.is_empty() || !self.eat(b':') {
                return self.error("expected `key : value`");
            }
            kw.insert(key, self.value()?);
        }
    }
}

/// Parses a meson option file's text into its declarations.
pub fn parse(text: &str) -> Result<Tree, String> {
    let mut p = Parser {
        s: text.as_bytes(),
        i: 0,
    };
    let mut tree = Tree::new();
    loop {
        p.skip_space();
        if p.i >= p.s.len() {
            return Ok(tree);
        }
        if p.ident() != "option" || !p.eat(b'(') {
            return p.error("expected option(");
        }
        let (name, kw) = p.option()?;
        let kind = match kw.get("type") {
            Some(Lit::Str(t)) => t.clone(),
            _ => return p.error(&format!("option {name:?} has no type")),
        };
        let choices = match kw.get("choices") {
            Some(Lit::Array(a)) => a
                .iter()
                .filter_map(|l| match l {
                    Lit::Str(s) => Some(s.clone()),
                    _ => None,
                })
                .collect(),
            _ => Vec::new(),
        };
        let deprecated = matches!(kw.get("deprecated"), Some(Lit::Bool(true)));
        tree.insert(
            name,
            Declared {
                kind,
                choices,
                deprecated,
            },
        );
    }
}

/// What umbra wants of an option.
#[derive(Clone, Copy, Debug)]
pub enum Want {
    /// Built (`true`, `enabled`).
    On,
    /// Not built (`false`, `disabled`, a combo's `disabled`).
    Off,
    /// An array with these values; each entry lists alternatives in order of preference, `|`
    /// between names that must all be choices (`llvmpipe+softpipe` or `swrast`).
    List(&'static [&'static str]),
}

/// Whether an option must be in the tree (a driver umbra runs), or may be absent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Need {
    /// A tree without it cannot build what umbra runs: an error.
    Required,
    /// Left out, with a note, where the tree lacks it.
    Optional,
}

/// The smallest Mesa that holds every driver umbra runs: llvmpipe and softpipe (`swrast`
/// before 24.3), zink and lavapipe, EGL through glvnd, GL and GLES 2/3, no window system
/// and nothing else that costs build time.
pub const WANTED: &[(&str, Want, Need)] = &[
    (
        "gallium-drivers",
        Want::List(&["llvmpipe+softpipe|swrast", "zink"]),
        Need::Required,
    ),
    ("vulkan-drivers", Want::List(&["swrast"]), Need::Required),
    ("platforms", Want::List(&[]), Need::Optional),
    ("glx", Want::Off, Need::Optional),
    ("egl", Want::On, Need::Required),
    ("gbm", Want::Off, Need::Optional),
    ("glvnd", Want::On, Need::Required),
    ("gles1", Want::Off, Need::Optional),
    ("gles2", Want::On, Need::Required),
    ("opengl", Want::On, Need::Optional),
    ("shared-glapi", Want::On, Need::Optional),
    ("llvm", Want::On, Need::Required),
    ("shared-llvm", Want::On, Need::Optional),
    ("dri3", Want::Off, Need::Optional),
    ("gallium-va", Want::Off, Need::Optional),
    ("gallium-vdpau", Want::Off, Need::Optional),
    ("gallium-xa", Want::Off, Need::Optional),
    ("gallium-omx", Want::Off, Need::Optional),
    ("gallium-nine", Want::Off, Need::Optional),
    ("gallium-opencl", Want::Off, Need::Optional),
    ("osmesa", Want::Off, Need::Optional),
    ("valgrind", Want::Off, Need::Optional),
    ("libunwind", Want::Off, Need::Optional),
    ("build-tests", Want::Off, Need::Optional),
    ("video-codecs", Want::List(&[]), Need::Optional),
    ("vulkan-layers", Want::List(&[]), Need::Optional),
    ("tools", Want::List(&[]), Need::Optional),
];

/// meson's own options, the same in every tree.
pub const BUILTIN: &[&str] = &[
    "--prefix=/usr",
    "--libdir=lib/x86_64-linux-gnu",
    "--buildtype=release",
    "-Db_ndebug=true",
];

/// A tree's option list: what to pass, and what was left out or chosen, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Derived {
    /// meson's arguments: [`BUILTIN`], then one `-Dname=value` per option.
    pub args: Vec<String>,
    /// One line per option left out or written another way than the newest tree's.
    pub notes: Vec<String>,
}

/// The value that says `want` in the form `decl` takes.
fn value_of(name: &str, want: Want, decl: &Declared) -> Result<String, String> {
    let has = |c: &str| decl.choices.iter().any(|x| x == c);
    match (want, decl.kind.as_str()) {
        (Want::On, "boolean") => Ok("true".into()),
        (Want::Off, "boolean") => Ok("false".into()),
        (Want::On, "feature") => Ok("enabled".into()),
        (Want::Off, "feature") => Ok("disabled".into()),
        (Want::On, "combo") if has("enabled") => Ok("enabled".into()),
        (Want::On, "combo") if has("true") => Ok("true".into()),
        (Want::Off, "combo") if has("disabled") => Ok("disabled".into()),
        (Want::Off, "combo") if has("false") => Ok("false".into()),
        (Want::List(items), "array") => {
            let mut out: Vec<&str> = Vec::new();
            for item in items {
                let pick = item
                    .split('|')
                    .find(|alt| decl.choices.is_empty() || alt.split('+').all(has));
                match pick {
                    Some(alt) => out.extend(alt.split('+')),
                    None => {
                        return Err(format!(
                            "-D{name}: this tree's choices ({}) have none of {}",
                            decl.choices.join(", "),
                            item.replace('|', " or ").replace('+', " and ")
                        ));
                    }
                }
            }
            Ok(out.join(","))
        }
        _ => Err(format!(
            "-D{name}: a {} option with choices [{}] has no value for {want:?}",
            decl.kind,
            decl.choices.join(", ")
        )),
    }
}

/// The options for a tree with these declarations ([`WANTED`] in its words).
pub fn derive(tree: &Tree) -> Result<Derived, String> {
    let mut args: Vec<String> = BUILTIN.iter().map(|s| s.to_string()).collect();
    let mut notes = Vec::new();
    for &(name, want, need) in WANTED {
        match tree.get(name) {
            None if need == Need::Required => {
                return Err(format!(
                    "this tree declares no option {name:?}, which umbra's drivers need"
                ));
            }
            None => notes.push(format!("{name}: not an option of this tree, left out")),
            Some(d) if d.deprecated => {
                notes.push(format!("{name}: deprecated here (does nothing), left out"))
            }
            Some(d) => {
                let v = value_of(name, want, d)?;
                if name == "gallium-drivers" && v.contains("swrast") {
                    notes.push(format!(
                        "{name}: this tree has no llvmpipe/softpipe choice; swrast builds both"
                    ));
                }
                if d.kind == "boolean" && matches!(want, Want::On | Want::Off) && name == "glvnd" {
                    notes.push(format!(
                        "{name}: a boolean in this tree (a feature from 24.1)"
                    ));
                }
                args.push(format!("-D{name}={v}"));
            }
        }
    }
    Ok(Derived { args, notes })
}

/// What meson would refuse in `args` for a tree with these declarations: an option it does
/// not declare, a value outside its choices or its type. meson's own options (`b_*`, and
/// those given as `--name`) are meson's to check.
pub fn check(args: &[String], tree: &Tree) -> Vec<String> {
    let mut problems = Vec::new();
    for a in args {
        let Some((name, value)) = a.strip_prefix("-D").and_then(|kv| kv.split_once('=')) else {
            continue;
        };
        if name.starts_with("b_") || name.contains(':') || is_meson_builtin(name) {
            continue;
        }
        let Some(d) = tree.get(name) else {
            problems.push(format!("{a}: this tree declares no option {name:?}"));
            continue;
        };
        let ok = |v: &str| match d.kind.as_str() {
            "boolean" => matches!(v, "true" | "false"),
            "feature" => matches!(v, "enabled" | "disabled" | "auto" | "true" | "false"),
            "combo" => d.choices.iter().any(|c| c == v),
            "array" => d.choices.is_empty() || d.choices.iter().any(|c| c == v),
            _ => true,
        };
        let values: Vec<&str> = if d.kind == "array" {
            value.split(',').filter(|v| !v.is_empty()).collect()
        } else {
            vec![value]
        };
        for v in values.into_iter().filter(|v| !ok(v)) {
            problems.push(format!(
                "{a}: {v:?} is not a value of this tree's {} option {name:?}{}",
                d.kind,
                if d.choices.is_empty() {
                    String::new()
                } else {
                    format!(" (choices: {})", d.choices.join(", "))
                }
            ));
        }
    }
    problems
}

/// meson's core options that may also be written `-Dname=value`.
fn is_meson_builtin(name: &str) -> bool {
    matches!(
        name,
        "prefix"
            | "libdir"
            | "bindir"
            | "includedir"
            | "datadir"
            | "sysconfdir"
            | "buildtype"
            | "debug"
            | "optimization"
            | "default_library"
            | "warning_level"
            | "werror"
            | "wrap_mode"
            | "strip"
            | "unity"
            | "layout"
            | "backend"
            | "pkg_config_path"
            | "cmake_prefix_path"
            | "auto_features"
            | "force_fallback_for"
            | "cpp_rtti"
            | "c_std"
            | "cpp_std"
    )
}

/// The option file of a tree at revision `rev` (`meson.options`, or before Mesa 25.0
/// `meson_options.txt`), read with git, and its file name.
pub fn at_revision(src: &std::path::Path, rev: &str) -> Result<(String, String), String> {
    for file in ["meson.options", "meson_options.txt"] {
        let out = std::process::Command::new("git")
            .arg("-C")
            .arg(src)
            .args(["show", &format!("{rev}:{file}")])
            .output()
            .map_err(|e| format!("cannot run git: {e}"))?;
        if out.status.success() {
            return Ok((
                String::from_utf8_lossy(&out.stdout).into_owned(),
                file.into(),
            ));
        }
    }
    Err(format!(
        "{rev} has neither meson.options nor meson_options.txt: not a Mesa tree meson can configure"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_parser_reads_every_literal_meson_allows_here() {
        let t = parse(
            "# comment\noption('a', type : 'boolean', value : false, description : 'it\\'s')\n\
             option(\n  'b',\n  type : 'combo',\n  choices : ['x', 'y'], # trailing\n)\n\
             option('c', type : 'feature', deprecated: {'true': 'enabled', 'false': 'disabled'})\n\
             option('d', type : 'feature', deprecated: true)\n\
             option('e', type : 'integer', min : -1, value : 3, description : '''two\nlines''')\n\
             option('f', type : 'array', choices : ['a'] + ['b'], description : 'one ' +\n 'two')\n",
        )
        .expect("parses");
        assert_eq!(t.len(), 6);
        assert_eq!(t["b"].choices, ["x", "y"]);
        assert_eq!(t["f"].choices, ["a", "b"]);
        assert!(!t["c"].deprecated && t["d"].deprecated);
        assert_eq!(t["e"].kind, "integer");
    }

    /// Mesa's real option files, 22.3 to 26.2 (`tests/fixtures/meson-options/SOURCES.md`):
    /// each derives a list that its own declarations accept, in that release's words.
    #[test]
    fn every_fixture_release_derives_options_its_tree_accepts() {
        let dir =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/meson-options");
        let derive_of = |release: &str| {
            let text = std::fs::read_to_string(dir.join(format!("{release}.options")))
                .unwrap_or_else(|e| panic!("{release}: {e}"));
            let tree = parse(&text).unwrap_or_else(|e| panic!("{release}: {e}"));
            let d = derive(&tree).unwrap_or_else(|e| panic!("{release}: {e}"));
            assert_eq!(check(&d.args, &tree), Vec::<String>::new(), "{release}");
            println!("{release}: {}", d.args.join(" "));
            for n in &d.notes {
                println!("  {n}");
            }
            (tree, d.args)
        };
        let has = |args: &[String], a: &str| args.iter().any(|x| x == a);
        let named =
            |args: &[String], name: &str| args.iter().any(|x| x.starts_with(&format!("-D{name}=")));
        let (t22, a22) = derive_of("22.3.5");
        assert!(
            has(&a22, "-Dgallium-drivers=swrast,zink") && has(&a22, "-Dglvnd=true"),
            "{a22:?}"
        );
        assert!(
            has(&a22, "-Dosmesa=false") && has(&a22, "-Dshared-glapi=enabled"),
            "{a22:?}"
        );
        assert!(
            has(&a22, "-Ddri3=disabled") && has(&a22, "-Dgallium-opencl=disabled"),
            "{a22:?}"
        );
        let (_, a240) = derive_of("24.0.9");
        assert!(
            has(&a240, "-Dglvnd=true") && has(&a240, "-Dgallium-drivers=swrast,zink"),
            "{a240:?}"
        );
        let (_, a241) = derive_of("24.1.2");
        assert!(has(&a241, "-Dglvnd=enabled"), "{a241:?}");
        let (_, a243) = derive_of("24.3.0-devel");
        assert!(
            has(&a243, "-Dgallium-drivers=llvmpipe,softpipe,zink"),
            "{a243:?}"
        );
        let (t25, a25) = derive_of("25.2.0");
        for gone in [
            "osmesa",
            "gallium-nine",
            "gallium-opencl",
            "gallium-xa",
            "dri3",
            "shared-glapi",
            "gallium-omx",
        ] {
            assert!(!named(&a25, gone), "25.2 has no {gone}: {a25:?}");
        }
        assert!(named(&a25, "gallium-vdpau"), "{a25:?}");
        let (_, a26) = derive_of("26.2.0-rc1");
        assert!(
            !named(&a26, "gallium-vdpau") && has(&a26, "-Dgallium-drivers=llvmpipe,softpipe,zink"),
            "{a26:?}"
        );
        // One fixed list serves one side of the renames only: 22.3's on 25.2 is refused
        // (swrast, osmesa, …), and 25.2's on 22.3 (llvmpipe, glvnd's form).
        let on25 = check(&a22, &t25);
        assert!(
            on25.iter().any(|p| p.contains("\"swrast\""))
                && on25.iter().any(|p| p.contains("osmesa")),
            "{on25:?}"
        );
        let on22 = check(&a25, &t22);
        assert!(
            on22.iter().any(|p| p.contains("\"llvmpipe\""))
                && on22.iter().any(|p| p.contains("glvnd")),
            "{on22:?}"
        );
    }

    #[test]
    fn check_refuses_what_meson_would() {
        let t = parse(
            "option('gallium-drivers', type : 'array', choices : ['llvmpipe', 'zink'])\n\
             option('glvnd', type : 'boolean', value : false)\n",
        )
        .expect("parses");
        let args: Vec<String> = [
            "--prefix=/usr",
            "-Db_ndebug=true",
            "-Dgallium-drivers=swrast,zink",
            "-Dglvnd=enabled",
            "-Dosmesa=false",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let p = check(&args, &t);
        assert_eq!(p.len(), 3, "{p:?}");
        assert!(p[0].contains("\"swrast\" is not a value") && p[0].contains("llvmpipe, zink"));
        assert!(p[1].contains("\"enabled\"") && p[2].contains("no option \"osmesa\""));
    }
}
