//! Spec discovery and what a missing spec costs. Without a hardware spec some rules have nothing
//! to compare against and stay silent, others fall back to what the model file alone shows. The
//! run says so once, naming where it looked (`modellint` on stderr, `spec` in JSON).

use std::path::{Path, PathBuf};

/// Rules that return without a spec (they compare the model with hardware facts only the spec
/// states), with the fact each needs.
/// Exactly the rules with no spec-less check (a test lints every fixture without a spec and
/// fails on a finding of a rule listed here).
pub const SKIPPED: &[(&str, &str)] = &[
    ("missing-action-delay", "control rate and measured action delay"),
    ("urdf-mjcf-drift", "the companion URDF to compare with"),
    ("mass-budget", "the weighed robot's mass"),
];

/// Rules that run without a spec but check less, and what they fall back to.
pub const WEAKENED: &[(&str, &str)] = &[
    (
        "armature-mismatch",
        "no rotor inertia or gear ratio: only one armature shared by joints of very different force limits",
    ),
    (
        "parallel-ankle-armature",
        "no motor counts: only values exactly 2 × another joint's, on passive joints or on single-motor joints while the model shows its two-motor joints (tendons, ankles)",
    ),
    (
        "actuator-mapping",
        "no actuated/passive joint list: only ctrlranges outside their joint's range",
    ),
    ("effort-limit-mismatch", "no motor peak torque: only the model's own limits are compared"),
    ("soft-limits", "soft-limit factor assumed 1.0"),
    ("underdamped-pd-gains", "only joints with position actuators (no spec kp/kd)"),
    ("gains-unstable-for-timestep", "only joints with position actuators (no spec kp/kd)"),
    ("toe-tilt", "feet found by body names, not the spec's foot_bodies"),
    ("foot-collision-geometry", "feet found by body names; no intended friction/condim"),
    ("collision-visual-mismatch", "feet found by body names, not the spec's foot_bodies"),
    ("mirror-asymmetry", "left/right found by common name patterns, not the spec's left/right"),
];

/// Where the spec was looked for, and what was found.
#[derive(Debug, Clone, Default)]
pub struct SpecSearch {
    /// The spec in use (given with --spec, or found).
    pub path: Option<PathBuf>,
    /// Every place looked at, in order (empty when --spec was given).
    pub searched: Vec<PathBuf>,
}

/// `<model>.toml` beside the model; when the model includes other files (a scene including the
/// robot file), `<included>.toml` beside each included file too, in include order.
pub fn discover(model: &Path) -> SpecSearch {
    let mut searched = vec![model.with_extension("toml")];
    let mut seen = vec![model.to_path_buf()];
    included_files(model, model.parent().unwrap_or(Path::new("")), &mut seen, 0);
    for inc in seen.iter().skip(1) {
        let p = inc.with_extension("toml");
        if !searched.contains(&p) {
            searched.push(p);
        }
    }
    let path = searched.iter().find(|p| p.is_file() && !is_fit_effects(p)).cloned();
    SpecSearch { path, searched }
}

/// Whether `p` is the effects file `modellint fit --write-actuators` writes (top-level
/// `[[effect]]` tables), not a hardware spec: written beside a fitted model of the same stem, it
/// would otherwise be picked up as that model's spec and rejected.
pub fn is_fit_effects(p: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(p) else { return false };
    if text.starts_with("# Written by `modellint fit`: effects") {
        return true;
    }
    let Ok(v) = text.parse::<toml::Table>() else { return false };
    v.get("effect").is_some_and(|e| e.is_array()) && !v.contains_key("robot")
}

/// The models to lint for the paths given (several, or under `--skip-non-models`): a hardware
/// spec among them (the pre-commit hook passes a staged `robot.toml` whose edit changes what the
/// spec-only rules say) stands for the model of its name beside it, `robot.xml`, else
/// `robot.urdf`; each such swap has a note for stderr. A `.toml` with no model beside it stays as
/// given (not a model).
pub fn models_for_args(args: &[PathBuf]) -> (Vec<PathBuf>, Vec<String>) {
    let mut notes = Vec::new();
    let models = args
        .iter()
        .map(|p| {
            if !p.extension().is_some_and(|e| e.eq_ignore_ascii_case("toml")) {
                return p.clone();
            }
            match ["xml", "urdf"].iter().map(|e| p.with_extension(e)).find(|m| m.is_file()) {
                Some(m) => {
                    notes.push(format!(
                        "modellint: {} is the spec of {}: linting the model\n",
                        p.display(),
                        m.display()
                    ));
                    m
                }
                None => p.clone(),
            }
        })
        .collect();
    (models, notes)
}

