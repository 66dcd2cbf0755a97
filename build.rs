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
fn main() {
    println!("cargo::rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
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
