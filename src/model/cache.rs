//! The lint cache directory: one small entry per lint run (what it printed and its exit code,
//! `src/lint_cache.rs`), keyed by a hash of every file the run reads (the model XML and its
//! includes, mesh/texture/height-field files, the spec, the config), the modellint version and
//! a hash of its sources (a rebuilt binary never reads another build's entries), MuJoCo's version
//! and the options. An unchanged re-lint (a pre-commit hook on the same meshes) is
//! answered from its entry without compiling the model; any edited input is a new key.
//!
//! Directory: `--cache-dir`, else `$MODELLINT_CACHE_DIR`, else `$XDG_CACHE_HOME/modellint`, else
//! `~/.cache/modellint`. `--no-cache` disables it. A cache that cannot be read or written is
//! ignored (the lint runs as without a cache). Its size is capped (least recently used out).

use std::path::{Path, PathBuf};

/// The default cache directory (None when no home directory is known).
pub fn default_dir() -> Option<PathBuf> {
    let env = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty()).map(PathBuf::from);
    if let Some(d) = env("MODELLINT_CACHE_DIR") {
        return Some(d);
    }
    if let Some(d) = env("XDG_CACHE_HOME") {
        return Some(d.join("modellint"));
    }
    env("HOME").map(|h| h.join(".cache").join("modellint"))
}

/// A fast 4-lane streaming hash (the xxHash64 round structure: multiply, rotate, multiply) with a
/// 128-bit output: hashing the inputs must cost far less than the compile it saves (tens of MB
/// of meshes in a few milliseconds). Not cryptographic: a cache key, not a signature.
struct Hash {
    lanes: [u64; 4],
    tail: Vec<u8>,
    len: u64,
}

const P1: u64 = 0x9E37_79B1_85EB_CA87;
const P2: u64 = 0xC2B2_AE3D_27D4_EB4F;
const P3: u64 = 0x1656_67B1_9E37_79F9;

fn round(acc: u64, v: u64) -> u64 {
    acc.wrapping_add(v.wrapping_mul(P2)).rotate_left(31).wrapping_mul(P1)
}

fn avalanche(mut h: u64) -> u64 {
    h ^= h >> 33;
    h = h.wrapping_mul(P2);
    h ^= h >> 29;
    h = h.wrapping_mul(P3);
    h ^ (h >> 32)
}

impl Hash {
    fn new() -> Self {
        Hash {
            lanes: [P1.wrapping_add(P2), P2, 0, 0u64.wrapping_sub(P1)],
            tail: Vec::new(),
            len: 0,
        }
    }
    fn stripes(&mut self, data: &[u8]) {
        for chunk in data.chunks_exact(32) {
            for (k, lane) in self.lanes.iter_mut().enumerate() {
                let v = u64::from_le_bytes(chunk[8 * k..8 * k + 8].try_into().unwrap_or([0; 8]));
                *lane = round(*lane, v);
            }
        }
    }
    fn write(&mut self, mut data: &[u8]) {
        self.len += data.len() as u64;
        if !self.tail.is_empty() {
            let need = 32 - self.tail.len();
            let take = need.min(data.len());
            self.tail.extend_from_slice(&data[..take]);
            data = &data[take..];
            if self.tail.len() < 32 {
                return;
            }
            let t = std::mem::take(&mut self.tail);
            self.stripes(&t);
        }
        let whole = data.len() / 32 * 32;
        self.stripes(&data[..whole]);
        self.tail.extend_from_slice(&data[whole..]);
    }
    /// A length-prefixed field, so that ("ab", "c") and ("a", "bc") differ.
    fn field(&mut self, data: &[u8]) {
        self.write(&(data.len() as u64).to_le_bytes());
        self.write(data);
    }
    fn finish(mut self) -> (u64, u64) {
        let mut pad = std::mem::take(&mut self.tail);
        pad.push(0x80);
        pad.resize(32, 0);
        self.stripes(&pad);
        let [a, b, c, d] = self.lanes;
        let h1 = avalanche(
            a.rotate_left(1) ^ b.rotate_left(7) ^ c.rotate_left(12) ^ d.rotate_left(18) ^ self.len,
        );
        let h2 = avalanche(
            a.wrapping_mul(P3)
                ^ b.rotate_left(23)
                ^ c.wrapping_mul(P1)
                ^ d.rotate_left(41)
                ^ self.len.wrapping_mul(P2),
        );
        (h1, h2)
    }
}

