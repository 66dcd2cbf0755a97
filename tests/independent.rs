//! `gap` and `fit` on recordings made outside modellint: `../shared/data/recordings/
//! independent_arm2` (a separate Python + MuJoCo simulator of an ordinary logging setup, with its
//! answers). Every expected value here comes from that data set's own files — the exact command
//! of every control tick (`truth_commands/`), the hidden effects (`truth.json`) and its noise
//! settings — never from modellint's replay. Skips visibly when ../shared is absent.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::indep::{fit_at, json};
use modellint::sim2real::commands::{CommandTiming, Fill, Schedule, reconstruct};
use modellint::sim2real::recording::read_csv;

fn arm2() -> Option<PathBuf> {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/recordings/independent_arm2");
    if d.join("arm2.xml").is_file() {
        Some(d)
    } else {
        eprintln!("skipping: ../shared/data/recordings/independent_arm2 is absent");
        None
    }
}

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_modellint")
}

/// (tick, per-joint command) rows of a truth_commands file.
fn truth_ticks(path: &Path) -> Vec<(i64, Vec<f64>)> {
    let text = std::fs::read_to_string(path).expect("truth commands");
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("tick"))
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.trim().parse().expect("number")).collect();
            (v[0] as i64, v[2..].to_vec())
        })
        .collect()
}

#[test]
fn command_reconstruction_matches_the_exact_ticks() {
    let Some(d) = arm2() else { return };
    for ds in ["arm2.none", "arm2.all.action_delay+coulomb_friction", "arm2.elbow.gain_error"] {
        for ep in 0..4 {
            let rec = read_csv(&d.join(format!("{ds}/episodes/ep_{ep:02}.csv"))).expect("csv");
            let truth = truth_ticks(&d.join(format!("{ds}/truth_commands/ep_{ep:02}.csv")));
            let cmds: Vec<&[f64]> =
                rec.joints.iter().map(|j| j.q_cmd.as_deref().expect("q_cmd")).collect();
            let t0 = rec.control_t0_s.unwrap_or(0.0);
            let s = reconstruct(
                &rec.t,
                &cmds,
                rec.control_rate_hz,
                t0,
                CommandTiming::InForce,
                Fill::Ramps,
            )
            .expect("schedule");
            let held = reconstruct(
                &rec.t,
                &cmds,
                rec.control_rate_hz,
                t0,
                CommandTiming::InForce,
                Fill::Hold,
            )
            .expect("schedule");
            let Schedule::Ticks { k0, cmd, stats, .. } = &s else { panic!("a rate is declared") };
            let Schedule::Ticks { cmd: cmd_held, .. } = &held else { panic!("a rate is declared") };
            let (mut exact, mut total, mut worst) = (0usize, 0usize, 0.0f64);
            let (mut filled_sq, mut held_sq) = (0.0, 0.0);
            for (k, want) in &truth {
                let i = k - k0;
                if i < 0 || i as usize >= cmd[0].len() {
                    continue;
                }
                let i = i as usize;
                total += 1;
                let err = (0..want.len()).map(|j| (cmd[j][i] - want[j]).abs()).fold(0.0, f64::max);
                if err < 1e-9 {
                    exact += 1;
                } else {
                    filled_sq +=
                        (0..want.len()).map(|j| (cmd[j][i] - want[j]).powi(2)).sum::<f64>();
                    held_sq +=
                        (0..want.len()).map(|j| (cmd_held[j][i] - want[j]).powi(2)).sum::<f64>();
                }
                worst = worst.max(err);
            }
            eprintln!(
                "{ds} ep {ep}: {exact} of {total} ticks exact ({} with rows, {} filled); filled-tick error {:.2e} rad² vs {:.2e} held",
                stats.occupied, stats.empty, filled_sq, held_sq
            );
            // Every tick with a row is exact (the row carries the command in force); the empty
            // ticks (about 12 %) are filled, and interpolating ramps beats holding every one.
            assert!(total > 900, "{ds} ep {ep}: {total} ticks compared");
            assert!(
                exact >= stats.occupied,
                "{ds} ep {ep}: {exact} exact of {total}, {} ticks had rows",
                stats.occupied
            );
            assert!(exact + stats.empty >= total, "{ds} ep {ep}: a tick with a row is wrong");
            assert!(
                filled_sq <= 0.5 * held_sq,
                "{ds} ep {ep}: filled {filled_sq} vs held {held_sq}"
            );
            assert_eq!(stats.conflicting, 0, "{ds} ep {ep}");
            assert!(worst < 0.5, "{ds} ep {ep}: worst tick error {worst}");
        }
    }
}

