//! RUNPATH of the extension module: installed from the wheel it lives in
//! `site-packages/modellint/` and libmujoco in `site-packages/mujoco/` (the `mujoco` package it
//! depends on); from a checkout, the `.mujoco/lib` it was linked against.
fn main() {
    println!("cargo::rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    let mut paths = vec!["$ORIGIN/../mujoco".to_string()];
    if let Ok(dir) = std::env::var("MUJOCO_DYNAMIC_LINK_DIR") {
        paths.push(dir);
    }
    println!("cargo::rustc-link-arg=-Wl,-rpath,{}", paths.join(":"));
}
