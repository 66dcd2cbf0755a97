//! Kept effects that are not missing physics: an effect whose every fitted parameter is within
//! [`Z_ABSENT`] standard errors of the value meaning "as modelled" (its start: the model's own
//! value for a MuJoCo-native parameter, else the default that means absent) has not been shown
//! to be there. `fit` names it in a note instead of the missing-physics list (issue 48: an
//! armature of 0.0000 ± 0.008 was listed as missing).
//!
//! Nor is a kept body effect whose value is the bound of its search ([`at_bound`]): where the
//! data push a point mass to the edge of the place it may have, the fitted values are that
//! edge, not an estimate of a body (issue 48: floatsim's clean `KFR0` came back with 0.30 kg at
//! 0.398 ± 0.089 m, its bound 0.4 m, the floor's compliance standing in).

use crate::fit::effects::{self, JointTarget, WriteBack};
use crate::fit::select::Selected;
use crate::model::Robot;

/// Standard errors within which a fitted value counts as its start value (two: a 95 % band
/// under the fit's own error model).
pub const Z_ABSENT: f64 = 2.0;

/// `Some(note)` when `s` is indistinguishable from its start on the model as given: every
/// fitted parameter `p` with `|p − p₀| ≤ Z_ABSENT · se` (an infinite standard error counts as
/// within). `None`: at least one parameter is away from its start beyond its uncertainty.
pub fn within_uncertainty(robot: &Robot, s: &Selected) -> Option<String> {
    let e = effects::by_id(&s.effect)?;
    let t = JointTarget::of(robot, s.joints.first()?)?;
    let start = e.initial(&robot.mj, &t);
    let mut shown = Vec::new();
    for (i, d) in e.params().iter().enumerate().take(e.fitted()) {
        let v = *s.params.get(d.name)?;
        let se = s.stderr.get(d.name).copied().unwrap_or(f64::INFINITY);
        let p0 = start.get(i).copied().unwrap_or(d.default);
        if se.is_finite() && (v - p0).abs() > Z_ABSENT * se {
            return None;
        }
        let se_text = if se.is_finite() { format!("{se:.2e}") } else { "?".into() };
        shown.push(format!("{} = {v:.4} ± {se_text} (as modelled {p0:.4})", d.name));
    }
    Some(format!(
        "{} on {}: {} — within {Z_ABSENT} standard errors of the model's own value, so not listed as missing physics (it stays in the fitted replay)",
        s.effect,
        s.joints.join(","),
        shown.join(", ")
    ))
}

/// Moves the kept effects that are within their uncertainty of the model as given out of
/// `selected`; returns their notes (in order).
pub fn split_off(robot: &Robot, selected: &mut Vec<Selected>) -> Vec<String> {
    let mut notes = Vec::new();
    selected.retain(|s| match within_uncertainty(robot, s) {
        Some(n) => {
            notes.push(n);
            false
        }
        None => true,
    });
    notes
}

/// `Some(warning)` when `s` is a body effect ([`WriteBack::Inertial`]) with an identified
/// parameter within [`Z_ABSENT`] standard errors of a bound of its search on the model as given
/// (`Effect::bounds`) that is not its start (a mass of 0 is absent, not bounded: [`within_uncertainty`]).
/// A bound is where the search stopped, not what the data determined: the effect as
/// parametrised (a body's mass, its place within one link length) cannot be what they want.
/// Joint effects are not judged so: their bounds grow with the drive (docs/fitting.md, Effects).
pub fn at_bound(robot: &Robot, s: &Selected) -> Option<String> {
    let e = effects::by_id(&s.effect)?;
    if e.write_back(&s.values) != WriteBack::Inertial {
        return None;
    }
    let t = JointTarget::of(robot, s.joints.first()?)?;
    let start = e.initial(&robot.mj, &t);
    let (lo, hi) = e.bounds(&robot.mj, &t);
    for (i, d) in e.params().iter().enumerate().take(e.fitted()) {
        let (Some(&v), Some(&se)) = (s.params.get(d.name), s.stderr.get(d.name)) else {
            continue;
        };
        if !se.is_finite() || s.unidentified.iter().any(|u| u == d.name) {
            continue;
        }
        let p0 = start.get(i).copied().unwrap_or(d.default);
        let hit = [lo.get(i), hi.get(i)]
            .into_iter()
            .flatten()
            .copied()
            .find(|&b| b != p0 && (v - b).abs() <= Z_ABSENT * se);
        if let Some(b) = hit {
            let unit = if d.unit.is_empty() { String::new() } else { format!(" {}", d.unit) };
            return Some(format!(
                "{} on {}: {} = {v:.4} ± {se:.2e}{unit} is at the bound of its search ({b:.4}{unit}, within {Z_ABSENT} standard errors) — the data push it beyond what this effect can be, so its values are the bound, not an estimate: not listed as missing physics (it stays in the fitted replay); what it stands in for is unexplained",
                s.effect,
                s.joints.join(","),
                d.name
            ));
        }
    }
    None
}