/// Monte-Carlo MAE of `round((x + N(0, σ)) / Δ)·Δ − x` over uniformly spread x (fixed seed).
fn noise_floor_mae(sigma: f64, quantum: f64) -> f64 {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut u = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        ((s >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let n = 400_000;
    let mut acc = 0.0;
    for _ in 0..n {
        let x = 10.0 * u();
        let g = (-2.0 * u().ln()).sqrt() * (std::f64::consts::TAU * u()).cos();
        let y = ((x + sigma * g) / quantum).round() * quantum;
        acc += (y - x).abs();
    }
    acc / n as f64
}

#[test]
fn gap_on_the_clean_control_is_at_the_noise_floor() {
    let Some(d) = arm2() else { return };
    let truth = json(&d.join("arm2.none/truth.json"));
    let rec = &truth["recording"];
    let floor =
        noise_floor_mae(rec["q_noise"].as_f64().unwrap(), rec["q_quantum"].as_f64().unwrap());
    assert!((floor - 0.54e-3).abs() < 0.03e-3, "floor {floor}");
    let out = Command::new(bin())
        .args(["gap", "--format", "json"])
        .arg(d.join("arm2.xml"))
        .arg(d.join("arm2.none/episodes"))
        .output()
        .expect("run");
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    for j in v["per_joint"].as_array().unwrap() {
        let mae = j["mae"].as_f64().unwrap();
        eprintln!(
            "{}: MAE {:.3} mrad, floor {:.3} mrad ({:.2}×)",
            j["name"],
            1e3 * mae,
            1e3 * floor,
            mae / floor
        );
        assert!(mae <= 1.3 * floor, "{}: MAE {mae} > 1.3 × floor {floor}", j["name"]);
    }
    // No lag is located on the clean control (the one-tick command lag would show as −11 ms).
    for c in v["localisation"]["causes"].as_array().unwrap() {
        let lag = c["lag_s"].as_f64().unwrap();
        assert!(lag.abs() < 2e-3, "{}: lag {lag} s", c["name"]);
        assert!(!c["summary"].as_str().unwrap().contains("time lag"), "{c}");
    }
}

/// arm2.none's episodes as a log that starts mid-motion (the first 3 rows dropped, so the first
/// row is ~35 ms in, off the controller's ticks at k × 10 ms) and declares `control_t0_s` as
/// `t0` (`None`: not at all), written under `dir`.
fn cut_arm2(d: &Path, dir: &Path, t0: Option<&str>) -> Vec<f64> {
    std::fs::create_dir_all(dir).expect("mkdir");
    let mut firsts = Vec::new();
    for ep in 0..4 {
        let text = std::fs::read_to_string(d.join(format!("arm2.none/episodes/ep_{ep:02}.csv")))
            .expect("csv");
        let mut out = String::new();
        let mut rows = 0;
        for l in text.lines() {
            if l.starts_with("# control_t0_s") {
                continue;
            }
            if !(l.starts_with('#') || l.starts_with("t,")) {
                rows += 1;
                if rows <= 3 {
                    continue;
                }
                if firsts.len() == ep {
                    firsts.push(l.split(',').next().unwrap().parse::<f64>().unwrap());
                }
            }
            out.push_str(l);
            out.push('\n');
        }
        if let Some(v) = t0 {
            let v = if v == "first" { format!("{}", firsts[ep]) } else { v.to_string() };
            out = format!("# control_t0_s: {v}\n{out}");
        }
        std::fs::write(dir.join(format!("ep_{ep:02}.csv")), out).expect("write");
    }
    firsts
}

/// `gap --format json` on `dir`: (per-joint position MAE, stderr).
fn gap_mae(model: &Path, dir: &Path) -> (Vec<f64>, String) {
    let out = Command::new(bin())
        .args(["gap", "--format", "json"])
        .arg(model)
        .arg(dir)
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(0), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let mae = v["per_joint"].as_array().unwrap().iter().map(|j| j["mae"].as_f64().unwrap());
    // What stderr says about the recordings is in the JSON too.
    for key in ["notes", "warnings"] {
        let said: Vec<&str> =
            v[key].as_array().map_or(vec![], |a| a.iter().map(|x| x.as_str().unwrap()).collect());
        for s in &said {
            assert!(err.contains(s), "{key} {s} not on stderr: {err}");
        }
        assert_eq!(
            said.len(),
            err.matches(&format!("modellint: {}: ", &key[..key.len() - 1])).count()
        );
    }
    (mae.collect(), err)
}

/// A log without `control_t0_s` whose first row is not on a control tick: the rows place the
/// ticks (arm2's 88 Hz recorder is slower than its 100 Hz controller, so the command's shape
/// decides among the phases the command changes allow). The answer is the data set's own
/// `control_t0_s: 0`, not anything modellint computed; the first row's time — what the replay
/// used before — is shown to be worse, and to be reported when declared.
#[test]
fn a_missing_control_t0_is_recovered_from_the_rows() {
    let Some(d) = arm2() else { return };
    let root = std::env::temp_dir().join(format!("modellint-no-t0-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let model = d.join("arm2.xml");
    cut_arm2(&d, &root.join("declared"), Some("0"));
    let firsts = cut_arm2(&d, &root.join("none"), None);
    cut_arm2(&d, &root.join("first"), Some("first"));
    assert!(firsts.iter().all(|&f| (f * 100.0 - (f * 100.0).round()).abs() > 0.05), "{firsts:?}");

    let (truth, err) = gap_mae(&model, &root.join("declared"));
    // Nothing said about the ticks (the timestep note is about the model).
    let said = |l: &&str| !l.contains("model's timestep");
    assert!(
        !err.lines().filter(said).any(|l| l.contains("warning") || l.contains("note")),
        "{err}"
    );
    let (est, err) = gap_mae(&model, &root.join("none"));
    eprintln!("{err}");
    // Every estimate is a control tick of the data set's grid (k × 10 ms) within 0.1 ms.
    let values: Vec<f64> = err
        .split("control_t0_s = ")
        .skip(1)
        .map(|x| x.split_whitespace().next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(values.len(), 3, "three listed, then 'and 1 more': {err}");
    for v in &values {
        let off = (v * 100.0 - (v * 100.0).round()).abs() / 100.0;
        assert!(off < 1e-4, "control_t0_s {v} is {off} s off the ticks");
    }
    let (first, err) = gap_mae(&model, &root.join("first"));
    assert!(err.contains("control_t0_s 0.0") && err.contains("the rows put the ticks at"), "{err}");
    for j in 0..truth.len() {
        eprintln!(
            "joint {j}: MAE declared 0 {:.3} mrad, estimated {:.3}, first row {:.3}",
            truth[j] * 1e3,
            est[j] * 1e3,
            first[j] * 1e3
        );
        assert!(est[j] <= 1.1 * truth[j], "joint {j}: {} vs {}", est[j], truth[j]);
        assert!(first[j] >= 1.5 * truth[j], "joint {j}: {} vs {}", first[j], truth[j]);
    }
    let _ = std::fs::remove_dir_all(&root);
}

/// Unix-epoch timestamps (ROS logs, 1.7e9 s): `gap` on arm2.none's episodes shifted by 1.7e9 s
/// (its `control_t0_s` with them) gives the position error of the originals (before the times
/// were rebased, the simulation clock drifted a rounding per step: 3.2× on a humanoid log).
#[test]
fn epoch_timestamps_replay_as_the_originals() {
    let Some(d) = arm2() else { return };
    let dir = std::env::temp_dir().join(format!("modellint-epoch-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("mkdir");
    for ep in 0..4 {
        let text = std::fs::read_to_string(d.join(format!("arm2.none/episodes/ep_{ep:02}.csv")))
            .expect("csv");
        let mut out = String::new();
        for l in text.lines() {
            if let Some(v) = l.strip_prefix("# control_t0_s: ") {
                let v: f64 = v.trim().parse().expect("t0");
                out.push_str(&format!("# control_t0_s: {:.6}\n", 1.7e9 + v));
            } else if l.starts_with('#') || l.starts_with("t,") {
                out.push_str(l);
                out.push('\n');
            } else {
                let (t, rest) = l.split_once(',').expect("row");
                let t: f64 = t.parse().expect("t");
                out.push_str(&format!("{:.6},{rest}\n", 1.7e9 + t));
            }
        }
        std::fs::write(dir.join(format!("ep_{ep:02}.csv")), out).expect("write");
    }
    let model = d.join("arm2.xml");
    let (orig, _) = gap_mae(&model, &d.join("arm2.none/episodes"));
    let (epoch, err) = gap_mae(&model, &dir);
    for j in 0..orig.len() {
        eprintln!("joint {j}: MAE {:.4} mrad, from 1.7e9 s {:.4}", orig[j] * 1e3, epoch[j] * 1e3);
        assert!((epoch[j] - orig[j]).abs() <= 0.02 * orig[j], "joint {j}: {epoch:?} vs {orig:?}");
    }
    assert!(!err.contains("warning"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `fit` on one data set and checks it against truth.json: exactly the hidden effects,
/// parameters within 10 % (delay within 1.5 ms). Returns the fit's JSON (`None` when the data
/// are absent).
fn fit_matches_truth(ds: &str) -> Option<serde_json::Value> {
    let d = arm2()?;
    let truth = json(&d.join(format!("{ds}/truth.json")));
    let v = fit_at(&d.join(format!("{ds}/nominal.xml")), &d.join(format!("{ds}/episodes")), &[]);
    let found = v["missing_physics"].as_array().unwrap();
    let mut want: Vec<String> = truth["effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e.as_str().unwrap().to_string())
        .filter(|e| e != "none")
        .collect();
    want.sort();
    let mut got: Vec<String> =
        found.iter().map(|m| m["effect"].as_str().unwrap().to_string()).collect();
    got.sort();
    eprintln!("{ds}: found {found:?}");
    assert_eq!(got, want, "{ds}: effects");
    let joints: Vec<String> = truth["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j.as_str().unwrap().to_string())
        .collect();
    for m in found {
        let id = m["effect"].as_str().unwrap();
        let mut mj: Vec<String> = m["joints"]
            .as_array()
            .unwrap()
            .iter()
            .map(|j| j.as_str().unwrap().to_string())
            .collect();
        mj.sort();
        let mut tj = joints.clone();
        tj.sort();
        assert_eq!(mj, tj, "{ds}: {id} joints");
        for (k, p) in truth["resolved"]["params"][id].as_object().unwrap() {
            // truth.json names the MuJoCo attribute; the effect's parameter of the same meaning.
            let got = match (id, k.as_str()) {
                ("gain_error", "kp_scale") => m["params"]["kp_scale"].as_f64(),
                ("gain_error", "kd_scale") => m["params"]["kd_scale"].as_f64(),
                _ => m["params"].as_object().unwrap().values().next().and_then(|x| x.as_f64()),
            }
            .unwrap();
            let p = p.as_f64().unwrap();
            if id == "action_delay" {
                assert!((got - p).abs() <= 1.5e-3, "{ds}: delay {got} vs {p}");
            } else if id == "armature" {
                // truth: armature × 2 on the shoulder (0.02 → 0.04).
                let want =
                    truth["resolved"]["joints"]["shoulder"]["joint.armature"][1].as_f64().unwrap();
                assert!((got - want).abs() <= 0.1 * want, "{ds}: armature {got} vs {want}");
            } else {
                assert!((got - p).abs() <= 0.1 * p.abs(), "{ds}: {id}.{k} {got} vs {p}");
            }
        }
    }
    let (b, a) = (
        v["before"]["position_mae"].as_f64().unwrap(),
        v["after"]["position_mae"].as_f64().unwrap(),
    );
    assert!(a <= b + 1e-12, "{ds}: held-out MAE {b} → {a}");
    // The fitted model's floor is the logger's noise: the white part of each joint's training
    // residual is the RMS of a noisy, quantised reading, √(σ² + Δ²/12) from the simulator's own
    // settings, and the residual is at it (nothing left unexplained, nothing over-fitted).
    let rec = &truth["recording"];
    let (sigma, quantum) = (rec["q_noise"].as_f64().unwrap(), rec["q_quantum"].as_f64().unwrap());
    let noise = (sigma * sigma + quantum * quantum / 12.0).sqrt();
    let floors = v["floor"].as_array().unwrap();
    let recorded = truth["recorded_joints"].as_array().unwrap().len();
    assert_eq!(floors.len(), recorded, "{ds}: floors {floors:?}");
    for f in floors {
        let white = f["white_floor_rms"].as_f64().unwrap();
        let res = f["residual_rms"].as_f64().unwrap();
        assert!((white / noise - 1.0).abs() < 0.1, "{ds}: white floor {white} vs noise {noise}");
        assert!(res < 1.1 * noise, "{ds}: residual {res} vs noise {noise}");
    }
    Some(v)
}

#[test]
fn fit_reports_nothing_on_the_clean_control() {
    fit_matches_truth("arm2.none");
}

#[test]
fn fit_finds_the_elbow_delay() {
    fit_matches_truth("arm2.elbow.action_delay");
}

#[test]
fn fit_finds_the_elbow_gain_error() {
    fit_matches_truth("arm2.elbow.gain_error");
}

#[test]
fn fit_finds_friction_on_all_joints_as_one_group() {
    fit_matches_truth("arm2.all.coulomb_friction");
}

/// Delay 12 ms and Coulomb friction 0.25 on both joints (truth.json). Each effect alone is
/// mimicked in part by the other: Coulomb friction alone takes up part of the delay's lag. The
/// structure of the search: the first round's pair look-ahead, whose linear prediction from the
/// members' single fits ranks the true pair first, fits the two together; or, when the pair is
/// not among the look-ahead's, the second round's winner joins the effect kept before it on the
/// same joints and they are re-fitted together. Either way the two effects found take at most
/// two rounds that fit candidates, and the next stops at the noise floor. (Without the re-fit
/// the third and fourth rounds hunted for what the biased friction left: a gain error kept in
/// a pair and dropped again by the simplification, at twice the search's cost.)
#[test]
fn fit_finds_the_delay_and_friction_pair_in_at_most_two_rounds() {
    let Some(v) = fit_matches_truth("arm2.all.action_delay+coulomb_friction") else { return };
    let found = v["missing_physics"].as_array().unwrap().len();
    let greedy = [
        "add",
        "screen",
        "floor",
        "floor_screen",
        "heldout_screen",
        "discretisation",
        "pair",
        "pair_restart",
        "joint_pair",
    ];
    let mut rounds: Vec<u64> = v["tried"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|t| greedy.contains(&t["phase"].as_str().unwrap()))
        .map(|t| t["round"].as_u64().unwrap())
        .collect();
    rounds.dedup();
    let n = rounds.len() as u64;
    assert!(
        (1..=found as u64).contains(&n) && rounds == (0..n).collect::<Vec<_>>(),
        "{:#?}",
        v["tried"]
    );
    // What the search fits in full. The richer friction models hold Coulomb friction as a
    // special case, and its fit leaves neither a breakaway nor a load-shaped residual: they are
    // judged from that fit, not fitted (the build before fitted both in full, 3,700 of its
    // 18,800 replayed seconds). The look-ahead's linear prediction from the members' single
    // fits leaves out the pairs that cannot come near the best (the build before fitted ten
    // pairs of the round's candidates, none of them this one).
    let tried = v["tried"].as_array().unwrap();
    for t in tried {
        let id = t["effect"].as_str().unwrap();
        if ["stribeck_friction", "load_dependent_friction"].contains(&id) {
            assert_ne!(t["phase"], "add", "{t:#?}");
            // On both joints they are judged before any fit of their own on the screen's data:
            // from Coulomb friction's fit, or on the probes' data against the pair at the floor
            // (the build before coarse-fitted both, ~360 replayed seconds).
            if t["joints"].as_array().unwrap().len() == 2 {
                let judged = t["params"].as_array().is_some_and(|p| p.is_empty())
                    || ["floor", "floor_screen"].contains(&t["phase"].as_str().unwrap());
                assert!(judged, "{t:#?}");
            }
        }
    }
    // The pair is judged right after the lead (the delay on both joints), with its rivals'
    // coarse fits as partners: no rival is fitted in full (the build before fitted nine in
    // full, ~2,900 replayed seconds, only to rank singles that all lose to the pair).
    let full: Vec<_> = tried.iter().filter(|t| t["round"] == 0 && t["phase"] == "add").collect();
    assert_eq!(full.len(), 1, "{full:#?}");
    let pairs = tried.iter().filter(|t| t["phase"] == "pair").count();
    assert!(pairs <= found, "{pairs} pairs fitted: {:#?}", v["tried"]);
    // The linear model predicts 27-38 % training gains for these smooth effects (the bar is
    // half the round's best, ~25 %) where their coarse fits reach 9-11 %: only the linear step
    // as replayed admits a smooth candidate, and these steps reach at most 9 % (the build
    // before fitted all four in full).
    for t in tried.iter().filter(|t| t["round"] == 0) {
        let id = t["effect"].as_str().unwrap();
        if ["armature", "link_inertia", "com_offset", "link_mass"].contains(&id) {
            assert_ne!(t["phase"], "add", "{t:#?}");
        }
    }
}

/// `--start-estimate` estimates each episode's start; without it the replay starts at the first
/// row's reading. On the clean control both report
/// nothing; the estimated start leaves a residual no larger (weighted by each joint's noise,
/// what the estimate minimises: the first-row start is one of its candidates) and a different
/// floor. (arm2's servos are well damped: the two differ by ~1 %; on a lightly damped leg of
/// the independent Python simulator the hip's residual drops 0.837 → 0.784 mrad.)
#[test]
fn the_start_estimate_can_be_switched_on() {
    let Some(d) = arm2() else { return };
    let run = |extra: &[&str]| {
        fit_at(&d.join("arm2.none/nominal.xml"), &d.join("arm2.none/episodes"), extra)
    };
    let (est, first) = (run(&["--start-estimate"]), run(&[]));
    let score = |v: &serde_json::Value| -> f64 {
        assert_eq!(v["missing_physics"].as_array().unwrap().len(), 0, "{v}");
        v["floor"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| {
                let (r, w) =
                    (f["residual_rms"].as_f64().unwrap(), f["white_floor_rms"].as_f64().unwrap());
                (r / w).powi(2)
            })
            .sum()
    };
    let (a, b) = (score(&est), score(&first));
    assert!(a <= b * 1.001, "estimated start {a} vs first row {b}");
    assert_ne!(est["floor"], first["floor"]);
}

/// `fit --told`: no search, the named effect fitted on the named joints. On the independent
/// simulator's elbow damping (truth.json: 0.8 N·m·s/rad on the elbow) the told fit comes within
/// 10 % and improves the held-out error; the blind search on the same data asks for several
/// times as many rollouts. A malformed or unknown `--told` is exit 2 with the reason.
#[test]
fn a_told_fit_fits_exactly_the_named_effect() {
    let Some(d) = arm2() else { return };
    let ds = d.join("arm2.elbow.viscous_damping");
    let truth = json(&ds.join("truth.json"));
    let damping = truth["params"]["damping"].as_f64().expect("truth damping");
    let run = |extra: &[&str]| fit_at(&ds.join("nominal.xml"), &ds.join("episodes"), extra);
    let told = run(&["--told", "viscous_damping@elbow"]);
    let mp = told["missing_physics"].as_array().expect("missing_physics");
    assert_eq!(mp.len(), 1, "{mp:#?}");
    assert_eq!(mp[0]["effect"], "viscous_damping");
    assert_eq!(mp[0]["joints"], serde_json::json!(["elbow"]));
    let got = mp[0]["params"]["damping"].as_f64().expect("damping");
    assert!((got / damping - 1.0).abs() < 0.1, "told damping {got} vs {damping}");
    assert!(mp[0]["heldout_improvement"].as_f64().expect("improvement") > 0.5);
    assert!(told["tried"].as_array().expect("tried").iter().all(|t| t["phase"] == "told"));
    let blind = run(&[]);
    let rollouts = |v: &serde_json::Value| v["search"]["rollouts"].as_u64().expect("rollouts");
    assert!(rollouts(&blind) > 2 * rollouts(&told), "{} vs {}", rollouts(&blind), rollouts(&told));
    for bad in ["viscous_damping", "no_such_effect@elbow", "viscous_damping@knee"] {
        let out = Command::new(bin())
            .arg("fit")
            .arg(ds.join("nominal.xml"))
            .arg(ds.join("episodes"))
            .args(["--quiet", "--told", bad])
            .output()
            .expect("run");
        assert_eq!(out.status.code(), Some(2), "--told {bad}");
        assert!(String::from_utf8_lossy(&out.stderr).contains("--told"), "--told {bad}");
    }
}