/// Every file `model` includes (directly or through other includes), as MuJoCo resolves them.
pub fn includes(model: &Path) -> Vec<PathBuf> {
    let mut seen = vec![model.to_path_buf()];
    included_files(model, model.parent().unwrap_or(Path::new("")), &mut seen, 0);
    seen.into_iter().skip(1).collect()
}

/// Included files of an MJCF file (paths relative to the main model's directory, as MuJoCo
/// resolves them), depth first. Unreadable or malformed files are skipped here: the loader
/// reports them with their location.
fn included_files(file: &Path, base: &Path, seen: &mut Vec<PathBuf>, depth: usize) {
    if depth > 16 {
        return;
    }
    let Ok(text) = std::fs::read_to_string(file) else { return };
    let opts = roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() };
    let Ok(doc) = roxmltree::Document::parse_with_options(&text, opts) else { return };
    for n in doc.descendants().filter(|n| n.has_tag_name("include")) {
        let Some(f) = n.attribute("file") else { continue };
        let p = base.join(f);
        if seen.contains(&p) {
            continue;
        }
        seen.push(p.clone());
        included_files(&p, base, seen, depth + 1);
    }
}

/// The one-paragraph note for a run without a spec.
pub fn missing_note(model: &Path, s: &SpecSearch, enabled: &dyn Fn(&str) -> bool) -> String {
    let looked: Vec<String> = s
        .searched
        .iter()
        .map(|p| {
            if p.is_file() && is_fit_effects(p) {
                format!("{} (a `modellint fit` effects file, not a spec)", p.display())
            } else {
                p.display().to_string()
            }
        })
        .collect();
    let skipped: Vec<&str> = SKIPPED.iter().map(|r| r.0).filter(|id| enabled(id)).collect();
    let weakened: Vec<&str> = WEAKENED.iter().map(|r| r.0).filter(|id| enabled(id)).collect();
    let mut out = format!(
        "modellint: {}: no hardware spec found (looked for {}; pass --spec FILE.toml; `modellint docs spec`)",
        model.display(),
        looked.join(", ")
    );
    if !skipped.is_empty() {
        out.push_str(&format!("\n  skipped without a spec: {}", skipped.join(", ")));
    }
    if !weakened.is_empty() {
        out.push_str(&format!("\n  weakened without a spec: {}", weakened.join(", ")));
    }
    out.push('\n');
    out
}

