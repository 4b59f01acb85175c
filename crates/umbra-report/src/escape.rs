//! Every escape umbra's writers use, one per target, and the one base64 encoder for inlined
//! pictures. Any text a report carries may come from outside umbra (a case's name, a driver's
//! `GL_RENDERER`, an error message, an expectation's reason), so each writer passes every such
//! text through its target's escape: [`esc`] for HTML, [`script_json`] for JSON embedded in a
//! page's `<script>`, [`xml`] for junit.xml, `csv::csv_field` for CSV, [`term`] for a line on
//! the terminal.

/// Escapes text for HTML (element content and quoted attributes).
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

/// `value` as JSON text that is safe inside a `<script>` element: `<`, `>` and `&` become
/// `\u003c`, `\u003e`, `\u0026` (so neither `</script` nor `<!--` can change how the page
/// parses the element), and U+2028/U+2029 their escapes (line terminators to older
/// JavaScript). They occur only inside JSON strings, where the escapes mean the same text.
pub fn script_json(value: &serde_json::Value) -> String {
    let text = value.to_string();
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '<' => out.push_str("\\u003c"),
            '>' => out.push_str("\\u003e"),
            '&' => out.push_str("\\u0026"),
            '\u{2028}' => out.push_str("\\u2028"),
            '\u{2029}' => out.push_str("\\u2029"),
            c => out.push(c),
        }
    }
    out
}

/// Whether XML 1.0 allows `c` in a document (its `Char` production): tab, line feed,
/// carriage return and everything from U+0020 but U+FFFE and U+FFFF.
fn xml_char(c: char) -> bool {
    matches!(c, '\t' | '\n' | '\r') || (c >= ' ' && c != '\u{fffe}' && c != '\u{ffff}')
}

/// Escapes text for XML 1.0 content and quoted attributes: the five markup characters as
/// entities, tab, line feed and carriage return as character references, and every
/// character XML 1.0 forbids (the other C0 controls) written out as `\u{..}` text, since
/// not even a character reference may name them.
pub fn xml(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            // Allowed, but a parser turns a raw one in an attribute into a space and a raw
            // carriage return anywhere into a line feed: references keep them as they were.
            '\r' => out.push_str("&#13;"),
            '\n' => out.push_str("&#10;"),
            '\t' => out.push_str("&#9;"),
            c if !xml_char(c) => out.extend(c.escape_unicode()),
            c => out.push(c),
        }
    }
    out
}

/// `s` as one word for a POSIX shell, for the commands a report offers to copy: as it is
/// when it holds only characters no shell treats specially, else in single quotes (a quote
/// inside written `'\\''`).
pub fn shell_word(s: &str) -> String {
    let plain = !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=,:@+%".contains(c));
    if plain {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// A file `path` as one shell word that no command line reads as an option: a relative path
/// that begins with `-` gets `./` before it (`-x.json` → `./-x.json`), the same file.
pub fn operand(path: &str) -> String {
    if path.starts_with('-') {
        shell_word(&format!("./{path}"))
    } else {
        shell_word(path)
    }
}

/// Text for one line of terminal output: every control character (C0, DEL, C1: escape
/// sequences, carriage returns and line feeds that could redraw or fake a line) and every
/// bidirectional override or isolate (which reorder what is shown) is written as its Rust
/// escape (`\u{1b}`, `\n`, `\u{202e}`); everything else as it is.
pub fn term(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if c.is_control() || matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}') {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// Standard base64 (RFC 4648) of `bytes`.
pub fn base64(bytes: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                out.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    /// What a hostile case name, driver string or reason may hold.
    const HOSTILE: &str =
        "a<!--b<script>alert(1)</script>&\"'\u{1b}[2K\r\u{7}\u{0}x\u{2028}y\u{202e}z\u{fffe}";

    #[test]
    fn script_json_cannot_end_or_comment_its_element_and_reads_back_the_same() {
        let v = serde_json::json!({ "reason": HOSTILE });
        let s = super::script_json(&v);
        for bad in ["<", ">", "&", "\u{2028}", "\u{2029}"] {
            assert!(!s.contains(bad), "{bad:?} left in {s}");
        }
        let back: serde_json::Value = serde_json::from_str(&s).expect("still JSON");
        assert_eq!(back, v);
    }

    #[test]
    fn xml_escape_leaves_only_characters_xml_allows() {
        let s = super::xml(HOSTILE);
        assert!(s.chars().all(super::xml_char), "{s:?}");
        for bad in ['<', '>', '"', '\''] {
            assert!(!s.contains(bad), "{bad:?} left in {s}");
        }
        assert!(s.contains("\\u{1b}") && s.contains("&lt;script&gt;"), "{s}");
    }

    #[test]
    fn terminal_text_has_no_control_or_reordering_character() {
        let s = super::term(HOSTILE);
        assert!(
            !s.chars()
                .any(|c| c.is_control() || ('\u{202a}'..='\u{202e}').contains(&c)),
            "{s:?}"
        );
        assert!(s.contains("\\u{1b}[2K\\r"), "{s}");
    }

    #[test]
    fn an_operand_never_reads_as_an_option() {
        assert_eq!(super::operand("-rf.json"), "./-rf.json");
        assert_eq!(super::operand("cases/a b.json"), "'cases/a b.json'");
        assert_eq!(super::operand("/tmp/-x"), "/tmp/-x");
    }

    #[test]
    fn shell_words_quote_what_a_shell_would_read() {
        assert_eq!(super::shell_word("cases/a.json"), "cases/a.json");
        assert_eq!(super::shell_word("x=1,y=[2]"), "'x=1,y=[2]'");
        assert_eq!(super::shell_word("it's $(rm)"), "'it'\\''s $(rm)'");
        assert_eq!(super::shell_word(""), "''");
    }

    #[test]
    fn html_escape_leaves_no_markup_character() {
        let s = super::esc(HOSTILE);
        assert!(!s.contains(['<', '>', '"', '\'']), "{s}");
    }

    #[test]
    fn base64_matches_rfc_4648_vectors() {
        for (i, o) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(super::base64(i.as_bytes()), o);
        }
    }
}
