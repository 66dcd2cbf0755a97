//! MuJoCo's plugin libraries: a model that uses a first-party plugin (the `mujoco.pid`
//! actuator, `mujoco.elasticity.*`, the SDF shapes, the touch-grid sensor) compiles only once
//! the plugin's shared library is loaded. MuJoCo ships them beside the engine (`mujoco_plugin/`
//! of a release, `mujoco/plugin/` of the Python package); modellint links the engine alone, so
//! it loads the libraries of the directory `MUJOCO_PLUGIN_DIR` names, once, before the first
//! model compiles. A library in that directory that MuJoCo cannot load ends the process with
//! MuJoCo's own message (`mj_loadAllPluginLibraries`): point the variable at MuJoCo's plugin
//! directory of the same version (3.17), nothing else.

use std::path::PathBuf;
use std::sync::Once;

/// The environment variable naming the plugin directory.
pub const PLUGIN_DIR_VAR: &str = "MUJOCO_PLUGIN_DIR";

fn plugin_dir() -> Option<PathBuf> {
    std::env::var_os(PLUGIN_DIR_VAR).filter(|v| !v.is_empty()).map(PathBuf::from)
}

/// Loads the plugin libraries of `MUJOCO_PLUGIN_DIR` (if set and a directory), once.
pub fn load_once() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        if let Some(dir) = plugin_dir().filter(|d| d.is_dir()) {
            let _ = mujoco_rs::wrappers::load_all_plugin_libraries(&dir, None);
        }
    });
}

/// MuJoCo's compile error, with what to do when it names a plugin it does not know.
pub fn explain(msg: String) -> String {
    if !(msg.contains("plugin") && msg.contains("not found")) {
        return msg;
    }
    let state = match plugin_dir() {
        Some(d) if d.is_dir() => format!("{PLUGIN_DIR_VAR}={} holds no library of it", d.display()),
        Some(d) => format!("{PLUGIN_DIR_VAR}={} is not a directory", d.display()),
        None => format!("{PLUGIN_DIR_VAR} is not set"),
    };
    format!(
        "{msg}\n(the model uses a MuJoCo plugin and {state}: point {PLUGIN_DIR_VAR} at MuJoCo 3.17's plugin directory — `mujoco_plugin/` of a release, `site-packages/mujoco/plugin/` of the Python package — and modellint loads its libraries)"
    )
}
