use std::collections::BTreeMap;
use std::path::Path;

use super::*;
use crate::fit::effects::{self, Applied, by_id, model_with};
use crate::fit::effects::{Armature, CoulombFriction, Effect, JointStiffness, StribeckFriction};
use crate::fit::select::FitOptions;
use crate::fit::select::engine::Engine;
use crate::fit::select::polish::polish_budget;
use crate::fit::select::prune::simpler_set_ok;
use crate::fit::select::verdict::verdict;
use crate::fit::select::{Errors, FitOutcome, Search, SearchPolicy, Selected};
use crate::fit::split::split;
use crate::fit::stats::bic_pieces;
use crate::model::Robot;
use crate::model::source::SourceMap;
use crate::sim2real::recording::Recording;
use crate::sim2real::recording::read_csv;
use crate::synth::{self, Settings, truth::Hidden};

type Pass = fn(&Search, usize, &mut FitOutcome) -> bool;

/// arm3 (each joint's armature 0.01 kg·m², no frictionloss; `attrs` sets one joint
/// attribute each) with `hidden`, recorded by the independent synth and read back from CSV.
fn recorded(
    tag: &str,
    attrs: &[(&str, &str, f64)],
    hidden: &[(&str, &str, &[f64])],
) -> (Robot, Vec<Recording>) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut xml = std::fs::read_to_string(root.join("fixtures/gap/arm3.xml")).expect("arm3");
    for (j, attr, v) in attrs {
        let from = format!("<joint name=\"{j}\"/>");
        assert!(xml.contains(&from), "{from}");
        xml = xml.replace(&from, &format!("<joint name=\"{j}\" {attr}=\"{v}\"/>"));
    }
    let dir = std::env::temp_dir().join(format!("modellint_simplify_{tag}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("arm3.xml");
    std::fs::write(&path, xml).expect("write model");
    let robot = crate::model::load(&mut SourceMap::default(), &path, None).expect("arm3");
    let joints: Vec<String> =
        ["shoulder_pitch", "elbow_pitch", "wrist_pitch"].map(String::from).to_vec();
    let hidden: Vec<Hidden> = hidden
        .iter()
        .map(|(e, j, p)| Hidden {
            effect: by_id(e).expect("effect").id(),
            joint: (*j).into(),
            params: p.to_vec(),
        })
        .collect();
    let s =
        Settings { episodes: 8, duration_s: 4.0, amplitude: 0.5, seed: 7, ..Settings::default() };
    let ds = synth::generate(&robot, &joints, &hidden, &s, &|_, _| {}).expect("synth");
    let files = synth::write::write(&ds, &dir.join("rec")).expect("write");
    let recs = files.iter().map(|f| read_csv(f).expect("read")).collect();
    let _ = std::fs::remove_dir_all(&dir);
    (robot, recs)
}

fn applied(id: &str, joints: &[&str], params: &[f64]) -> Applied {
    Applied {
        effect: by_id(id).expect("effect"),
        joints: joints.iter().map(|j| j.to_string()).collect(),
        params: params.to_vec(),
    }
}

/// Runs `pass` on the kept set `start`; returns the outcome and whether the set changed.
fn run(pass: Pass, robot: &Robot, recs: &[Recording], start: Vec<Applied>) -> (FitOutcome, bool) {
    let opts = FitOptions::default();
    let engine = Engine::new(robot, recs, &opts);
    let sp = split(recs, opts.holdout);
    let allowed: Vec<String> = effects::all().iter().map(|e| e.id().to_string()).collect();
    let s = Search { engine: &engine, train: &sp.train, heldout: &sp.heldout, allowed: &allowed };
    let h = engine.errors(&sp.heldout, &start).expect("replay");
    let mut out = FitOutcome::empty(String::new());
    for a in &start {
        let v = verdict(&h, &h, &a.joints, SearchPolicy::default().gate());
        out.selected.push(Selected::new(a, BTreeMap::new(), &v, 1.0, 1.0, (0.0, 0.0)));
    }
    out.applied = start;
    let changed = pass(&s, 2, &mut out);
    (out, changed)
}

fn near(got: &[f64], truth: &[f64], rel: f64) -> bool {
    got.len() == truth.len() && got.iter().zip(truth).all(|(g, t)| (g - t).abs() <= rel * t.abs())
}

const STRIBECK: [f64; 3] = [0.3, 0.1, 0.2];

/// The Asimov failure, on arm3: Coulomb friction taken first, then a Stribeck friction with
/// its levels short by the Coulomb part. The fold gives one Stribeck friction at the truth.
#[test]
fn coulomb_next_to_stribeck_folds_into_stribeck() {
    // The model's own frictionloss on the elbow is 0.2 N·m (the truth adds the Stribeck
    // friction to it): the fold must take only the Coulomb part above it.
    let (robot, recs) = recorded(
        "fold",
        &[("elbow_pitch", "frictionloss", 0.2)],
        &[(StribeckFriction.id(), "elbow_pitch", &STRIBECK)],
    );
    let t = JointTarget::of(&robot, "elbow_pitch").expect("elbow");
    let c0 = by_id(CoulombFriction.id()).expect("coulomb").initial(&model_with(&robot, &[]), &t)[0];
    assert!((c0 - 0.2).abs() < 1e-12, "model frictionloss {c0}");
    // Coulomb took 0.12 N·m above the model's frictionloss, Stribeck a part of the rest:
    // folded, (0.22, 0.12, 0.14) is 20–30 % off the truth; the polish must bring it there.
    // (Adding the whole 0.32 instead would start at (0.42, 0.32, 0.14).)
    let start = vec![
        applied(CoulombFriction.id(), &["elbow_pitch"], &[c0 + 0.12]),
        applied(StribeckFriction.id(), &["elbow_pitch"], &[0.10, 0.0, 0.14]),
    ];
    // The folded start, by hand: 0.10 + 0.12, 0.0 + 0.12, 0.14.
    let got = absorbed_start(&robot, &start[1..], &start[1], &start[0]).expect("absorbs");
    assert!(near(&got, &[0.22, 0.12, 0.14], 1e-9), "folded start {got:?}");
    let (out, folded) = run(fold_pass, &robot, &recs, start);
    assert!(folded, "no fold; tried {:?}", out.tried);
    assert_eq!(out.applied.len(), 1, "{:?}", out.applied);
    let a = &out.applied[0];
    assert_eq!(a.effect.id(), StribeckFriction.id());
    assert!(near(&a.params, &STRIBECK, 0.05), "fitted {:?} for {STRIBECK:?}", a.params);
    assert_eq!(out.selected.len(), 1);
    assert!(out.selected[0].evidence.contains_key("absorbs_coulomb_friction"));
    assert!(out.tried.iter().any(|t| t.phase == Phase::Fold && t.kept));
}

/// Must not fire: the two frictions on different joints are not one effect.
#[test]
fn frictions_on_different_joints_do_not_fold() {
    let (robot, recs) =
        recorded("apart", &[], &[(StribeckFriction.id(), "elbow_pitch", &STRIBECK)]);
    let start = vec![
        applied(CoulombFriction.id(), &["shoulder_pitch"], &[0.05]),
        applied(StribeckFriction.id(), &["elbow_pitch"], &STRIBECK),
    ];
    let (out, folded) = run(fold_pass, &robot, &recs, start);
    assert!(!folded);
    assert_eq!(out.applied.len(), 2);
    assert!(out.tried.iter().all(|t| t.phase != Phase::Fold));
}

/// Armature 0.04 kg·m² on the three joints, whose model values differ (shoulder 0.02, the
/// others 0.01): found as a group of two (0.047) and on the elbow alone (0.022), the two
/// are one group at the truth. The start, weighted by joint count, is 0.0387 (3.3 % off;
/// unweighted 0.0345): the polish must bring it within 2 %.
#[test]
fn armatures_from_different_model_values_merge() {
    let (robot, recs) = recorded(
        "merge",
        &[("shoulder_pitch", Armature.id(), 0.02)],
        &[
            (Armature.id(), "shoulder_pitch", &[0.04]),
            (Armature.id(), "elbow_pitch", &[0.04]),
            (Armature.id(), "wrist_pitch", &[0.04]),
        ],
    );
    let start = vec![
        applied(Armature.id(), &["shoulder_pitch", "wrist_pitch"], &[0.047]),
        applied(Armature.id(), &["elbow_pitch"], &[0.022]),
    ];
    let (out, merged) = run(merge_pass, &robot, &recs, start);
    assert!(merged, "no merge; tried {:?}", out.tried);
    assert_eq!(out.applied.len(), 1, "{:?}", out.applied);
    let a = &out.applied[0];
    assert_eq!(a.joints, ["shoulder_pitch", "elbow_pitch", "wrist_pitch"]);
    eprintln!("merged: {:?}", a.params);
    assert!(near(&a.params, &[0.04], 0.02), "fitted {:?} for 0.04", a.params);
    assert!(out.tried.iter().any(|t| t.phase == Phase::Merge && t.kept));
}

/// Armature 0.04 kg·m² on the shoulder and wrist, 0.0402 on the elbow (0.5 % apart):
/// fitted as two groups, each at its training optimum, the two values are a hair apart and
/// the per-sample BIC reads them as two parameters (the Asimov legs' two armature groups,
/// both 0.1501 kg·m² to four digits, were kept apart so). Counted per window they are one:
/// the merge is made, within 1 % of both values. Fails if the merge goes back to the
/// per-sample BIC; `different_armatures_do_not_merge` is the other side.
#[test]
fn armatures_a_hair_apart_merge() {
    let (robot, recs) = recorded(
        "hair",
        &[],
        &[
            (Armature.id(), "shoulder_pitch", &[0.04]),
            (Armature.id(), "elbow_pitch", &[0.0402]),
            (Armature.id(), "wrist_pitch", &[0.04]),
        ],
    );
    let opts = FitOptions::default();
    let engine = Engine::new(&robot, &recs, &opts);
    let sp = split(&recs, opts.holdout);
    let start = vec![
        applied(Armature.id(), &["shoulder_pitch", "wrist_pitch"], &[0.04]),
        applied(Armature.id(), &["elbow_pitch"], &[0.04]),
    ];
    let start = polish_budget(&engine, &sp.train, &sp.train, start, 0.02, 400);
    let (a, b) = (start[0].params[0], start[1].params[0]);
    assert!(near(&[a, b], &[0.04, 0.0402], 0.002), "two groups {a}, {b}");
    // The case is the one claimed: the one value costs more than a parameter per sample,
    // less than one per window.
    let one = vec![applied(
        Armature.id(),
        &["shoulder_pitch", "elbow_pitch", "wrist_pitch"],
        &[(2.0 * a + b) / 3.0],
    )];
    let one = polish_budget(&engine, &sp.train, &sp.train, one, 0.02, 400);
    let (t1, t2) = (
        engine.errors(&sp.train, &one).expect("replay"),
        engine.errors(&sp.train, &start).expect("replay"),
    );
    let m = t2.windows.len();
    assert!(bic(t1.n, t1.sse, 1) > bic(t2.n, t2.sse, 2), "per sample the two are one");
    assert!(bic_pieces(m, t1.n, t1.sse, 1) <= bic_pieces(m, t2.n, t2.sse, 2));
    let (out, merged) = run(merge_pass, &robot, &recs, start);
    assert!(merged, "no merge; tried {:?}", out.tried);
    assert_eq!(out.applied.len(), 1, "{:?}", out.applied);
    let g = &out.applied[0];
    assert_eq!(g.joints, ["shoulder_pitch", "elbow_pitch", "wrist_pitch"]);
    assert!(near(&g.params, &[0.0401], 0.01), "merged at {:?}", g.params);
}

/// Two groups' values agree when they differ by at most 2 standard errors of the
/// difference: the Asimov legs' armatures (0.150124 and 0.150064, ± 3e-5 each: 1.4) do,
/// 0.03 and 0.06 ± 1e-4 do not, nor do values without a finite standard error. Every fitted
/// parameter must agree (a Stribeck friction whose velocity scales differ does not).
#[test]
fn values_agree_within_their_standard_errors() {
    let se = |v: &[(&str, f64)]| -> BTreeMap<String, f64> {
        v.iter().map(|(k, x)| (k.to_string(), *x)).collect()
    };
    let name = |id: &str, k: usize| by_id(id).unwrap().params()[k].name;
    let arm = name(Armature.id(), 0);
    let (a, b) =
        (applied(Armature.id(), &["a"], &[0.150124]), applied(Armature.id(), &["b"], &[0.150064]));
    let s3 = se(&[(arm, 3e-5)]);
    assert!(values_agree(&a, &b, &s3, &s3));
    assert!(!values_agree(&a, &b, &se(&[(arm, 1e-5)]), &se(&[(arm, 1e-5)])));
    let (c, d) = (applied(Armature.id(), &["a"], &[0.03]), applied(Armature.id(), &["b"], &[0.06]));
    let s4 = se(&[(arm, 1e-4)]);
    assert!(!values_agree(&c, &d, &s4, &s4));
    assert!(!values_agree(&a, &b, &se(&[(arm, f64::INFINITY)]), &s3));
    assert!(!values_agree(&a, &b, &se(&[(arm, f64::NAN)]), &s3));
    assert!(!values_agree(&a, &b, &se(&[]), &s3));
    // Two parameters: one level agrees, the velocity scale does not.
    let st = by_id(StribeckFriction.id()).unwrap();
    let k = st.fitted();
    assert!(k >= 2, "stribeck fits {k}");
    let names: Vec<&str> = (0..k).map(|i| name(StribeckFriction.id(), i)).collect();
    let pa: Vec<f64> = (0..k).map(|i| 0.1 + i as f64).collect();
    let mut pb = pa.clone();
    let sab = se(&names.iter().map(|n| (*n, 0.01)).collect::<Vec<_>>());
    let (x, y) =
        (applied(StribeckFriction.id(), &["a"], &pa), applied(StribeckFriction.id(), &["b"], &pb));
    assert!(values_agree(&x, &y, &sab, &sab));
    pb[k - 1] += 0.5;
    let y = applied(StribeckFriction.id(), &["b"], &pb);
    assert!(!values_agree(&x, &y, &sab, &sab));
}

/// The drop with re-fit counts the training BIC per window: 400 windows of 100 samples,
/// held-out unchanged, the remainder's training SSE 0.6 % higher with one parameter fewer
/// is a drop (per sample, 240 of likelihood against ln 40000 = 10.6 of penalty, it was
/// not); 5 % higher is not (19.5 against ln 400 = 6.0), nor is a held-out error worse
/// beyond noise.
#[test]
fn drop_refit_counts_the_bic_per_window() {
    let errs = |w: &[f64], scale: f64| {
        let w: Vec<f64> = w.iter().map(|v| v * scale).collect();
        Errors {
            sse: w.iter().map(|v| v * v * 100.0).sum(),
            n: 100 * w.len(),
            windows: w.iter().map(|v| ("j".to_string(), *v)).collect(),
            eps: vec![],
        }
    };
    let base: Vec<f64> = (0..400).map(|i| 1e-3 * (1.0 + 0.3 * ((i * 7) % 11) as f64)).collect();
    let (h, t) = (errs(&base, 1.0), errs(&base, 1.0));
    let j = ["j".to_string()];
    let t_hair = errs(&base, 1.006f64.sqrt());
    assert!(bic(t_hair.n, t_hair.sse, 2) > bic(t.n, t.sse, 3), "per sample: kept");
    assert_eq!(
        simpler_set_ok(&SearchPolicy::default(), (&h, &t_hair, 2), (&h, &t, 3), &j, true, false),
        (true, false, true)
    );
    let t_more = errs(&base, 1.05f64.sqrt());
    assert_eq!(
        simpler_set_ok(&SearchPolicy::default(), (&h, &t_more, 2), (&h, &t, 3), &j, true, false),
        (false, false, false)
    );
    let h_worse = errs(&base, 1.03);
    let (ok, worse, _) = simpler_set_ok(
        &SearchPolicy::default(),
        (&h_worse, &t_hair, 2),
        (&h, &t, 3),
        &j,
        true,
        false,
    );
    assert!(!ok && worse);
}

/// Joint stiffness 10 N·m/rad on the three joints (every joint starts from the model's 0,
/// so the group has a start of its own), found as two groups that agree exactly: merged at
/// those values the model is the same with one parameter fewer, so the merge must be made
/// and its training error must not be above the two groups' (a fresh fit from 0 that stops
/// short of them, as at 19.987 for 20.000 on the Asimov legs, loses the BIC test).
#[test]
fn equal_stiffnesses_merge_at_their_own_value() {
    let k = [10.0];
    let (robot, recs) = recorded(
        "stiff",
        &[],
        &[
            (JointStiffness.id(), "shoulder_pitch", &k),
            (JointStiffness.id(), "elbow_pitch", &k),
            (JointStiffness.id(), "wrist_pitch", &k),
        ],
    );
    let start = vec![
        applied(JointStiffness.id(), &["shoulder_pitch", "wrist_pitch"], &k),
        applied(JointStiffness.id(), &["elbow_pitch"], &k),
    ];
    let opts = FitOptions::default();
    let engine = Engine::new(&robot, &recs, &opts);
    let sp = split(&recs, opts.holdout);
    let t_cur = engine.errors(&sp.train, &start).expect("replay").rmse();
    let (out, merged) = run(merge_pass, &robot, &recs, start);
    assert!(merged, "no merge; tried {:?}", out.tried);
    assert_eq!(out.applied.len(), 1, "{:?}", out.applied);
    let a = &out.applied[0];
    assert_eq!(a.joints, ["shoulder_pitch", "elbow_pitch", "wrist_pitch"]);
    assert!(near(&a.params, &k, 0.01), "fitted {:?} for {k:?}", a.params);
    let t_new = engine.errors(&sp.train, &out.applied).expect("replay").rmse();
    assert!(t_new <= t_cur * (1.0 + 1e-12), "training RMSE {t_new} > {t_cur} of the two groups");
}

/// Must not fire: stiffnesses 4 and 12 N·m/rad are two values, not one, from the mean
/// start (6.67, weighted by joint count) or a fresh fit alike.
#[test]
fn different_stiffnesses_do_not_merge() {
    let (robot, recs) = recorded(
        "stiffapart",
        &[],
        &[
            (JointStiffness.id(), "shoulder_pitch", &[4.0]),
            (JointStiffness.id(), "wrist_pitch", &[4.0]),
            (JointStiffness.id(), "elbow_pitch", &[12.0]),
        ],
    );
    let start = vec![
        applied(JointStiffness.id(), &["shoulder_pitch", "wrist_pitch"], &[4.0]),
        applied(JointStiffness.id(), &["elbow_pitch"], &[12.0]),
    ];
    let (out, merged) = run(merge_pass, &robot, &recs, start);
    assert!(!merged, "merged: {:?}", out.applied);
    assert_eq!(out.applied.len(), 2);
    // Both starts were tried: the weighted mean and the group's own start.
    let n = out.tried.iter().filter(|t| t.phase == Phase::Merge && !t.kept).count();
    assert_eq!(n, 2, "{:?}", out.tried);
}

/// Must not fire: armatures 0.03 and 0.06 are two values, not one.
#[test]
fn different_armatures_do_not_merge() {
    let (robot, recs) = recorded(
        "nomerge",
        &[("shoulder_pitch", Armature.id(), 0.02)],
        &[(Armature.id(), "shoulder_pitch", &[0.03]), (Armature.id(), "elbow_pitch", &[0.06])],
    );
    let start = vec![
        applied(Armature.id(), &["shoulder_pitch"], &[0.03]),
        applied(Armature.id(), &["elbow_pitch"], &[0.06]),
    ];
    let (out, merged) = run(merge_pass, &robot, &recs, start);
    assert!(!merged, "merged: {:?}", out.applied);
    assert_eq!(out.applied.len(), 2);
    assert!(out.tried.iter().any(|t| t.phase == Phase::Merge && !t.kept), "{:?}", out.tried);
}
