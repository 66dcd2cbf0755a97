//! Embeds an rpath to the project's MuJoCo so `modellint` runs without LD_LIBRARY_PATH.
fn main() {
    println!("cargo::rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    if let Ok(dir) = std::env::var("MUJOCO_DYNAMIC_LINK_DIR") {
        // Absolute path to the library the binary was linked against, plus an $ORIGIN-relative
        // fallback for a binary that stays inside target/{debug,release}/ of a moved checkout.
        println!("cargo::rustc-link-arg=-Wl,-rpath,{dir}");
        println!("cargo::rustc-link-arg=-Wl,-rpath,$ORIGIN/../../.mujoco/lib");
        println!("cargo::rustc-link-arg=-Wl,-rpath,$ORIGIN/../../../.mujoco/lib");
    }
}
