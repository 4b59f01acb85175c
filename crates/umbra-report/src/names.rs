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
