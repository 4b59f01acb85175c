//! A parsed command line as the commands read it: positionals, and each flag's values by its
//! long name. Filled by [`crate::cli::parse`] from clap's matches, so commands stay free of
//! parser types and tests can build one directly.

use std::collections::BTreeMap;

/// Parsed arguments.
#[derive(Debug, Default)]
pub struct Args {
    /// Positional arguments, in order.
    pub positional: Vec<String>,
    flags: BTreeMap<String, Vec<String>>,
}

impl Args {
    /// Adds a value of flag `name` (an empty string for a switch).
    pub fn set(&mut self, name: &str, value: String) {
        self.flags.entry(name.to_string()).or_default().push(value);
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
