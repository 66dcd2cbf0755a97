//! Embeds an rpath to MuJoCo so `modellint` runs without LD_LIBRARY_PATH, both from a checkout
//! and installed from the Python wheel (pyproject.toml). One binary serves both, so building the
//! wheel and `cargo build` share target/ without recompiling.
//!
//! Order of the RUNPATH entries:
//! 1. Installed from the wheel: the binary lives in the environment's scripts directory
//!    (`<prefix>/bin`) and `libmujoco.so.3.17.0` inside the `mujoco` package
//!    (`<prefix>/lib/python3.N/site-packages/mujoco`; `dist-packages` for Debian's system Python).
//!    The layout is the same for a venv, `pip install --user`, uv tool and pipx. The Python minor
//!    version is not known when the wheel is built, so every version that has a `mujoco==3.17.0`
//!    wheel (3.10–3.14) is listed. Entries that do not exist cost one failed open() each.
//! 2. From a checkout: the absolute `.mujoco/lib` the binary was linked against (`make build`,
//!    `cargo install --path .`), then `$ORIGIN`-relative fallbacks for binaries that stay in
//!    target/release/ (and its deps/ and examples/) of a moved checkout.
///
/// It also sets `MODELLINT_SOURCE_HASH`, a hash of every file under `src/`, which the lint cache
/// puts in its keys (`model::cache`): a build whose rules differ never answers from an entry
/// another build wrote, even at the same package version.
///
/// And `MODELLINT_VERSION`, what `modellint --version` prints: the package version and the
/// commit the binary was built from (`git rev-parse --short HEAD`), or the package version alone
/// where there is no git or no repository (a source archive, the wheel's sdist).
fn main() {
    println!("cargo::rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    println!("cargo::rerun-if-changed=src");
    println!("cargo::rustc-env=MODELLINT_SOURCE_HASH={:016x}", source_hash());
    let pkg = std::env::var("CARGO_PKG_VERSION").unwrap_or_default();
    let version = match git_commit() {
        Some(c) => format!("{pkg} (commit {c})"),
        None => pkg,
    };
    println!("cargo::rustc-env=MODELLINT_VERSION={version}");
    let mut paths = Vec::new();
    for minor in 10..=14 {
        for dir in ["site-packages", "dist-packages"] {
            paths.push(format!("$ORIGIN/../lib/python3.{minor}/{dir}/mujoco"));
        }
    }
    if let Ok(dir) = std::env::var("MUJOCO_DYNAMIC_LINK_DIR") {
        paths.push(dir);
    }
    paths.push("$ORIGIN/../../.mujoco/lib".into());
    paths.push("$ORIGIN/../../../.mujoco/lib".into());
    println!("cargo::rustc-link-arg=-Wl,-rpath,{}", paths.join(":"));
}

/// FNV-1a over the relative path and bytes of every file under `src/`, in sorted order.
fn source_hash() -> u64 {
    fn walk(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
        let Ok(rd) = std::fs::read_dir(dir) else { return };
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else {
                out.push(p);
            }
        }
    }
    let mut files = Vec::new();
    walk(std::path::Path::new("src"), &mut files);
    files.sort();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for f in files {
        eat(f.to_string_lossy().as_bytes());
        eat(&std::fs::read(&f).unwrap_or_default());
    }
    h
}

/// `git rev-parse --short HEAD` of the checkout being built, `None` without git or a repository.
/// Asks cargo to run this again when HEAD moves (the HEAD file, the branch's ref, packed refs).
fn git_commit() -> Option<String> {
    let git = |args: &[&str]| -> Option<String> {
        let o = std::process::Command::new("git").args(args).output().ok()?;
        let s = String::from_utf8(o.stdout).ok()?.trim().to_string();
        (o.status.success() && !s.is_empty()).then_some(s)
    };
    let commit = git(&["rev-parse", "--short", "HEAD"])?;
    if !commit.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    let mut watched = vec!["HEAD".to_string(), "packed-refs".to_string()];
    if let Some(r) = git(&["rev-parse", "--symbolic-full-name", "HEAD"]) {
        watched.push(r);
    }
    for w in watched {
        // Only files that exist: cargo runs a script that watches a missing one every build.
        if let Some(p) = git(&["rev-parse", "--git-path", &w])
            && std::path::Path::new(&p).exists()
        {
            println!("cargo::rerun-if-changed={p}");
        }
    }
    Some(commit)
}
