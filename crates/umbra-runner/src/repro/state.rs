//! What a capture's replay holds at the lit pass's draw, compared between two drivers:
//! `eglretrace -D CALL` dumps the GL state as JSON, with every bound texture and framebuffer
//! attachment as an image (PNG for colour, PFM for depth). A colour snapshot alone misses a
//! deviation that lives in the shadow map or in the visibility target (zink's doubled offset
//! unit changes 47 map texels and 2 visibility pixels and no colour); the state shows it.

use std::path::Path;
use std::process::Command;

/// Runs `eglretrace --headless -D call` on `trace` with `env`; the state, parsed.
pub fn dump(
    dir: &Path,
    trace: &str,
    call: u64,
    env: &[(String, String)],
) -> Option<serde_json::Value> {
    let o = Command::new("eglretrace")
        .current_dir(dir)
        .args(["--headless", "-D", &call.to_string(), trace])
        .envs(env.iter().map(|(k, v)| (k, v)))
        .output()
        .ok()?;
    serde_json::from_str(&escape_controls(&String::from_utf8_lossy(&o.stdout))).ok()
}

/// apitrace writes shader sources with raw tabs and line feeds inside JSON strings: escape
/// every control character inside a string so a strict parser reads it.
fn escape_controls(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let (mut in_string, mut escaped) = (false, false);
    for c in s.chars() {
        if in_string && !escaped && (c as u32) < 0x20 {
            out.push_str(&format!("\\u{:04x}", c as u32));
            continue;
        }
        out.push(c);
        if escaped {
            escaped = false;
        } else if c == '\\' && in_string {
            escaped = true;
        } else if c == '"' {
            in_string = !in_string;
        }
    }
    out
}

/// Per image of both states (textures and attachments): its name and how many of its
/// pixels differ, of how many (None where they cannot be compared).
pub fn differences(
    a: &serde_json::Value,
    b: &serde_json::Value,
) -> Vec<(String, Option<(u64, u64)>)> {
    let mut out = Vec::new();
    for section in ["textures", "framebuffer"] {
        let Some(images) = a[section].as_object() else {
            continue;
        };
        for (name, img) in images {
            let other = &b[section][name];
            let (Some(x), Some(y)) = (
                img["__data__"].as_str().and_then(base64),
                other["__data__"].as_str().and_then(base64),
            ) else {
                continue;
            };
            out.push((name.clone(), compare(&x, &y)));
        }
    }
    out
}

/// Pixels that differ between two encoded images of one size: PNG (any channel) or PFM.
fn compare(a: &[u8], b: &[u8]) -> Option<(u64, u64)> {
    if let (Some(x), Some(y)) = (pfm(a), pfm(b)) {
        if x.len() != y.len() {
            return None;
        }
        let differ = x
            .iter()
            .zip(&y)
            .filter(|(p, q)| p.to_bits() != q.to_bits())
            .count();
        return Some((differ as u64, x.len() as u64));
    }
    let (x, y) = (
        image::load_from_memory(a).ok()?.to_rgba8(),
        image::load_from_memory(b).ok()?.to_rgba8(),
    );
    if x.dimensions() != y.dimensions() {
        return None;
    }
    let differ = x.pixels().zip(y.pixels()).filter(|(p, q)| p != q).count();
    Some((differ as u64, u64::from(x.width()) * u64::from(x.height())))
}

/// A greyscale PFM's samples ("Pf\nW H\nSCALE\n", then W·H f32, little-endian when SCALE < 0).
fn pfm(bytes: &[u8]) -> Option<Vec<f32>> {
    let mut fields = Vec::new();
    let mut at = 0;
    while fields.len() < 4 {
        let start = at;
        while at < bytes.len() && !bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        fields.push(std::str::from_utf8(&bytes[start..at]).ok()?.to_string());
        at += 1;
    }
    if fields[0] != "Pf" {
        return None;
    }
    let (w, h): (usize, usize) = (fields[1].parse().ok()?, fields[2].parse().ok()?);
    let little = fields[3].parse::<f32>().ok()? < 0.0;
    let data = bytes.get(at..at + 4 * w * h)?;
    Some(
        data.chunks_exact(4)
            .map(|c| {
                let b = [c[0], c[1], c[2], c[3]];
                if little {
                    f32::from_le_bytes(b)
                } else {
                    f32::from_be_bytes(b)
                }
            })
            .collect(),
    )
}

/// Standard base64 (RFC 4648), padding optional; None on any other character.
fn base64(s: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(s.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0);
    for c in s.bytes().filter(|c| !c.is_ascii_whitespace() && *c != b'=') {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        };
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    #[test]
    fn base64_and_pfm_decode() {
        assert_eq!(super::base64("aGVsbG8=").as_deref(), Some(&b"hello"[..]));
        assert_eq!(super::base64("aGk").as_deref(), Some(&b"hi"[..]));
        let mut pfm = b"Pf\n2 1\n-1.0\n".to_vec();
        pfm.extend(0.5f32.to_le_bytes());
        pfm.extend(1.0f32.to_le_bytes());
        assert_eq!(super::pfm(&pfm), Some(vec![0.5, 1.0]));
        let mut other = b"Pf\n2 1\n-1.0\n".to_vec();
        other.extend(0.5f32.to_le_bytes());
        other.extend(0.75f32.to_le_bytes());
        assert_eq!(super::compare(&pfm, &other), Some((1, 2)));
    }

    #[test]
    fn control_characters_inside_strings_are_escaped() {
        let v: serde_json::Value = serde_json::from_str(&super::escape_controls(
            "{\"a\": \"x\ty\nz\\\"\",\n\"b\": 1}",
        ))
        .expect("parses");
        assert_eq!(v["a"], "x\ty\nz\"");
        assert_eq!(v["b"], 1);
    }
}
