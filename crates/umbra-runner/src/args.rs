//! A small argument parser: `--flag value`, `--switch`, positionals. Enough for the `umbra`
//! commands without a parser dependency; errors name the flag and what it wants.

use std::collections::BTreeMap;

/// Parsed arguments.
#[derive(Debug, Default)]
pub struct Args {
    /// Positional arguments, in order.
    pub positional: Vec<String>,
    flags: BTreeMap<String, Vec<String>>,
}

impl Args {
    /// Parses `argv` (without the program and command), knowing which flags take a value.
    pub fn parse(argv: &[String], valued: &[&str], switches: &[&str]) -> Result<Args, String> {
        let mut a = Args::default();
        let mut it = argv.iter();
        while let Some(s) = it.next() {
            if let Some(flag) = s
                .strip_prefix("--")
                .or_else(|| s.strip_prefix('-').filter(|f| f.len() == 1))
            {
                let (name, inline) = match flag.split_once('=') {
                    Some((n, v)) => (n, Some(v.to_string())),
                    None => (flag, None),
                };
                if valued.contains(&name) {
                    let v = match inline {
                        Some(v) => v,
                        None => it
                            .next()
                            .cloned()
                            .ok_or_else(|| format!("--{name} needs a value"))?,
                    };
                    a.flags.entry(name.to_string()).or_default().push(v);
                } else if switches.contains(&name) && inline.is_none() {
                    a.flags
                        .entry(name.to_string())
                        .or_default()
                        .push(String::new());
                } else {
                    let mut known: Vec<String> = valued
                        .iter()
                        .chain(switches)
                        .map(|f| format!("--{f}"))
                        .collect();
                    known.sort();
                    return Err(format!(
                        "unknown option --{name}; known: {}",
                        known.join(", ")
                    ));
                }
            } else {
                a.positional.push(s.clone());
            }
        }
        Ok(a)
    }

    /// The last value of a valued flag.
    pub fn value(&self, name: &str) -> Option<&str> {
        self.flags
            .get(name)
            .and_then(|v| v.last())
            .map(String::as_str)
    }

    /// Every value of a repeatable flag.
    pub fn values(&self, name: &str) -> Vec<&str> {
        self.flags
            .get(name)
            .map(|v| v.iter().map(String::as_str).collect())
            .unwrap_or_default()
    }

    /// Whether a switch was given.
    pub fn has(&self, name: &str) -> bool {
        self.flags.contains_key(name)
    }
}
