//! Concealed-effect benchmark: hidden effects → synthetic recordings → blind `fit` → score.
//! `bench/conceal.sh [--quick] [--filter SUBSTRING]` (see docs/conceal-benchmark.md).

#[path = "../bench/conceal_core.rs"]
mod conceal_core;

use conceal_core::*;

fn matrix(quick: bool) -> Vec<Case> {
    let mut v = Vec::new();
    let singles = arm3_single_truths();
    if quick {
        for (e, p) in singles.iter().filter(|(e, _)| ["action_delay", "armature", "position_offset"].contains(e)) {
            v.push(arm3_case(&format!("arm3 {e}"), Kind::Single, vec![(*e, p.clone())], Noise::Real, 7));
        }
        v.push(arm3_case("arm3 armature+viscous_damping", Kind::Pair, vec![("armature", vec![0.04]), ("viscous_damping", vec![0.4])], Noise::Real, 13));
        v.push(arm3_case("arm3 control", Kind::Control, vec![], Noise::Real, 11));
        return v;
    }
    // Every effect alone on arm3's elbow, at two noise levels.
    for noise in [Noise::Real, Noise::High] {
        for (e, p) in &singles {
            v.push(arm3_case(&format!("arm3 {e}"), Kind::Single, vec![(*e, p.clone())], noise, 7));
        }
    }
    // Pendulum rig (one XL330 servo).
    for (e, p) in [("action_delay", vec![0.02]), ("coulomb_friction", vec![0.03]), ("viscous_damping", vec![0.05]), ("armature", vec![0.005])] {
        v.push(rig_case(&format!("rig {e}"), Kind::Single, vec![(e, p)], Noise::Real, 5));
    }
    // Pairs on one joint.
    let pairs: [(&str, Vec<(&'static str, Vec<f64>)>); 3] = [
        ("arm3 action_delay+coulomb_friction", vec![("action_delay", vec![0.02]), ("coulomb_friction", vec![0.15])]),
        ("arm3 armature+viscous_damping", vec![("armature", vec![0.04]), ("viscous_damping", vec![0.4])]),
        ("arm3 backlash+position_offset", vec![("backlash", vec![0.04]), ("position_offset", vec![0.05])]),
    ];
    for noise in [Noise::Real, Noise::High] {
        for (n, t) in &pairs {
            v.push(arm3_case(n, Kind::Pair, t.clone(), noise, 13));
        }
    }
    // Asimov legs on a test stand: effects on the left/right knee pair, and on one knee only
    // (must not be smeared over both sides by the mirror grouping).
    let knees = vec!["left_knee".to_string(), "right_knee".to_string()];
    v.push(asimov_case("asimov left knee viscous_damping", Kind::Single, vec![("viscous_damping", vec!["left_knee".to_string()], vec![3.0])], Noise::Real, 7));
    v.push(asimov_case("asimov knees viscous_damping", Kind::Group, vec![("viscous_damping", knees.clone(), vec![3.0])], Noise::Real, 5));
    v.push(asimov_case("asimov knees armature", Kind::Group, vec![("armature", knees.clone(), vec![0.15])], Noise::Real, 6));
    // Controls: nothing missing.
    v.push(arm3_case("arm3 control", Kind::Control, vec![], Noise::Real, 11));
    v.push(arm3_case("arm3 control", Kind::Control, vec![], Noise::High, 12));
    v.push(rig_case("rig control", Kind::Control, vec![], Noise::Real, 11));
    v.push(asimov_case("asimov control", Kind::Control, vec![], Noise::Real, 11));
    // Booster T1 (base fixed), when the shared data is present.
    let t1 = root().join("../shared/data/models/booster_t1/t1.xml");
    if t1.exists() {
        let robot = load(&t1);
        let joints = actuated(&robot);
        let knees: Vec<String> = joints.iter().filter(|j| j.to_lowercase().contains("knee")).cloned().collect();
        let group = if knees.is_empty() { vec![joints[0].clone()] } else { knees };
        let mk = |name: &str, kind, truth| Case { name: name.into(), kind, model: t1.clone(), joints: joints.clone(), truth, noise: Noise::Real, episodes: 8, duration_s: 4.0, amplitude: 0.15, seed: 5, suspend_m: 0.0 };
        v.push(mk("t1 knees viscous_damping", Kind::Group, vec![("viscous_damping", group, vec![3.0])]));
        v.push(mk("t1 control", Kind::Control, vec![]));
    } else {
        println!("note: {} is absent: Booster T1 cases skipped\n", t1.display());
    }
    v
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "--quick");
    let filter = args.iter().position(|a| a == "--filter").and_then(|i| args.get(i + 1)).cloned();
    let cases: Vec<Case> = matrix(quick).into_iter().filter(|c| filter.as_ref().is_none_or(|f| format!("{} {}", c.name, c.noise.label()).contains(f.as_str()))).collect();
    eprintln!("conceal bench: {} cases{}", cases.len(), if quick { " (--quick)" } else { "" });
    let mut scores = Vec::new();
    for (i, c) in cases.iter().enumerate() {
        let s = run(c, 3);
        eprint!("[{}/{}] {}", i + 1, cases.len(), table_row(&s));
        for w in &s.warnings {
            eprintln!("    warning: {w}");
        }
        eprintln!("    diagnosis: {}", s.diagnosis.join("; "));
        for t in &s.tried {
            eprintln!("    tried {t}");
        }
        scores.push(s);
    }
    print!("{}", table_header());
    for s in &scores {
        print!("{}", table_row(s));
    }
    let (text, _) = summary(&scores);
    println!("\n{text}");
}