/// Builds a cache key: the tool's version and source hash (build.rs), MuJoCo's version, then
/// fields and files in order.
pub struct KeyBuilder(Hash);

impl Default for KeyBuilder {
    fn default() -> Self {
        let mut h = Hash::new();
        h.field(env!("CARGO_PKG_VERSION").as_bytes());
        h.field(env!("MODELLINT_SOURCE_HASH").as_bytes());
        h.field(mujoco_rs::mujoco_c::mjVERSION_HEADER.to_string().as_bytes());
        KeyBuilder(h)
    }
}

impl KeyBuilder {
    /// A length-prefixed field (an option, a path as given).
    pub fn field(&mut self, data: &[u8]) {
        self.0.field(data);
    }
    /// A file: its canonical path and its bytes. `None` when it cannot be read.
    pub fn file(&mut self, path: &Path) -> Option<()> {
        let abs = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        self.0.field(abs.to_string_lossy().as_bytes());
        self.0.field(&std::fs::read(path).ok()?);
        Some(())
    }
    pub fn finish(self) -> String {
        let (a, b) = self.0.finish();
        format!("{a:016x}{b:016x}")
    }
}

/// The extension of an entry. Entries of the compiled-model cache of earlier versions
/// (`.mjb`, tens of MB each) are counted and evicted too, and removed by `cache clean`.
const EXT: &str = "lint";
const OLD_EXT: &str = "mjb";

fn ours(p: &Path) -> bool {
    p.extension().is_some_and(|x| x == EXT || x == OLD_EXT)
}

fn entry(dir: &Path, key: &str) -> PathBuf {
    dir.join(format!("{key}.{EXT}"))
}

/// Default size cap of the cache directory, bytes (`MODELLINT_CACHE_MAX_MB` overrides it).
pub const DEFAULT_MAX_BYTES: u64 = 300 * 1024 * 1024;

/// The cap given on the command line (`--cache-max MB`), bytes; before the environment.
static CLI_MAX: std::sync::OnceLock<u64> = std::sync::OnceLock::new();

/// Sets the cap for this process (`--cache-max MB`); a negative or non-finite value is ignored.
pub fn set_max_mb(mb: f64) {
    if mb.is_finite() && mb >= 0.0 {
        let _ = CLI_MAX.set((mb * 1024.0 * 1024.0) as u64);
    }
}

/// The size cap: `--cache-max` when given, else `$MODELLINT_CACHE_MAX_MB` (megabytes) when set
/// and valid, else the default.
pub fn max_bytes() -> u64 {
    if let Some(&b) = CLI_MAX.get() {
        return b;
    }
    std::env::var("MODELLINT_CACHE_MAX_MB")
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v >= 0.0)
        .map(|mb| (mb * 1024.0 * 1024.0) as u64)
        .unwrap_or(DEFAULT_MAX_BYTES)
}

/// The cache's entries with their size and last use (modification time, set on every hit).
fn entries(dir: &Path) -> Vec<(PathBuf, u64, std::time::SystemTime)> {
    let Ok(rd) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut v: Vec<_> = rd
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| ours(p))
        .filter_map(|p| {
            let m = std::fs::metadata(&p).ok()?;
            Some((p, m.len(), m.modified().ok()?))
        })
        .collect();
    // Least recently used first; ties by name, so eviction is deterministic.
    v.sort_by(|a, b| a.2.cmp(&b.2).then(a.0.cmp(&b.0)));
    v
}

/// Removes least-recently-used entries until the directory holds at most `cap` bytes of them.
/// `keep` (the entry just written) goes last. Returns the number removed.
pub fn evict(dir: &Path, cap: u64, keep: Option<&Path>) -> usize {
    let mut v = entries(dir);
    if let Some(k) = keep
        && let Some(i) = v.iter().position(|e| e.0 == k)
    {
        let e = v.remove(i);
        v.push(e);
    }
    let mut total: u64 = v.iter().map(|e| e.1).sum();
    let mut removed = 0;
    for (p, len, _) in v {
        if total <= cap {
            break;
        }
        if std::fs::remove_file(&p).is_ok() {
            total = total.saturating_sub(len);
            removed += 1;
        }
    }
    removed
}

