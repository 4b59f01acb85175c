//! The command line's values as types, parsed by clap through `FromStr`: a bad value is
//! refused by clap, the same way for every command that takes the flag (`error: invalid value
//! '10x' for '--timeout <SECS>': …`, exit 125), before any command runs: numbers, durations,
//! sizes, shards and backend names. What clap cannot check alone (whether this machine has
//! the device a backend id names, a glob, a directory's contents, a Mesa build) is checked
//! where the run is set up ([`super::resolve`]). Paths are `PathBuf`s.

use std::fmt;
use std::num::NonZeroUsize;
use std::str::FromStr;
use std::time::Duration;

/// A time limit in whole seconds, 1 or more (`300`, or `300s`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Seconds(pub u64);

impl Seconds {
    /// As a duration.
    pub fn duration(self) -> Duration {
        Duration::from_secs(self.0)
    }
}

impl FromStr for Seconds {
    type Err = String;
    fn from_str(s: &str) -> Result<Seconds, String> {
        let digits = s.strip_suffix('s').unwrap_or(s);
        match digits.parse::<u64>() {
            Ok(0) => Err("no run can finish in no time; give whole seconds, 1 or more".into()),
            Ok(n) => Ok(Seconds(n)),
            Err(_) => Err("give whole seconds, 1 or more (e.g. 300 or 300s)".into()),
        }
    }
}

impl fmt::Display for Seconds {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// How many worker processes run at once, 1 or more.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Jobs(pub NonZeroUsize);

impl Jobs {
    /// The count.
    pub fn get(self) -> usize {
        self.0.get()
    }
}

impl FromStr for Jobs {
    type Err = String;
    fn from_str(s: &str) -> Result<Jobs, String> {
        match s.parse::<usize>() {
            Ok(n) => NonZeroUsize::new(n)
                .map(Jobs)
                .ok_or_else(|| "at least one worker must run; give 1 or more".into()),
            Err(_) => Err("give a whole number of workers, 1 or more".into()),
        }
    }
}

impl fmt::Display for Jobs {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// A count of things, 1 or more (generated cases, timed renders).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Count(pub NonZeroUsize);

impl Count {
    /// The count.
    pub fn get(self) -> usize {
        self.0.get()
    }
}

impl FromStr for Count {
    type Err = String;
    fn from_str(s: &str) -> Result<Count, String> {
        s.parse::<usize>()
            .ok()
            .and_then(NonZeroUsize::new)
            .map(Count)
            .ok_or_else(|| "give a whole number, 1 or more".into())
    }
}

impl fmt::Display for Count {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// A memory size (`4GiB`, `512MiB`, `1073741824`), as [`umbra_case::memory::parse_size`]
/// reads it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bytes(pub u64);

impl FromStr for Bytes {
    type Err = String;
    fn from_str(s: &str) -> Result<Bytes, String> {
        umbra_case::memory::parse_size(s).map(Bytes)
    }
}

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// `--shard I/N`: shard I (0-based) of N.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// I.
    pub index: usize,
    /// N.
    pub count: usize,
}

impl Shard {
    /// The whole run: shard 0 of 1.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };
}

impl FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Shard, String> {
        let bad = || format!("{s:?}: give I/N with 0 ≤ I < N, e.g. 0/4");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            i.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// A `--backend` value as the command line gives it: one of this build's ids, a device id's
/// form (`gl33/radeonsi`, `wgpu-vk/radv`), or an alias (`all`, `hw`). clap refuses any other
/// word here, the same way for every command; whether this machine has the device an id
/// names, and what an alias stands for on it, is the registry's to say when the selection is
/// resolved ([`crate::harness::registry::selected`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BackendName(pub String);

impl BackendName {
    /// The id or alias as given.
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

impl FromStr for BackendName {
    type Err = String;
    fn from_str(s: &str) -> Result<BackendName, String> {
        if matches!(s, "all" | "hw") || crate::harness::registry::is_known(s) {
            Ok(BackendName(s.to_string()))
        } else {
            Err(format!(
                "unknown backend; this build has: {}, the aliases hw and all, and this machine's devices (`umbra backends`)",
                crate::harness::registry::known().join(", ")
            ))
        }
    }
}

impl AsRef<str> for BackendName {
    fn as_ref(&self) -> &str {
        &self.0
    }
}

impl fmt::Display for BackendName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// The names as the registry takes them.
pub fn names(backends: &[BackendName]) -> Vec<&str> {
    backends.iter().map(BackendName::as_str).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_read_what_the_help_offers_and_refuse_the_rest() {
        assert_eq!("300".parse(), Ok(Seconds(300)));
        assert_eq!("10s".parse(), Ok(Seconds(10)));
        assert!("0".parse::<Seconds>().is_err());
        assert!("10m".parse::<Seconds>().is_err());
        assert_eq!("2".parse::<Jobs>().map(Jobs::get), Ok(2));
        assert!("0".parse::<Jobs>().is_err());
        assert!("two".parse::<Jobs>().is_err());
        assert_eq!("100".parse::<Count>().map(Count::get), Ok(100));
        assert!("0".parse::<Count>().is_err());
        assert_eq!("1GiB".parse(), Ok(Bytes(1 << 30)));
        assert!("lots".parse::<Bytes>().is_err());
        assert_eq!("1/4".parse(), Ok(Shard { index: 1, count: 4 }));
        assert!("4/4".parse::<Shard>().is_err());
        assert!("1".parse::<Shard>().is_err());
        // Written back as read, for a child umbra's command line.
        assert_eq!(Shard { index: 1, count: 4 }.to_string(), "1/4");
        assert_eq!(Seconds(10).to_string(), "10");
    }
}
