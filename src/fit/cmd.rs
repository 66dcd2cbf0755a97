//! `modellint fit`: load the model and recordings, run the selection, print the missing physics
//! with before → after on the held-out episodes, write the model / actuator TOML / reports.
//! Exit codes: 0 done, 2 could not do the job.

use std::io::Write;
use std::path::PathBuf;

use serde_json::json;

use crate::fit::effects::{self, simulate};
use crate::fit::select::{FitOptions, Progress, ProgressInfo, fit};
use crate::sim2real::gap::{self, GapOptions, GapReport};
use crate::sim2real::replay::{Episode, ReplayOptions};

pub struct FitArgs {
    pub model: PathBuf,
    pub recordings: Vec<PathBuf>,
    pub spec: Option<PathBuf>,
    pub effects: Vec<String>,
    pub joints: Option<String>,
    pub holdout: usize,
    pub window: Option<f64>,
    pub control_hz: Option<f64>,
    pub command_timing: Option<crate::sim2real::commands::CommandTiming>,
    pub base: crate::sim2real::replay::BaseMode,
    pub quiet: bool,
    pub json: bool,
    pub write_model: Option<PathBuf>,
    pub write_actuators: Option<PathBuf>,
    pub report: Option<PathBuf>,
}

/// A spinner on stderr (hidden when stderr is not a terminal, or with `--quiet`).
fn progress_bar(quiet: bool) -> Option<indicatif::ProgressBar> {
    if quiet {
        return None;
    }
    let b = indicatif::ProgressBar::with_draw_target(None, indicatif::ProgressDrawTarget::stderr());
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{spinner} modellint fit: {wide_msg}")
    {
        b.set_style(style);
    }
    b.enable_steady_tick(std::time::Duration::from_millis(200));
    Some(b)
}

fn fail(msg: impl std::fmt::Display) -> i32 {
    eprintln!("modellint: {msg}");
    2
}