/// `modellint cache clean`: removes every entry (and leftover temporary files). Returns (files,
/// bytes) removed.
pub fn clean(dir: &Path) -> (usize, u64) {
    let Ok(rd) = std::fs::read_dir(dir) else { return (0, 0) };
    let (mut n, mut bytes) = (0, 0);
    for p in rd.filter_map(|e| e.ok()).map(|e| e.path()) {
        let name = p.file_name().map(|x| x.to_string_lossy().into_owned()).unwrap_or_default();
        if !(ours(&p) || (name.starts_with('.') && name.ends_with(".tmp"))) {
            continue;
        }
        let len = std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
        if std::fs::remove_file(&p).is_ok() {
            n += 1;
            bytes += len;
        }
    }
    (n, bytes)
}

/// The bytes of an entry, when present and readable. A hit marks the entry as used now (its
/// modification time), for the least-recently-used eviction.
pub fn load(dir: &Path, key: &str) -> Option<Vec<u8>> {
    let path = entry(dir, key);
    if let Ok(f) = std::fs::File::options().write(true).open(&path) {
        let _ = f.set_modified(std::time::SystemTime::now());
    }
    std::fs::read(path).ok()
}

/// Writes an entry atomically (temporary file, then rename); failures are ignored.
pub fn store(dir: &Path, key: &str, bytes: &[u8]) {
    if std::fs::create_dir_all(dir).is_err() {
        return;
    }
    let tmp = dir.join(format!(".{key}.{}.tmp", std::process::id()));
    if std::fs::write(&tmp, bytes).is_ok() && std::fs::rename(&tmp, entry(dir, key)).is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    evict(dir, max_bytes(), Some(&entry(dir, key)));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eviction_removes_least_recently_used_until_under_the_cap() {
        let dir = std::env::temp_dir().join(format!("modellint-cache-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let t0 = std::time::SystemTime::now() - std::time::Duration::from_secs(100);
        for (i, k) in ["a", "b", "c"].iter().enumerate() {
            let p = entry(&dir, k);
            std::fs::write(&p, vec![0u8; 1000]).unwrap();
            let f = std::fs::File::options().write(true).open(&p).unwrap();
            f.set_modified(t0 + std::time::Duration::from_secs(10 * i as u64)).unwrap();
        }
        std::fs::write(dir.join("unrelated.txt"), b"x").unwrap();
        // "a" is the oldest, but was just written: "b" goes first, then "c".
        assert_eq!(evict(&dir, 2000, Some(&entry(&dir, "a"))), 1);
        assert!(!entry(&dir, "b").exists() && entry(&dir, "a").exists());
        assert_eq!(evict(&dir, 1000, Some(&entry(&dir, "a"))), 1);
        assert!(!entry(&dir, "c").exists() && entry(&dir, "a").exists());
        assert_eq!(evict(&dir, 5000, None), 0);
        assert_eq!(clean(&dir), (1, 1000));
        assert!(dir.join("unrelated.txt").exists(), "clean removes only cache entries");
        let _ = std::fs::remove_dir_all(&dir);
    }

    fn h(parts: &[&[u8]]) -> (u64, u64) {
        let mut x = Hash::new();
        for p in parts {
            x.write(p);
        }
        x.finish()
    }

    #[test]
    fn hash_is_streaming_and_sensitive() {
        let data: Vec<u8> = (0..1000u32).map(|i| (i * 7 % 251) as u8).collect();
        // Any split of the stream gives the same hash.
        assert_eq!(h(&[&data]), h(&[&data[..1], &data[1..33], &data[33..500], &data[500..]]));
        // One flipped bit anywhere changes both halves.
        for i in [0, 31, 32, 999] {
            let mut d = data.clone();
            d[i] ^= 1;
            let (a, b) = (h(&[&data]), h(&[&d]));
            assert!(a.0 != b.0 && a.1 != b.1, "byte {i}");
        }
        // Trailing zero bytes are not ignored.
        assert_ne!(h(&[&data]), h(&[&data, &[0u8]]));
    }
}