/// Rule ids with the spec keys each is missing.
pub type Waiting = Vec<(&'static str, String)>;

/// Rules a spec in use leaves without the facts they need (keys not set, e.g. placeholders of
/// `modellint init-spec` not filled in): (skipped, weakened), each rule with the missing keys.
pub fn waiting(spec: &crate::spec::Spec, robot: &crate::model::Robot) -> (Waiting, Waiting) {
    use crate::spec::v;
    let r = &spec.robot;
    let mut skipped = Vec::new();
    let mut weakened = Vec::new();
    let mut keys = Vec::new();
    if r.control_hz.is_none() {
        keys.push("robot.control_hz");
    }
    if r.action_delay_steps.is_none() {
        keys.push("robot.action_delay_steps");
    }
    if !keys.is_empty() && !robot.actuators.is_empty() {
        skipped.push(("missing-action-delay", keys.join(", ")));
    }
    if r.mass_kg.is_none() {
        skipped.push(("mass-budget", "robot.mass_kg".to_string()));
    }
    // Only when there is a URDF to compare with: `<model>.urdf` beside the model.
    if r.companion_urdf.is_none()
        && robot.format == crate::model::Format::Mjcf
        && robot.path.with_extension("urdf").is_file()
    {
        skipped.push(("urdf-mjcf-drift", "robot.companion_urdf".to_string()));
    }
    // Families the actuated joints use, and what each states.
    let mut used: Vec<String> = robot
        .joints
        .iter()
        .filter(|j| j.is_scalar() && !robot.actuators_on_joint(j.id).is_empty())
        .filter_map(|j| spec.joint(&j.name).filter(|f| !f.passive)?.motor)
        .collect();
    used.sort();
    used.dedup();
    let motors: Vec<&crate::spec::Motor> = used.iter().filter_map(|f| spec.motor(f)).collect();
    let any = |f: &dyn Fn(&crate::spec::Motor) -> bool| motors.iter().any(|m| f(m));
    if !any(&|m| v(&m.rotor_inertia).is_some_and(|x| x > 0.0) && v(&m.gear_ratio).is_some()) {
        let what = "motors.*.rotor_inertia and gear_ratio".to_string();
        weakened.push(("armature-mismatch", what.clone()));
        weakened.push(("parallel-ankle-armature", what));
    }
    if !any(&|m| m.peak_torque.is_some()) {
        weakened.push(("effort-limit-mismatch", "motors.*.peak_torque".to_string()));
    }
    let torque_driven = robot.joints.iter().any(|j| {
        j.is_scalar()
            && robot
                .actuators_on_joint(j.id)
                .iter()
                .any(|a| a.kind == crate::model::ActuatorKind::Motor)
    });
    if torque_driven && !any(&|m| m.kp.is_some() && m.kd.is_some()) {
        let what = "motors.*.kp and kd (the model drives joints by torque)".to_string();
        weakened.push(("underdamped-pd-gains", what.clone()));
        weakened.push(("gains-unstable-for-timestep", what));
    }
    (skipped, weakened)
}

/// The note for a run whose spec leaves rules without their facts (`None`: nothing waits).
pub fn waiting_note(
    model: &Path,
    spec_path: &Path,
    skipped: &[(&str, String)],
    weakened: &[(&str, String)],
) -> Option<String> {
    if skipped.is_empty() && weakened.is_empty() {
        return None;
    }
    let list = |v: &[(&str, String)]| {
        v.iter().map(|(id, k)| format!("{id} ({k})")).collect::<Vec<_>>().join(", ")
    };
    let mut out = format!(
        "modellint: {}: the spec {} does not set every fact the rules use",
        model.display(),
        spec_path.display()
    );
    if !skipped.is_empty() {
        out.push_str(&format!("\n  not run: {}", list(skipped)));
    }
    if !weakened.is_empty() {
        out.push_str(&format!("\n  run as without a spec: {}", list(weakened)));
    }
    out.push('\n');
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_rule_exists() {
        for (id, _) in SKIPPED.iter().chain(WEAKENED) {
            assert!(crate::rules::find_meta(id).is_some(), "unknown rule `{id}` in spec_use");
        }
    }

    /// `fit --write-actuators fitted.toml` beside `--write-model fitted.xml` is not that model's
    /// spec: discovery passes over it (and the note says why) instead of rejecting it as a bad spec.
    #[test]
    fn a_fit_effects_file_beside_the_model_is_not_its_spec() {
        let dir = std::env::temp_dir().join(format!("modellint-specuse-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let model = dir.join("fitted.xml");
        std::fs::write(&model, "<mujoco/>").unwrap();
        let toml = dir.join("fitted.toml");
        for text in [
            crate::fit::writeback::actuators_toml(&[]),
            "[[effect]]\nid = \"gain_error\"\njoints = [\"elbow\"]\n".to_string(),
        ] {
            std::fs::write(&toml, text).unwrap();
            let s = discover(&model);
            assert_eq!(s.path, None, "an effects file is not a spec");
            assert!(missing_note(&model, &s, &|_| true).contains("effects file, not a spec"));
        }
        std::fs::write(&toml, "[robot]\ncontrol_hz = 50\n").unwrap();
        assert_eq!(discover(&model).path.as_deref(), Some(toml.as_path()), "a spec is");
        std::fs::remove_dir_all(&dir).ok();
    }
}