pub fn run_fit(a: FitArgs) -> i32 {
    let loaded = match crate::lint::load_for_command(&a.model, a.spec.clone()) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let robot = &loaded.robot;
    for e in &a.effects {
        if effects::by_id(e).is_none() {
            let ids: Vec<String> = effects::all().iter().map(|e| e.id().to_string()).collect();
            return fail(format!("unknown effect `{e}`; known: {}", ids.join(", ")));
        }
    }
    if a.holdout < 2 {
        return fail("--holdout must be at least 2");
    }
    let files = match crate::sim2real::input::expand_inputs(&a.recordings) {
        Ok(f) => f,
        Err(e) => return fail(e),
    };
    let names: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    let mut recs = Vec::new();
    for f in &files {
        match crate::sim2real::input::read_recording(f) {
            Ok(r) => {
                if let Err(e) = r.validate_joint_names(&names) {
                    return fail(e);
                }
                recs.push(r);
            }
            Err(e) => return fail(e),
        }
    }
    let mut joints = Vec::new();
    if let Some(g) = &a.joints {
        let m = match globset::Glob::new(g) {
            Ok(x) => x.compile_matcher(),
            Err(e) => return fail(format!("--joints: {e}")),
        };
        for r in &recs {
            for j in &r.joints {
                if m.is_match(&j.name) && !joints.contains(&j.name) {
                    joints.push(j.name.clone());
                }
            }
        }
        if joints.is_empty() {
            return fail(format!("--joints {g} matches no recorded joint"));
        }
    }
    let replay = ReplayOptions {
        control_hz: a.control_hz,
        command_timing: a.command_timing,
        base: a.base,
        ..Default::default()
    };
    let families = match loaded.spec.as_ref() {
        Some(s) => names
            .iter()
            .filter_map(|n| s.joint(n).and_then(|f| f.motor).map(|m| (n.clone(), m)))
            .collect(),
        None => Default::default(),
    };
    let bar = progress_bar(a.quiet);
    let progress = bar.clone().map(|b| {
        let start = std::time::Instant::now();
        Progress(std::sync::Arc::new(move |p: &ProgressInfo| {
            let what = match &p.candidate {
                Some((i, n, c)) => format!("candidate {i}/{n}: {c}"),
                None => p.phase.to_string(),
            };
            b.set_message(format!(
                "round {}: {what} · {} simulations · {:.0} s",
                p.round + 1,
                p.simulations,
                start.elapsed().as_secs_f64()
            ));
        }))
    });
    let opts = FitOptions {
        holdout: a.holdout,
        effects: a.effects.clone(),
        joints,
        replay: replay.clone(),
        shooting_s: a.window,
        families,
        progress,
        ..Default::default()
    };
    let out = fit(robot, &recs, &opts);
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    for w in &out.warnings {
        eprintln!("modellint: warning: {w}");
    }
    if out.heldout.is_empty() {
        return 2;
    }
    let spec = loaded.spec.as_ref();
    let region = |name: &str| {
        spec.and_then(|s| s.joint(name))
            .and_then(|f| f.region)
            .unwrap_or_else(|| gap::region_from_name(name))
    };
    let run = |applied| -> Result<(GapReport, Vec<Episode>), String> {
        let eps: Result<Vec<Episode>, _> =
            simulate(robot, &out.heldout, applied, &replay).into_iter().collect();
        let eps = eps.map_err(|e| e.to_string())?;
        Ok((gap::compute(&out.heldout, &eps, &region, &GapOptions::default()), eps))
    };
    let ((before, eps_b), (after, eps_a)) = match (run(&[]), run(&out.applied)) {
        (Ok(b), Ok(a)) => (b, a),
        (Err(e), _) | (_, Err(e)) => return fail(e),
    };
    // Everything said on stderr after the fit also goes into the JSON `warnings`.
    let mut notes: Vec<String> = Vec::new();
    if let Some(dir) = &a.report {
        let page = crate::fit::report::FitReport {
            model: &a.model,
            selected: &out.selected,
            before: &before,
            after: &after,
            recs: &out.heldout,
            eps_before: &eps_b,
            eps_after: &eps_a,
        };
        match crate::fit::report::write(dir, &page) {
            Ok(p) => {
                let msg = format!("report written to {}", p.display());
                eprintln!("modellint: {msg}");
                notes.push(msg);
            }
            Err(e) => return fail(format!("cannot write report in {}: {e}", dir.display())),
        }
    }
    if let Some(path) = &a.write_model {
        match crate::fit::writemodel::write_model(&a.model, robot, &out.selected, path) {
            Ok(w) => {
                for n in w.notes {
                    eprintln!("modellint: note: {n}");
                    notes.push(n);
                }
                let list: Vec<String> = w.files.iter().map(|p| p.display().to_string()).collect();
                let msg = format!("fitted model written to {}", list.join(", "));
                eprintln!("modellint: {msg}");
                notes.push(msg);
            }
            Err(e) => return fail(e),
        }
    }
    if let Some(path) = &a.write_actuators {
        match crate::fit::writeback::write_actuators(path, robot, &out.selected) {
            Ok(files) => {
                let list: Vec<String> = files.iter().map(|p| p.display().to_string()).collect();
                let msg = format!("actuator parameters written to {}", list.join(", "));
                eprintln!("modellint: {msg}");
                notes.push(msg);
            }
            Err(e) => return fail(e),
        }
    }
    let text = if a.json {
        let mp: Vec<_> = out
            .selected
            .iter()
            .map(|s| {
                json!({
                    "effect": s.effect, "joints": s.joints, "params": s.params,
                    "stderr": s.stderr.iter().map(|(k, v)| (k.clone(), if v.is_finite() { json!(v) } else { serde_json::Value::Null })).collect::<serde_json::Map<_, _>>(),
                    "identifiable": s.identifiable, "evidence": s.evidence, "heldout_improvement": s.heldout_improvement,
                    "heldout_rmse_before": s.heldout_rmse_before, "heldout_rmse_after": s.heldout_rmse_after,
                })
            })
            .collect();
        let v = json!({
            "missing_physics": mp,
            "before": before,
            "after": after,
            "diagnosis": out.diagnosis.iter().take(20).collect::<Vec<_>>(),
            "tried": out.tried,
            "split": {"train": out.train.len(), "heldout": out.heldout.len(), "by_time": out.split_by_time, "note": out.split_note},
            "floor": out.floors.iter().map(|f| json!({"joint": f.joint, "residual_rms": f.ms.sqrt(), "white_floor_rms": f.white.sqrt(), "reconstruction_floor_rms": f.reconstruction.sqrt()})).collect::<Vec<_>>(),
            "stopped_at_floor": out.stopped_at_floor,
            "warnings": out.warnings.iter().chain(&notes).collect::<Vec<_>>(),
        });
        serde_json::to_string_pretty(&v).unwrap_or_default() + "\n"
    } else {
        // Human output: angles in degrees (as `gap`), SI in JSON; one before → after figure.
        let deg = |rad: f64| rad.to_degrees();
        let mut s = String::from("missing physics\n");
        if out.selected.is_empty() {
            s.push_str(if out.stopped_at_floor {
                "  nothing: the training residual is at its noise floor on every joint (nothing left to explain)\n"
            } else {
                "  nothing: no candidate effect improved the held-out error beyond noise\n"
            });
        }
        for x in &out.selected {
            let e = effects::by_id(&x.effect);
            let ps: Vec<String> = x
                .params
                .iter()
                .map(|(k, v)| {
                    let unit = e
                        .and_then(|e| e.params().iter().find(|p| p.name == k))
                        .map_or("", |p| p.unit);
                    let se = x.stderr.get(k).copied().unwrap_or(f64::INFINITY);
                    let (v, se, unit) =
                        if unit == "rad" { (deg(*v), deg(se), "°") } else { (*v, se, unit) };
                    let se = if se.is_finite() { format!(" ± {se:.2e}") } else { " ± ?".into() };
                    let sep = if unit.is_empty() || unit == "°" { "" } else { " " };
                    format!("{k} = {v:.4}{se}{sep}{unit}")
                })
                .collect();
            s.push_str(&format!(
                "  {:<24} {:<28} {}\n",
                x.effect,
                x.joints.join(","),
                ps.join(", ")
            ));
            let shown = e.map_or(&[][..], |e| e.shown_evidence());
            let ev: Vec<String> = ["corr", "explained_share"]
                .iter()
                .chain(shown)
                .filter_map(|k| x.evidence.get(*k).map(|v| format!("{k} {v:.3}")))
                .collect();
            s.push_str(&format!(
                "      evidence: {}; when added, held-out error {:+.0} %{}\n",
                if ev.is_empty() { "fitted jointly".to_string() } else { ev.join(", ") },
                -100.0 * x.heldout_improvement,
                if x.identifiable { "" } else { "  [not identifiable]" }
            ));
        }
        s.push_str(&format!(
            "\nheld-out ({} episode{}{}): before → after\n  position MAE   {:.3}° → {:.3}°\n  position RMSE  {:.3}° → {:.3}°\n  correlation    {:.3} → {:.3}\n  gap score      {:.3} → {:.3}\n",
            out.heldout.len(),
            if out.heldout.len() == 1 { "" } else { "s" },
            if out.split_by_time { ", time windows" } else { "" },
            deg(before.position_mae),
            deg(after.position_mae),
            deg(before.position_rmse),
            deg(after.position_rmse),
            before.correlation_mean,
            after.correlation_mean,
            before.gap_overall,
            after.gap_overall
        ));
        if !out.floors.is_empty() {
            let f: Vec<String> = out
                .floors
                .iter()
                .map(|f| {
                    format!(
                        "{} {:.3}° + {:.3}°",
                        f.joint,
                        deg(f.white.sqrt()),
                        deg(f.reconstruction.sqrt())
                    )
                })
                .collect();
            s.push_str(&format!(
                "  floor (RMS: white part of the training residual + command reconstruction): {}\n",
                f.join(", ")
            ));
        }
        if !out.split_note.is_empty() {
            s.push_str(&format!("  ({})\n", out.split_note));
        }
        s
    };
    if std::io::stdout().lock().write_all(text.as_bytes()).is_err() {
        return 2;
    }
    0
}

