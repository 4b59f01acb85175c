//! Glob matching for `--filter`: `*` any run of characters, `?` one character, the rest
//! literal. Matched against the whole run id (`case@sweep=value`).

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

#[cfg(test)]
mod tests {
    use super::matches;

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
