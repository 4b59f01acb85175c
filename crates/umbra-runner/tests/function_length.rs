//! No function in the workspace is longer than [`LIMIT`] lines (issue 37): a command's main
//! reads as its steps, each step a function with a name, so a newcomer can follow it and a
//! reviewer can hold one step in view. Counted from the `fn` line to its closing brace, tests
//! and build scripts included; string and character literals and comments are skipped when
//! the braces are matched, so a `{stem}` in a format string does not end a function.

use std::path::{Path, PathBuf};

/// The longest a function may be, in lines.
const LIMIT: usize = 150;

/// One function: file, first line (1-based), name, length in lines.
#[derive(Debug)]
struct Function {
    file: PathBuf,
    line: usize,
    name: String,
    lines: usize,
}

/// Blanks out comments and the contents of string and character literals (newlines kept),
/// so braces can be matched on what is left.
fn code_only(src: &str) -> String {
    let b: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    let keep_newlines = |s: &[char], out: &mut String| {
        for c in s {
            out.push(if *c == '\n' { '\n' } else { ' ' });
        }
    };
    while i < b.len() {
        let c = b[i];
        let next = b.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            let end = (i..b.len()).find(|&j| b[j] == '\n').unwrap_or(b.len());
            keep_newlines(&b[i..end], &mut out);
            i = end;
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            let mut j = i;
            while j < b.len() {
                if b[j] == '/' && b.get(j + 1) == Some(&'*') {
                    depth += 1;
                    j += 2;
                } else if b[j] == '*' && b.get(j + 1) == Some(&'/') {
                    depth -= 1;
                    j += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    j += 1;
                }
            }
            keep_newlines(&b[i..j.min(b.len())], &mut out);
            i = j;
        } else if c == 'r'
            && (next == Some('"') || next == Some('#'))
            && !ident(b.get(i.wrapping_sub(1)))
        {
            // A raw string: r"…", r#"…"#, …
            let hashes = b[i + 1..].iter().take_while(|&&h| h == '#').count();
            if b.get(i + 1 + hashes) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            let close: String = std::iter::once('"')
                .chain(std::iter::repeat_n('#', hashes))
                .collect();
            let body = i + 2 + hashes;
            let rest: String = b[body..].iter().collect();
            let len = rest
                .find(&close)
                .map_or(rest.chars().count(), |k| rest[..k].chars().count());
            let end = (body + len + close.chars().count()).min(b.len());
            keep_newlines(&b[i..end], &mut out);
            i = end;
        } else if c == '"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != '"' {
                j += if b[j] == '\\' { 2 } else { 1 };
            }
            let end = (j + 1).min(b.len());
            keep_newlines(&b[i..end], &mut out);
            i = end;
        } else if c == '\'' {
            // A character literal ('{', '\'', '\u{7b}'), not a lifetime ('a).
            let end = if next == Some('\\') {
                (i + 2..b.len()).find(|&j| b[j] == '\'' && j > i + 2)
            } else if b.get(i + 2) == Some(&'\'') {
                Some(i + 2)
            } else {
                None
            };
            match end {
                Some(e) => {
                    keep_newlines(&b[i..=e], &mut out);
                    i = e + 1;
                }
                None => {
                    out.push(c);
                    i += 1;
                }
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

fn ident(c: Option<&char>) -> bool {
    c.is_some_and(|c| c.is_alphanumeric() || *c == '_')
}

/// Every function with a body in `src`.
fn functions(file: &Path, src: &str) -> Vec<Function> {
    let code = code_only(src);
    let lines: Vec<&str> = code.lines().collect();
    let mut found = Vec::new();
    for (n, line) in lines.iter().enumerate() {
        let Some(at) = find_fn(line) else { continue };
        let name: String = line[at + 3..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        // From the `fn`, the first `{` opens the body, unless a `;` comes first (a
        // declaration in a trait).
        // A `;` inside the signature's brackets (`[[T; 3]]`) is not the end of a declaration.
        let mut depth = 0usize;
        let mut brackets = 0usize;
        let mut opened = false;
        let mut end = None;
        'scan: for (m, l) in lines.iter().enumerate().skip(n) {
            let text = if m == n { &l[at..] } else { l };
            for ch in text.chars() {
                match ch {
                    '(' | '[' if !opened => brackets += 1,
                    ')' | ']' if !opened => brackets = brackets.saturating_sub(1),
                    ';' if !opened && brackets == 0 => break 'scan,
                    '{' => {
                        opened = true;
                        depth += 1;
                    }
                    '}' if opened => {
                        depth -= 1;
                        if depth == 0 {
                            end = Some(m);
                            break 'scan;
                        }
                    }
                    _ => {}
                }
            }
        }
        if let Some(e) = end {
            found.push(Function {
                file: file.to_path_buf(),
                line: n + 1,
                name,
                lines: e - n + 1,
            });
        }
    }
    found
}

/// Where `fn NAME` starts in a line of code, if it declares one.
fn find_fn(line: &str) -> Option<usize> {
    let mut from = 0;
    while let Some(k) = line[from..].find("fn ") {
        let at = from + k;
        let before = line[..at].chars().next_back();
        let after = line[at + 3..].chars().next();
        if !before.is_some_and(|c| c.is_alphanumeric() || c == '_')
            && after.is_some_and(|c| c.is_alphabetic() || c == '_')
        {
            return Some(at);
        }
        from = at + 3;
    }
    None
}

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn all_functions() -> Vec<Function> {
    let root = workspace();
    let mut files: Vec<PathBuf> = ["crates", "xtask", "tests", "golden"]
        .iter()
        .flat_map(|top| {
            umbra_runner::judge::basis_key::files_under(&root.join(top)).expect("read sources")
        })
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .collect();
    files.sort();
    assert!(
        files.len() > 50,
        "the workspace's sources were not found under {}",
        root.display()
    );
    files
        .iter()
        .flat_map(|f| {
            let src = std::fs::read_to_string(f).unwrap_or_default();
            functions(f.strip_prefix(&root).unwrap_or(f), &src)
        })
        .collect()
}

#[test]
fn no_function_is_longer_than_the_limit() {
    let mut all = all_functions();
    assert!(all.len() > 500, "only {} functions found", all.len());
    all.sort_by_key(|f| std::cmp::Reverse(f.lines));
    println!("the longest functions (limit {LIMIT} lines):");
    for f in all.iter().take(12) {
        println!("  {:4} {}:{} {}", f.lines, f.file.display(), f.line, f.name);
    }
    let over: Vec<String> = all
        .iter()
        .filter(|f| f.lines > LIMIT)
        .map(|f| {
            format!(
                "{}:{} fn {} is {} lines",
                f.file.display(),
                f.line,
                f.name,
                f.lines
            )
        })
        .collect();
    assert!(
        over.is_empty(),
        "{} functions are longer than {LIMIT} lines; split each into named steps:\n{}",
        over.len(),
        over.join("\n")
    );
}

#[test]
fn the_counter_sees_through_literals_and_comments() {
    let src = "fn z(x: [[u8; 3]; 2]) {\n    x;\n}\nfn a() {\n    let s = \"}}{\";\n    let c = '}';\n    // }\n    /* } */\n    let r = r#\"}\"#;\n    let l: &'static str = s;\n}\nfn b();\nfn c() { }\n";
    let f = functions(Path::new("x.rs"), src);
    let got: Vec<(&str, usize)> = f.iter().map(|f| (f.name.as_str(), f.lines)).collect();
    assert_eq!(got, [("z", 3), ("a", 8), ("c", 1)]);
    // A function over the limit is found.
    let long = format!("fn long() {{\n{}}}\n", "    x();\n".repeat(LIMIT));
    let f = functions(Path::new("x.rs"), &long);
    assert_eq!(f[0].lines, LIMIT + 2);
}
