//! How a run's artifacts are named on disk: the orchestrator writes pictures under these
//! names and the report reads them back, so the rule lives here, once.

/// A run id as a file name (`/` and other awkward characters replaced; long sweep ids keep a
/// prefix and a hash, as file systems stop at 255 bytes).
pub fn file_name(id: &str) -> String {
    let plain: String = id
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.=@,".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    if plain.len() <= 120 {
        plain
    } else {
        format!("{}-{:08x}", &plain[..100], fnv1a(id))
    }
}

/// The `umbra repro` command that turns a failed run into a bug report for the driver's
/// developers, written into `target/umbra/repro/NAME` (on the Mesa build `mesa`, when the run
/// used one).
pub fn repro_command(run: &str, mesa: Option<&str>) -> String {
    let mut c = format!(
        "cargo run --bin umbra -- repro {} -o target/umbra/repro/{}",
        crate::escape::shell_word(run),
        file_name(run)
    );
    if let Some(m) = mesa {
        c.push_str(" --mesa=");
        c.push_str(&crate::escape::shell_word(m));
    }
    c
}

/// The `--mesa` value of a reproduce command (`RunResult::reproduce`; `--mesa=DIR`, or
/// `--mesa DIR` as reports before 2026-12 wrote it), as the shell reads the word
/// [`crate::escape::shell_word`] wrote.
pub fn mesa_of(reproduce: &str) -> Option<String> {
    let rest = reproduce
        .split_once(" --mesa=")
        .or_else(|| reproduce.split_once(" --mesa "))?
        .1;
    let (mut word, mut quoted, mut chars) = (String::new(), false, rest.chars());
    while let Some(c) = chars.next() {
        match c {
            '\'' => quoted = !quoted,
            '\\' if !quoted => word.extend(chars.next()),
            c if c.is_whitespace() && !quoted => break,
            c => word.push(c),
        }
    }
    (!word.is_empty()).then_some(word)
}

/// `text` percent-encoded for a URL's fragment (`report.html#run=NAME`): everything but
/// ASCII letters, digits and `-_.~/` as `%XX` of its UTF-8 bytes, as the page's
/// `decodeURIComponent` reads it back.
pub fn url_component(text: &str) -> String {
    text.bytes()
        .map(|b| {
            if b.is_ascii_alphanumeric() || b"-_.~/".contains(&b) {
                (b as char).to_string()
            } else {
                format!("%{b:02X}")
            }
        })
        .collect()
}

/// 32-bit FNV-1a of a name: a stable short tag for file names.
pub fn fnv1a(name: &str) -> u32 {
    name.bytes().fold(0x811c_9dc5u32, |h, b| {
        (h ^ u32::from(b)).wrapping_mul(0x0100_0193)
    })
}

/// 64-bit FNV-1a, as 16 hex digits.
pub fn fnv64(bytes: impl IntoIterator<Item = u8>) -> String {
    let h = bytes.into_iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    });
    format!("{h:016x}")
}

/// The Levenshtein distance between `a` and `b` (the near misses of a mistyped name: a check,
/// a backend id).
pub fn edits(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let here = row[j + 1];
            row[j + 1] = (row[j] + 1)
                .min(here + 1)
                .min(prev + usize::from(ca != *cb));
            prev = here;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    #[test]
    fn repro_commands_carry_the_runs_mesa_build() {
        let r = super::repro_command("gl33/softpipe/a@x=1", None);
        assert_eq!(
            r,
            "cargo run --bin umbra -- repro gl33/softpipe/a@x=1 -o target/umbra/repro/gl33_softpipe_a@x=1"
        );
        for m in ["/opt/mesa", "/opt/my mesa", "/opt/it's"] {
            for form in ["--mesa=", "--mesa "] {
                let reproduce = format!(
                    "cargo run --bin umbra -- render c.json --backend=gl33/zink --point=p {form}{}",
                    crate::escape::shell_word(m)
                );
                assert_eq!(super::mesa_of(&reproduce).as_deref(), Some(m));
            }
        }
        assert_eq!(
            super::mesa_of("cargo run --bin umbra -- render c.json"),
            None
        );
    }
}
