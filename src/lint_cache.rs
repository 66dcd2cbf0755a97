//! Lint-result cache: what a lint run printed (stdout, stderr) and its exit code, keyed by a
//! hash of every file it reads — each model XML and its includes, the mesh/texture/height-field
//! files they name, the spec and the config in use (found as the run finds them) — with the
//! modellint and MuJoCo versions and the options that shape the output. An unchanged re-lint is
//! answered from the entry (a few kB) without compiling the model; an edit of any input, a mesh
//! included, is a new key. Runs that exit 2 (modellint could not do its job) and URDF models
//! (whose `package://` meshes MuJoCo resolves its own way) are not cached. Storage, size cap and
//! eviction: `model::cache`.

use std::path::{Path, PathBuf};

use crate::model::cache;

/// What one lint run printed and its exit code.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Entry {
    pub stdout: String,
    pub stderr: String,
    pub code: i32,
}

const MAGIC: &str = "modellint-lint-result 1";

impl Entry {
    fn to_bytes(&self) -> Vec<u8> {
        let head = format!("{MAGIC}\n{} {} {}\n", self.code, self.stderr.len(), self.stdout.len());
        [head.as_bytes(), self.stderr.as_bytes(), self.stdout.as_bytes()].concat()
    }

    /// `None` for anything but a whole entry (a truncated or foreign file is a miss).
    fn from_bytes(b: &[u8]) -> Option<Entry> {
        let text = std::str::from_utf8(b).ok()?;
        let rest = text.strip_prefix(MAGIC)?.strip_prefix('\n')?;
        let (head, body) = rest.split_once('\n')?;
        let mut it = head.split(' ');
        let code = it.next()?.parse::<i32>().ok()?;
        let ne = it.next()?.parse::<usize>().ok()?;
        let no = it.next()?.parse::<usize>().ok()?;
        if it.next().is_some() || body.len() != ne.checked_add(no)? {
            return None;
        }
        let (stderr, stdout) = (body.get(..ne)?, body.get(ne..)?);
        Some(Entry { stdout: stdout.to_string(), stderr: stderr.to_string(), code })
    }
}

/// The key of a lint of `models` with the spec and config given on the command line (else
/// found beside each model, as the run finds them) and `options` (every other option that
/// changes what is printed). `None` when an input cannot be listed or read: then the run is
/// not cached.
pub fn key(
    models: &[PathBuf],
    spec: &Option<PathBuf>,
    config: &Option<PathBuf>,
    options: &[String],
) -> Option<String> {
    let mut k = cache::KeyBuilder::default();
    for o in options {
        k.field(o.as_bytes());
    }
    for model in models {
        k.field(model.as_os_str().as_encoded_bytes());
        for f in crate::model::inputs(model)? {
            k.file(&f)?;
        }
        let found = crate::spec_use::discover(model);
        // A file passed over (a fit's effects file) is named in the output: its presence counts.
        for p in found.searched.iter().filter(|p| found.path.is_none() && p.is_file()) {
            k.field(p.as_os_str().as_encoded_bytes());
        }
        let spec = spec.clone().or(found.path);
        let config = config.clone().or_else(|| crate::config::discover(model));
        for (what, p) in [("spec", spec), ("config", config)] {
            k.field(what.as_bytes());
            match p {
                Some(p) => k.file(&p)?,
                None => k.field(b"none"),
            }
        }
    }
    Some(k.finish())
}

/// The stored result of the run with this key, when there is a whole one.
pub fn load(dir: &Path, key: &str) -> Option<Entry> {
    Entry::from_bytes(&cache::load(dir, key)?)
}

/// Stores a run's result (atomically; failures ignored), then evicts down to the cap. A run
/// that exited 2 is not stored.
pub fn store(dir: &Path, key: &str, e: &Entry) {
    if e.code < 2 {
        cache::store(dir, key, &e.to_bytes());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_round_trip_and_partial_ones_are_misses() {
        let e =
            Entry { stdout: "a.xml:1:2: warning x ü\n".into(), stderr: "note\n".into(), code: 1 };
        let b = e.to_bytes();
        assert_eq!(Entry::from_bytes(&b), Some(e.clone()));
        for cut in [0, 5, b.len() / 2, b.len() - 1] {
            assert_eq!(Entry::from_bytes(&b[..cut]), None, "cut at {cut}");
        }
        assert_eq!(Entry::from_bytes(b"not a MuJoCo model"), None);
        let empty = Entry { stdout: String::new(), stderr: String::new(), code: 0 };
        assert_eq!(Entry::from_bytes(&empty.to_bytes()), Some(empty));
    }
}