/// `modellint fit RIG.xml LOGDIR --servo xl330`: held-out-by-gain servo identification.
pub fn run_servo(model: &std::path::Path, recordings: &[std::path::PathBuf], evals: usize) -> i32 {
    let mut map = crate::model::source::SourceMap::default();
    let robot = match crate::model::load(&mut map, model, None) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("modellint: {e}");
            return 2;
        }
    };
    let [dir] = recordings else {
        eprintln!("modellint: --servo takes one directory of BAM logs");
        return 2;
    };
    let logs = match crate::fit::servo_fit::load_logs(dir) {
        Ok(l) if !l.is_empty() => l,
        Ok(_) => {
            eprintln!("modellint: {}: no BAM logs found", dir.display());
            return 2;
        }
        Err(e) => {
            eprintln!("modellint: {e}");
            return 2;
        }
    };
    if crate::fit::servo_fit::gains(&logs).len() < 2 {
        eprintln!(
            "modellint: {}: --servo needs logs of at least two firmware gains to hold one out",
            dir.display()
        );
        return 2;
    }
    let o = crate::fit::servo_fit::FitOpts { max_evals: evals, ..Default::default() };
    let quiet = !std::io::IsTerminal::is_terminal(&std::io::stderr());
    match crate::fit::servo_report::run(&robot, &logs, &o, &|m| {
        if !quiet {
            eprintln!("{m}")
        }
    }) {
        Ok((report, _)) => {
            print!("{report}");
            0
        }
        Err(e) => {
            eprintln!("modellint: {e}");
            2
        }
    }
}