/// Moves the kept body effects at a bound of their search ([`at_bound`]) out of `selected`;
/// returns their warnings (in order).
pub fn split_off_at_bound(robot: &Robot, selected: &mut Vec<Selected>) -> Vec<String> {
    let mut warnings = Vec::new();
    selected.retain(|s| match at_bound(robot, s) {
        Some(w) => {
            warnings.push(w);
            false
        }
        None => true,
    });
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn sel(effect: &str, p: &[(&str, f64, f64)]) -> Selected {
        let mut s = Selected {
            effect: effect.into(),
            joints: vec!["j".into()],
            params: BTreeMap::new(),
            stderr: BTreeMap::new(),
            identifiable: true,
            unidentified: vec![],
            evidence: BTreeMap::new(),
            heldout_improvement: 0.1,
            heldout_rmse_before: 1.0,
            heldout_rmse_after: 0.9,
            window_improvement: 0.0,
            window_improvement_se: 0.0,
            bic_before: 0.0,
            bic_after: 0.0,
            values: p.iter().map(|x| x.1).collect(),
        };
        for (k, v, se) in p {
            s.params.insert(k.to_string(), *v);
            s.stderr.insert(k.to_string(), *se);
        }
        s
    }

    /// The issue's case: armature 0.0000 ± 0.008 on a joint modelled with none is not missing
    /// physics; 0.04 ± 0.008 is. On a joint modelled with armature 0.03, 0.031 ± 0.002 is the
    /// model's own value; a gain error (1.2, 1.0) ± 0.01 is away from (1, 1) in kp alone and is
    /// listed; one whose every parameter is unidentifiable is not.
    #[test]
    fn an_effect_at_its_start_within_its_uncertainty_is_not_listed() {
        let dir = std::env::temp_dir().join(format!("modellint-absent-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bare = effects::hinge_robot(&dir, "bare.xml", "", "", r#"kp="50" kv="2""#);
        let armed = effects::hinge_robot(&dir, "arm.xml", "", r#"armature="0.03""#, r#"kp="50""#);
        let zero = sel("armature", &[("armature", 0.0, 0.008)]);
        assert!(within_uncertainty(&bare, &zero).is_some_and(|n| n.contains("armature on j")));
        assert!(
            within_uncertainty(&bare, &sel("armature", &[("armature", 0.04, 0.008)])).is_none()
        );
        assert!(
            within_uncertainty(&armed, &sel("armature", &[("armature", 0.031, 0.002)])).is_some()
        );
        assert!(
            within_uncertainty(&armed, &sel("armature", &[("armature", 0.04, 0.002)])).is_none()
        );
        let gain = sel("gain_error", &[("kp_scale", 1.2, 0.01), ("kd_scale", 1.0, 0.01)]);
        assert!(within_uncertainty(&bare, &gain).is_none());
        let lost = sel(
            "gain_error",
            &[("kp_scale", 3.0, f64::INFINITY), ("kd_scale", 0.36, f64::INFINITY)],
        );
        assert!(within_uncertainty(&bare, &lost).is_some());
        let mut list = vec![zero, gain, lost];
        let notes = split_off(&bare, &mut list);
        assert_eq!(notes.len(), 2);
        assert_eq!(list.iter().map(|s| s.effect.as_str()).collect::<Vec<_>>(), ["gain_error"]);
        assert_eq!(list[0].params["kp_scale"], 1.2);
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A point mass on the test hinge's 0.2 m link (its place bounded to ±0.2 m): at
    /// 0.198 ± 0.01 m it is the bound, not a body, and is split off with a warning; at
    /// 0.15 ± 0.01 m it is listed; at the bound but not identified, or with no finite standard
    /// error, it is not judged so (the identifiability test speaks for it). An armature at its
    /// upper bound is a joint effect and not judged here.
    #[test]
    fn a_body_effect_at_the_bound_of_its_search_is_not_listed() {
        let dir = std::env::temp_dir().join(format!("modellint-bound-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let r = effects::hinge_robot(&dir, "bare.xml", "", "", r#"kp="50" kv="2""#);
        let t = JointTarget::of(&r, "j").unwrap();
        let lm = effects::by_id("link_mass").unwrap();
        let (_, hi) = lm.bounds(&r.mj, &t);
        assert!((hi[1] - 0.2).abs() < 1e-9, "{hi:?}");
        let mass = |offset: f64, se: f64| {
            let mut s = sel(
                "link_mass",
                &[("added_mass", 0.3, 0.05), ("offset", offset, se), ("across", 0.0, 0.01)],
            );
            s.joints = vec!["j".into()];
            s
        };
        let w = at_bound(&r, &mass(0.198, 0.01)).expect("at its bound");
        assert!(w.contains("link_mass on j: offset = 0.1980") && w.contains("(0.2000 m"), "{w}");
        assert!(at_bound(&r, &mass(0.15, 0.01)).is_none());
        assert!(at_bound(&r, &mass(-0.199, 0.01)).is_some());
        assert!(at_bound(&r, &mass(0.198, f64::INFINITY)).is_none());
        let mut hidden = mass(0.198, 0.01);
        hidden.unidentified = vec!["offset".into()];
        assert!(at_bound(&r, &hidden).is_none());
        // No mass: the lower bound of the mass is its start (absent, not bounded).
        let none = sel(
            "link_mass",
            &[("added_mass", 0.0, 0.05), ("offset", 0.1, 0.01), ("across", 0.0, 0.01)],
        );
        assert!(at_bound(&r, &none).is_none());
        let arm = effects::by_id("armature").unwrap();
        let top = arm.bounds(&r.mj, &JointTarget::of(&r, "j").unwrap()).1[0];
        assert!(at_bound(&r, &sel("armature", &[("armature", top, 0.01)])).is_none());
        let mut list = vec![mass(0.15, 0.01), mass(0.198, 0.01)];
        let w = split_off_at_bound(&r, &mut list);
        assert_eq!((w.len(), list.len()), (1, 1));
        assert_eq!(list[0].params["offset"], 0.15);
        std::fs::remove_dir_all(&dir).ok();
    }
}
