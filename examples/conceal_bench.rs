//! Concealed-effect benchmark: hidden effects → synthetic recordings → blind `fit` → score.
//! `bench/conceal.sh [--quick] [--filter TERM[,TERM…]]` (see docs/conceal-benchmark.md).

#[path = "../bench/conceal_core.rs"]
mod conceal_core;

use conceal_core::*;

/// Hidden effects of a case: (effect, joints, parameters).
type Effects = Vec<(&'static str, Vec<String>, Vec<f64>)>;

/// One robot's cases: every effect on one joint, every effect on all recorded joints (as one
/// group; skipped for one-joint robots), the pairs, and a control.
fn robot_cases(
    label: &str,
    mk: &dyn Fn(&str, Kind, Effects) -> Case,
    one: &str,
    all: &[String],
    singles: &[(&'static str, Vec<f64>)],
) -> Vec<Case> {
    let mut v = Vec::new();
    for (e, p) in singles {
        v.push(mk(
            &format!("{label} {e}@{one}"),
            Kind::Single,
            vec![(*e, vec![one.to_string()], p.clone())],
        ));
    }
    if all.len() > 1 {
        for (e, p) in singles {
            v.push(mk(
                &format!("{label} {e}@all"),
                Kind::Group,
                vec![(*e, all.to_vec(), p.clone())],
            ));
        }
    }
    for pair in pair_truths(singles) {
        let name = pair.iter().map(|(e, _)| *e).collect::<Vec<_>>().join("+");
        v.push(mk(
            &format!("{label} {name}@{one}"),
            Kind::Pair,
            pair.into_iter().map(|(e, p)| (e, vec![one.to_string()], p)).collect(),
        ));
    }
    v.push(mk(&format!("{label} control"), Kind::Control, vec![]));
    v
}

fn matrix(quick: bool) -> Vec<Case> {
    let mut v = Vec::new();
    if quick {
        for (e, p) in arm3_single_truths()
            .iter()
            .filter(|(e, _)| ["action_delay", "armature", "position_offset"].contains(e))
        {
            v.push(arm3_case(
                &format!("arm3 {e}"),
                Kind::Single,
                vec![(*e, p.clone())],
                Noise::Real,
                7,
            ));
        }
        v.push(arm3_case(
            "arm3 armature+viscous_damping",
            Kind::Pair,
            vec![("armature", vec![0.04]), ("viscous_damping", vec![0.4])],
            Noise::Real,
            13,
        ));
        v.push(arm3_case("arm3 control", Kind::Control, vec![], Noise::Real, 11));
        v.push(pendulum_case("pendulum control", Kind::Control, vec![], Noise::Real, 11));
        return v;
    }
    let base: Vec<Case> = {
        let mut b = Vec::new();
        // Lightly damped pendulum servo (ζ ≈ 0.15), one joint.
        let pend = |n: &str, k, t: Vec<(&'static str, Vec<String>, Vec<f64>)>| {
            let mut c = pendulum_case(n, k, vec![], Noise::Real, 5);
            c.truth = t;
            c
        };
        b.extend(robot_cases(
            "pendulum",
            &pend,
            "servo",
            &["servo".to_string()],
            &pendulum_single_truths(),
        ));
        // Three-joint arm (arm3), effects on the elbow or on all three joints.
        let arm = |n: &str, k, t: Vec<(&'static str, Vec<String>, Vec<f64>)>| {
            let mut c = arm3_case(n, k, vec![], Noise::Real, 7);
            c.truth = t;
            c
        };
        b.extend(robot_cases("arm3", &arm, "elbow_pitch", &arm3_joints(), &arm3_single_truths()));
        // Large dry friction on the stiff arm (static 2 N·m against kp 50): the breakaway
        // step an order of magnitude above the 11 singles' values.
        b.push(arm(
            "arm3 stribeck_friction@elbow_pitch large",
            Kind::Single,
            vec![("stribeck_friction", vec!["elbow_pitch".to_string()], vec![2.0, 1.0, 0.2])],
        ));
        b.push(arm(
            "arm3 coulomb_friction@elbow_pitch large",
            Kind::Single,
            vec![("coulomb_friction", vec!["elbow_pitch".to_string()], vec![1.5])],
        ));
        b.push(arm(
            "arm3 gain_error@elbow_pitch slow",
            Kind::Single,
            vec![("gain_error", vec!["elbow_pitch".to_string()], vec![0.4, 2.0])],
        ));
        // Asimov legs on a test stand (12 joints), effects on the left knee or all leg joints.
        let asi = |n: &str, k, t| asimov_case(n, k, t, Noise::Real, 7);
        b.extend(robot_cases("asimov", &asi, "left_knee", &asimov_legs(), &asimov_single_truths()));
        // A humanoid-sized knee (kp 250, 150 N·m): values beyond a small servo's fit box.
        for (e, p) in heavy_knee_truths() {
            b.push(heavy_knee_case(
                &format!("knee {e}"),
                Kind::Single,
                vec![(e, p)],
                Noise::Real,
                7,
            ));
        }
        b.push(heavy_knee_case("knee control", Kind::Control, vec![], Noise::Real, 11));
        // The BAM XL330 rig (ζ ≈ 0.23): control and a few singles.
        for (e, p) in [
            ("action_delay", vec![0.02]),
            ("coulomb_friction", vec![0.03]),
            ("viscous_damping", vec![0.05]),
            ("armature", vec![0.005]),
        ] {
            b.push(rig_case(&format!("rig {e}"), Kind::Single, vec![(e, p)], Noise::Real, 5));
        }
        b.push(rig_case("rig control", Kind::Control, vec![], Noise::Real, 11));
        b
    };
    // Every case with the 12-bit encoder and without quantisation.
    for c in base {
        v.push(c.clone().unquantised());
        v.push(c);
    }
    // High noise controls.
    v.push(arm3_case("arm3 control", Kind::Control, vec![], Noise::High, 12));
    v.push(pendulum_case("pendulum control", Kind::Control, vec![], Noise::High, 12));
    // Booster T1 on a test stand (0.5 m above its keyframe), when the shared data is present.
    let t1 = root().join("../shared/data/models/booster_t1/t1.xml");
    if t1.exists() {
        let robot = load(&t1);
        let joints = actuated(&robot);
        let knees: Vec<String> =
            joints.iter().filter(|j| j.to_lowercase().contains("knee")).cloned().collect();
        let group = if knees.is_empty() { vec![joints[0].clone()] } else { knees };
        let mk = |name: &str, kind, truth| Case {
            name: name.into(),
            kind,
            model: t1.clone(),
            joints: joints.clone(),
            truth,
            noise: Noise::Real,
            episodes: 8,
            duration_s: 4.0,
            amplitude: 0.15,
            seed: 5,
            suspend_m: 0.5,
            quant_bits: 12,
        };
        v.push(mk(
            "t1 knees viscous_damping",
            Kind::Group,
            vec![("viscous_damping", group, vec![3.0])],
        ));
        v.push(mk("t1 control", Kind::Control, vec![]));
    } else {
        println!("note: {} is absent: Booster T1 cases skipped\n", t1.display());
    }
    v
}

/// `true` when `term` occurs in `label` with no letter or digit right before or after it: `rig`
/// is in "rig viscous_damping@j1" but not in "asimov armature@right_knee"; `knee` is in both
/// "right_knee" and "knee ...".
fn has_words(label: &str, term: &str) -> bool {
    let word = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric());
    // A term that begins (ends) with a space or punctuation needs no boundary there.
    let (open, close) = (word(term.chars().next()), word(term.chars().next_back()));
    !term.is_empty()
        && label.match_indices(term).any(|(i, _)| {
            let glued_before = open && word(label[..i].chars().next_back());
            let glued_after = close && word(label[i + term.len()..].chars().next());
            !glued_before && !glued_after
        })
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "--quick");
    let filter = args.iter().position(|a| a == "--filter").and_then(|i| args.get(i + 1)).cloned();
    // An argument it does not know (a typo of --filter, or --help) is not a run of every case.
    let known = |i: usize, a: &str| {
        a == "--quick" || a == "--filter" || (i > 0 && args[i - 1] == "--filter")
    };
    if let Some((_, a)) = args.iter().enumerate().find(|(i, a)| !known(*i, a)) {
        let help = a == "--help" || a == "-h";
        let usage = "usage: conceal_bench [--quick] [--filter TERM[,TERM...]]\n  \
            cases whose label has every TERM as whole words (e.g. --filter 'arm3,real 12b'; \
            'asimov armature@all,real none');\n  \
            markdown table on stdout, per-case rows and progress on stderr; \
            MODELLINT_CONCEAL_KEEP=DIR keeps the recordings";
        if help {
            println!("{usage}");
            return;
        }
        eprintln!("conceal_bench: unknown argument '{a}'\n{usage}");
        std::process::exit(2);
    }
    let cases: Vec<Case> = matrix(quick)
        .into_iter()
        .filter(|c| {
            // Comma-separated terms, all of which must occur as whole words (e.g.
            // `arm3,real 12b`; `rig` is the rig, not `right_knee`).
            let label = format!("{} {}", c.name, c.noise_label());
            filter.as_ref().is_none_or(|f| f.split(',').all(|t| has_words(&label, t)))
        })
        .collect();
    eprintln!("conceal bench: {} cases{}", cases.len(), if quick { " (--quick)" } else { "" });
    if cases.is_empty() {
        // Not "all targets met": nothing was run.
        eprintln!("conceal_bench: no case matches --filter '{}'", filter.unwrap_or_default());
        std::process::exit(2);
    }
    let mut scores = Vec::new();
    for (i, c) in cases.iter().enumerate() {
        let s = run(c);
        eprint!("[{}/{}] {}", i + 1, cases.len(), table_row(&s));
        eprintln!("    noise + quantisation floor (held-out, MAE): {:.3} mrad", 1e3 * s.mae_floor);
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
