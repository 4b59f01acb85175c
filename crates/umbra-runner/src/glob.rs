//! Glob matching for `--filter`: `*` any run of characters, `?` one character, the rest
//! literal. Matched against the whole run id (`case@sweep=value`).
//!
//! `[` and `]` are literal (run names hold them in sweep paths and values:
//! `shadow.size[0]=512`, `polygon_offset":[2.0,4.0]`), and always in pairs; [`never_matches`]
//! says why a pattern cannot match any name umbra makes, so a typo in an expectation file is
//! an error, not a line that silently never applies.

/// Whether `text` matches `pattern` entirely.
pub fn matches(pattern: &str, text: &str) -> bool {
    let (p, t): (Vec<char>, Vec<char>) = (pattern.chars().collect(), text.chars().collect());
    let (mut pi, mut ti) = (0, 0);
    let (mut star, mut mark) = (None, 0);
    while ti < t.len() {
        if pi < p.len() && (p[pi] == '?' || p[pi] == t[ti]) {
            pi += 1;
            ti += 1;
        } else if pi < p.len() && p[pi] == '*' {
            star = Some(pi);
            mark = ti;
            pi += 1;
        } else if let Some(s) = star {
            pi = s + 1;
            mark += 1;
            ti = mark;
        } else {
            return false;
        }
    }
    p[pi..].iter().all(|c| *c == '*')
}

/// Why `pattern` can match no run name (`BACKEND/CASE@POINT`, BACKEND one of `backends`),
/// if it cannot: a bracket without its partner, a bracket holding what no sweep path or JSON
/// value holds (`[z-a]`: umbra's globs have no character classes), or a start that no
/// backend id has.
pub fn never_matches(pattern: &str, backends: &[&str]) -> Option<String> {
    if let Some(why) = unpaired(pattern) {
        return Some(why);
    }
    let mut rest = pattern;
    while let Some(open) = rest.find('[') {
        let close = rest[open..].find(']').map_or(rest.len(), |c| open + c);
        let inside = &rest[open + 1..close];
        if !json_like(inside) {
            return Some(format!(
                "`[{inside}]` is literal in umbra's globs (there are no character classes) and no run name holds it: brackets appear only around array indices and JSON values (shadow.size[0], [2.0,4.0]); use ? or *"
            ));
        }
        rest = &rest[close..];
    }
    let literal: String = pattern
        .chars()
        .take_while(|c| !matches!(c, '*' | '?'))
        .collect();
    let fits = |b: &&str| {
        let b = format!("{b}/");
        literal.starts_with(&b) || b.starts_with(&literal)
    };
    if !backends.iter().any(fits) {
        return Some(format!(
            "run names start with a backend id and `/` ({}), and {literal:?} is not the start of one",
            backends.join(", ")
        ));
    }
    None
}

/// Why the brackets of `pattern` cannot pair up as they do in every name, if they cannot.
pub fn unpaired(pattern: &str) -> Option<String> {
    let mut depth = 0i32;
    for c in pattern.chars() {
        match c {
            '[' => depth += 1,
            ']' if depth == 0 => {
                return Some(format!(
                    "{pattern:?} has a `]` without its `[`; names hold brackets only in pairs"
                ));
            }
            ']' => depth -= 1,
            _ => {}
        }
    }
    (depth != 0).then(|| {
        format!("{pattern:?} has a `[` without its `]`; names hold brackets only in pairs")
    })
}

/// Whether `inside` can be what a bracket of a run name holds: an index or JSON array
/// elements (numbers, strings, true/false/null), with wildcards anywhere.
fn json_like(inside: &str) -> bool {
    let mut unquoted = String::new();
    let mut quoted = false;
    for c in inside.chars() {
        match c {
            '"' => quoted = !quoted,
            c if !quoted => unquoted.push(c),
            _ => {}
        }
    }
    let words = unquoted
        .replace("true", "")
        .replace("false", "")
        .replace("null", "");
    words
        .chars()
        .all(|c| c.is_ascii_digit() || ".,-+eE*?[]{}: ".contains(c))
}

#[cfg(test)]
mod tests {
    use super::matches;

    #[test]
    fn globs_no_name_can_match_are_found() {
        let b = ["gl33/zink", "ref"];
        let never = |p| super::never_matches(p, &b);
        for ok in [
            "*",
            "gl33/zink/*",
            "gl*",
            "?ef/*",
            "gl33/zink/grazing@x=0.1?shadow.bias={\"polygon_offset\":[2.0?4.0]}",
            "gl33/zink/*shadow.size[0]=512",
            "gl33/zink/*[\"a\",true]",
        ] {
            assert_eq!(never(ok), None, "{ok}");
        }
        for bad in [
            "gl33/zink/packed[",
            "[z-a]*",
            "gl33/zink/a]",
            "gles3/*",
            "gl33/zink/*[z-a]*",
        ] {
            assert!(never(bad).is_some(), "{bad}");
        }
    }

    #[test]
    fn globs() {
        assert!(matches(
            "packed*",
            "packed-cubes@light.directional.azimuth_deg=90"
        ));
        assert!(matches(
            "*azimuth_deg=9?",
            "packed-cubes@light.directional.azimuth_deg=90"
        ));
        assert!(!matches("packed", "packed-cubes"));
        assert!(matches("*", ""));
        assert!(!matches("a?c", "ac"));
    }
}
