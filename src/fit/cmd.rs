//! `modellint fit`: load the model and recordings, run the selection, print the missing physics
//! with before → after on the held-out episodes, write the model / actuator TOML / reports.
//! Exit codes: 0 done, 2 could not do the job.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;

use serde_json::json;

use crate::error::CmdError;
use crate::fit::effects::{self, simulate};
use crate::fit::select::{FitOptions, FitOutcome, Progress, ProgressInfo, fit};
use crate::lint::Loaded;
use crate::sim2real::gap::{self, GapOptions, GapReport};
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::{Episode, ReplayOptions};
use crate::sink::{Sink, Stderr};

pub struct FitArgs {
    pub model: PathBuf,
    pub recordings: Vec<PathBuf>,
    pub spec: Option<PathBuf>,
    pub effects: Vec<String>,
    pub joints: Option<String>,
    /// `EFFECT@JOINTS`: fit exactly these, no search (`+`-separated joints, `*` for all).
    pub told: Vec<String>,
    pub holdout: usize,
    /// `KEY=VALUE`: hold out the episodes with that metadata value; `KEY`: every value in turn.
    pub holdout_by: Option<String>,
    pub window: Option<f64>,
    /// Estimate each episode's start state (else every replay starts at the first row).
    pub start_estimate: bool,
    /// How the recordings are replayed.
    /// How the recordings are read (`--ignore-columns`).
    pub parse: crate::sim2real::recording::ParseOptions,
    pub replay: ReplayOptions,
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
        indicatif::ProgressStyle::with_template("{spinner} [{elapsed}] modellint fit: {wide_msg}")
    {
        b.set_style(style);
    }
    b.enable_steady_tick(std::time::Duration::from_millis(200));
    Some(b)
}

/// Seconds between two plain progress lines when stderr is not a terminal.
const LOG_EVERY_S: f64 = 30.0;

/// The spinner and the fit's progress callback drawing on it (both `None` with `quiet`):
/// `prefix`, then the round, the phase or candidate i/n, the rollouts so far, the time and,
/// once a round has fitted a candidate, an estimate of the time its remaining candidates take
/// (their mean so far × how many are left). The search reports after every dataset
/// simulation, so on a terminal the line moves at least as often as a simulation ends, and
/// the spinner's clock every 200 ms. When stderr is not a terminal (a CI log, `2> file`) there
/// is no spinner: a plain line is written when a round starts and at most every
/// [`LOG_EVERY_S`] seconds in between, so a long fit in a log still shows where it is.
pub(crate) fn fit_progress(
    quiet: bool,
    prefix: String,
) -> (Option<indicatif::ProgressBar>, Option<Progress>) {
    if quiet {
        return (None, None);
    }
    let start = std::time::Instant::now();
    // ((round, phase, candidates), time its first candidate started) for the estimate.
    let round_start = std::sync::Mutex::new((None, 0.0f64));
    let line = move |p: &ProgressInfo| {
        let now = start.elapsed().as_secs_f64();
        let what = match &p.candidate {
            Some((i, n, c)) => {
                let mut rs = round_start.lock().unwrap_or_else(|e| e.into_inner());
                let key = Some((p.round, p.phase, *n));
                if rs.0 != key {
                    *rs = (key, now);
                }
                let eta = if *i > 1 {
                    let per = (now - rs.1) / (*i - 1) as f64;
                    format!(" · ≈ {:.0} s left in this phase", per * (n - i + 1) as f64)
                } else {
                    String::new()
                };
                format!("{} {i}/{n}{eta}: {c}", p.phase)
            }
            None => p.phase.to_string(),
        };
        format!("{prefix}round {} · {} rollouts · {what}", p.round + 1, p.rollouts)
    };
    if !std::io::stderr().is_terminal() {
        // (round of the last line, seconds at the last line)
        let last = std::sync::Mutex::new((usize::MAX, f64::NEG_INFINITY));
        let progress = Progress(std::sync::Arc::new(move |p: &ProgressInfo| {
            let now = start.elapsed().as_secs_f64();
            let Ok(mut last) = last.lock() else { return };
            if p.round != last.0 || now - last.1 >= LOG_EVERY_S {
                *last = (p.round, now);
                eprintln!("modellint fit: [{now:.0} s] {}", line(p));
            }
        }));
        return (None, Some(progress));
    }
    let bar = progress_bar(quiet);
    let progress = bar
        .clone()
        .map(|b| Progress(std::sync::Arc::new(move |p: &ProgressInfo| b.set_message(line(p)))));
    (bar, progress)
}

/// `--told EFFECT@JOINTS` values as (effect id, joint group): joints `+`-separated, `*` for
/// every fitted joint (those of `--joints`, else every recorded one).
fn parse_told(
    told: &[String],
    recs: &[crate::sim2real::recording::Recording],
    fitted: &[String],
) -> Result<Vec<(String, Vec<String>)>, String> {
    let recorded: Vec<String> = {
        let mut v: Vec<String> = Vec::new();
        for j in recs.iter().flat_map(|r| &r.joints) {
            if !v.contains(&j.name) {
                v.push(j.name.clone());
            }
        }
        v
    };
    let all = if fitted.is_empty() { recorded.clone() } else { fitted.to_vec() };
    told.iter()
        .map(|t| {
            let (id, js) = t
                .split_once('@')
                .ok_or_else(|| format!("--told {t}: expected EFFECT@JOINTS, e.g. viscous_damping@left_knee+right_knee or armature@*"))?;
            if effects::by_id(id).is_none() {
                let ids: Vec<String> = effects::all().iter().map(|e| e.id().to_string()).collect();
                let near = crate::util::near_matches(id, &ids);
                return Err(if near.is_empty() {
                    format!("--told {t}: unknown effect `{id}`; known: {}", ids.join(", "))
                } else {
                    format!("--told {t}: unknown effect `{id}`; did you mean {}?", near.join(", "))
                });
            }
            let joints: Vec<String> = if js == "*" {
                all.clone()
            } else {
                js.split('+').map(str::to_string).collect()
            };
            if let Some(j) = joints.iter().find(|j| !recorded.contains(j)) {
                let near = crate::util::near_matches(j, &recorded);
                return Err(if near.is_empty() {
                    format!("--told {t}: joint `{j}` is not recorded; recorded: {}", recorded.join(", "))
                } else {
                    format!("--told {t}: joint `{j}` is not recorded; did you mean {}?", near.join(", "))
                });
            }
            Ok((id.to_string(), joints))
        })
        .collect()
}

/// What [`prepare`] read: the model, the recordings and the fit's options (without progress).
pub struct Prepared {
    pub loaded: Loaded,
    pub recs: Vec<Recording>,
    /// Joints left out with `--no-command`: replayed, never fitted nor scored.
    pub unscored: Vec<String>,
    pub opts: FitOptions,
    /// `--holdout-by KEY` (no `=VALUE`): every value of KEY held out in turn.
    pub rotate_by: Option<String>,
    /// What reading the recordings found out (also printed through the sink).
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
}

/// Everything before the search: loads the model, checks the options, reads the recordings
/// (their warnings and notes go to `sink` at once, before minutes of fitting).
pub fn prepare(a: &FitArgs, sink: &dyn Sink) -> Result<Prepared, CmdError> {
    let mut loaded = crate::lint::load_for_api(&a.model, a.spec.clone()).map_err(CmdError::Load)?;
    crate::sim2real::replay::hold_base(&mut loaded.robot, a.replay.base);
    let robot = &loaded.robot;
    let mut replay = a.replay.clone();
    replay.pd_gains = crate::sim2real::replay::spec_pd_gains(loaded.spec.as_ref(), robot);
    // A candidate is a registered effect (a held component, `EFFECT~PARAMETER`, is told only).
    for e in &a.effects {
        if !effects::all().iter().any(|x| x.id() == e) {
            let ids: Vec<String> = effects::all().iter().map(|e| e.id().to_string()).collect();
            return Err(format!("unknown effect `{e}`; known: {}", ids.join(", ")).into());
        }
    }
    if a.holdout < 2 {
        return Err("--holdout must be at least 2".to_string().into());
    }
    if let Some(hz) = a.replay.control_hz
        && let Err(e) = crate::spec::control_hz_domain(hz)
    {
        return Err(format!("--control-hz {e}").into());
    }
    if let Some(w) = a.window
        && !(w.is_finite() && w > 0.0)
    {
        return Err(format!(
            "--window {w}: the window length must be a positive number of seconds (e.g. 1.0)"
        )
        .into());
    }
    let files = crate::sim2real::input::expand_inputs(&a.recordings).map_err(|e| e.to_string())?;
    let names: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    let mut inputs =
        crate::sim2real::input::read_for_replay(&files.files, robot, &replay, &a.parse)?;
    if let Some(n) = files.skipped_note() {
        inputs.notes.insert(0, n);
    }
    // The nominal model's own discretisation error beside its gap to the recordings.
    if let Some(w) = crate::sim2real::replay::timestep_check(robot, &inputs.recs, &replay, None)
        .as_ref()
        .and_then(crate::sim2real::replay::timestep_note)
    {
        inputs.notes.push(w);
    }
    // Said now (before minutes of fitting) and again in the JSON.
    for w in &inputs.warnings {
        sink.warning(w);
    }
    for n in &inputs.notes {
        sink.note(n);
    }
    let recs = inputs.recs;
    let unscored = inputs.unscored;
    let mut joints = Vec::new();
    if let Some(g) = &a.joints {
        let m = globset::Glob::new(g).map_err(|e| format!("--joints: {e}"))?.compile_matcher();
        for r in &recs {
            for j in &r.joints {
                if m.is_match(&j.name) && !joints.contains(&j.name) {
                    joints.push(j.name.clone());
                }
            }
        }
        if joints.is_empty() {
            return Err(format!("--joints {g} matches no recorded joint").into());
        }
    }
    // Joints left out with --no-command: replayed, never fitted nor scored (the fit scores
    // the joints it fits).
    if !unscored.is_empty() {
        if joints.is_empty() {
            for r in &recs {
                for j in &r.joints {
                    if !joints.contains(&j.name) {
                        joints.push(j.name.clone());
                    }
                }
            }
        }
        joints.retain(|j| !unscored.contains(j));
        if joints.is_empty() {
            return Err(format!(
                "no joint left to fit: the joints chosen are left out by --no-command ({})",
                unscored.join(", ")
            )
            .into());
        }
    }
    let told = parse_told(&a.told, &recs, &joints)?;
    let families = FitOptions::motor_families(loaded.spec.as_ref(), &names);
    let mut opts = FitOptions {
        holdout: a.holdout,
        effects: a.effects.clone(),
        joints,
        replay,
        shooting_s: a.window,
        families,
        estimate_start: a.start_estimate,
        told,
        ..Default::default()
    };
    let mut rotate_by = None;
    if let Some(by) = &a.holdout_by {
        match by.split_once('=') {
            Some((k, v)) if !k.is_empty() && !v.is_empty() => {
                // A key or value no recording has is the user's error, said before any work.
                crate::fit::split::split_by_key(&recs, k, v)?;
                opts.holdout_by = Some((k.to_string(), v.to_string()))
            }
            Some(_) => return Err(format!("--holdout-by {by}: expected KEY or KEY=VALUE").into()),
            None => rotate_by = Some(by.clone()),
        }
    }
    Ok(Prepared {
        loaded,
        recs,
        unscored,
        opts,
        rotate_by,
        notes: inputs.notes,
        warnings: inputs.warnings,
    })
}

/// One fit's result: what the search kept and the held-out episodes before → after it.
pub struct FitRun {
    pub out: FitOutcome,
    pub before: GapReport,
    pub after: GapReport,
    /// Joints the final model leaves above the search's white ratio of their floor.
    pub unexplained: Vec<crate::fit::unexplained::Unexplained>,
    /// Feet whose orientation the final model leaves above their joints' floors
    /// ([`crate::fit::contact`]).
    pub feet: Vec<crate::fit::contact::FootResidual>,
    /// Everything said through the sink, also in the JSON.
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
}

/// The search on `p` (with `progress`; `searched` is called when it ends, before anything
/// more is said), the held-out episodes before → after, and the files `a` asks for (report,
/// model, actuator TOML).
pub fn fit_once(
    a: &FitArgs,
    p: &Prepared,
    sink: &dyn Sink,
    progress: Option<Progress>,
    searched: &dyn Fn(),
) -> Result<FitRun, CmdError> {
    let robot = &p.loaded.robot;
    let replay = &p.opts.replay;
    let opts = FitOptions { progress, ..p.opts.clone() };
    let mut out = fit(robot, &p.recs, &opts);
    if opts.cancel.as_ref().is_some_and(|c| c.is_set()) {
        return Err(CmdError::Message("the fit was cancelled".into()));
    }
    searched();
    // Kept effects at the model's own value within their uncertainty are not missing physics.
    let within = crate::fit::absent::split_off(robot, &mut out.selected);
    out.notes.extend(within);
    // Nor a body effect whose value is the bound of its search.
    let bounded = crate::fit::absent::split_off_at_bound(robot, &mut out.selected);
    out.warnings.extend(bounded);
    // Nor a body effect the floor's contact explains as well.
    let rivals = crate::fit::floor_rival::split_off(robot, &p.recs, &opts, &mut out, &p.unscored);
    out.warnings.extend(rivals);
    // What the model's timestep puts into the kept values (told re-fits at two timesteps).
    if let Some(s) = crate::fit::timestep_shift::measure(robot, &p.recs, &opts, &mut out) {
        out.notes.push(crate::fit::timestep_shift::note(&s));
        let only = crate::fit::timestep_shift::split_off(&s, &mut out.selected);
        out.notes.extend(only);
    }
    let unexplained = crate::fit::unexplained::unexplained(&out.floors, opts.policy.white_ratio);
    out.warnings.extend(unexplained.iter().map(|u| u.message()));
    for w in &out.warnings {
        sink.warning(w);
    }
    let c = &out.cost;
    let cost_note = format!(
        "search cost: {} rollouts ({:.0} s of recording replayed) in {} batches ({:.1} s simulating), {} dataset simulations; screens saved {} full fits",
        c.rollouts.rollouts,
        c.rollouts.simulated_s,
        c.rollouts.batches,
        c.rollouts.seconds,
        c.simulations,
        c.fits_saved_by_screens
    );
    for n in out.notes.iter().chain([&cost_note]) {
        sink.note(n);
    }
    if out.heldout.is_empty() {
        let why = if out.warnings.is_empty() {
            "no episode could be held out".to_string()
        } else {
            out.warnings.join("; ")
        };
        return Err(CmdError::Said(why));
    }
    let spec = p.loaded.spec.as_ref();
    let region = |name: &str| gap::joint_region(spec, name);
    let run = |applied| -> Result<(GapReport, Vec<Recording>, Vec<Episode>), String> {
        let eps: Result<Vec<Episode>, _> =
            simulate(robot, &out.heldout, applied, replay).into_iter().collect();
        let eps = eps.map_err(|e| e.to_string())?;
        // The held-out episodes as scored: without the joints left out by --no-command.
        let (recs, eps) = crate::sim2real::input::scored_view(&out.heldout, &eps, &p.unscored)
            .ok_or_else(|| "no scored joint in the held-out episodes".to_string())?;
        Ok((gap::compute(&recs, &eps, &region, &GapOptions::default()), recs, eps))
    };
    let (before, heldout, eps_b) = run(&[])?;
    let (after, _, eps_a) = run(&out.applied)?;
    let feet = crate::fit::contact::unexplained_feet(
        robot,
        (&heldout, &eps_b, &eps_a),
        &out.applied,
        opts.policy.white_ratio,
    );
    for f in &feet {
        sink.warning(&f.message());
    }
    let mirrored = mirrored_warning(&before);
    if let Some(w) = &mirrored {
        sink.warning(w);
    }
    // Everything said on stderr also goes into the JSON `notes` / `warnings`.
    let mut notes: Vec<String> =
        p.notes.iter().chain(&out.notes).chain([&cost_note]).cloned().collect();
    let warnings: Vec<String> = p
        .warnings
        .iter()
        .chain(&out.warnings)
        .cloned()
        .chain(feet.iter().map(|f| f.message()))
        .chain(mirrored)
        .collect();
    if let Some(dir) = &a.report {
        let page = crate::fit::report::FitReport {
            model: &a.model,
            selected: &out.selected,
            before: &before,
            after: &after,
            recs: &heldout,
            eps_before: &eps_b,
            eps_after: &eps_a,
        };
        let path = crate::fit::report::write(dir, &page)
            .map_err(|e| format!("cannot write report in {}: {e}", dir.display()))?;
        let msg = format!("report written to {}", path.display());
        sink.said(&msg);
        notes.push(msg);
    }
    if let Some(path) = &a.write_model {
        notes.extend(write_model(&a.model, robot, &out.selected, path, sink)?);
    }
    if let Some(path) = &a.write_actuators {
        let files = crate::fit::writeback::write_actuators(path, robot, &out.selected)?;
        let list: Vec<String> = files.iter().map(|p| p.display().to_string()).collect();
        let msg = format!("actuator parameters written to {}", list.join(", "));
        sink.said(&msg);
        notes.push(msg);
    }
    Ok(FitRun { out, before, after, unexplained, feet, notes, warnings })
}

/// `--write-model`: the model with the MuJoCo-expressible fitted values; returns the notes it
/// made (also said through `sink`).
pub fn write_model(
    model: &std::path::Path,
    robot: &crate::model::Robot,
    selected: &[crate::fit::select::Selected],
    path: &std::path::Path,
    sink: &dyn Sink,
) -> Result<Vec<String>, CmdError> {
    let w = crate::fit::writemodel::write_model(model, robot, selected, path)?;
    let mut notes = Vec::new();
    for n in w.notes {
        sink.note_always(&n);
        notes.push(n);
    }
    let list: Vec<String> = w.files.iter().map(|p| p.display().to_string()).collect();
    let msg = if w.changed {
        format!("fitted model written to {}", list.join(", "))
    } else {
        format!("model written to {} (no fitted value in it: see the note above)", list.join(", "))
    };
    sink.said(&msg);
    notes.push(msg);
    Ok(notes)
}

pub fn run_fit(a: FitArgs) -> i32 {
    let sink = Stderr::new(a.quiet);
    let p = match prepare(&a, &sink) {
        Ok(p) => p,
        Err(e) => return crate::sim2real::cmd::report_error(&e),
    };
    if let Some(key) = &p.rotate_by {
        return crate::fit::cmd_rotate::rotate(&p, key, &a);
    }
    let (bar, progress) = fit_progress(a.quiet, String::new());
    let done = || {
        if let Some(b) = &bar {
            b.finish_and_clear();
        }
    };
    let r = match fit_once(&a, &p, &sink, progress, &done) {
        Ok(r) => r,
        Err(e) => return crate::sim2real::cmd::report_error(&e),
    };
    let text = if a.json {
        serde_json::to_string_pretty(&fit_json(&r)).unwrap_or_default() + "\n"
    } else {
        fit_text(&r)
    };
    if std::io::stdout().lock().write_all(text.as_bytes()).is_err() {
        return 2;
    }
    0
}

/// What `modellint fit --format json` prints (and the Python API returns).
pub fn fit_json(r: &FitRun) -> serde_json::Value {
    let (out, before, after) = (&r.out, &r.before, &r.after);
    let (warnings, notes) = (&r.warnings, &r.notes);
    let mp: Vec<_> = out
        .selected
        .iter()
        .map(|s| {
            json!({
                "effect": s.effect, "joints": s.joints, "params": s.params,
                "stderr": s.stderr.iter().map(|(k, v)| (k.clone(), if v.is_finite() { json!(v) } else { serde_json::Value::Null })).collect::<serde_json::Map<_, _>>(),
                "identifiable": s.identifiable, "unidentified": s.unidentified, "evidence": s.evidence, "heldout_improvement": s.heldout_improvement,
                "heldout_rmse_before": s.heldout_rmse_before, "heldout_rmse_after": s.heldout_rmse_after,
                "params_meaning": effects::by_id(&s.effect).map_or(&[][..], |e| e.param_meaning()).iter().copied().collect::<std::collections::BTreeMap<_, _>>(),
            })
        })
        .collect();
    let mut v = json!({
        "missing_physics": mp,
        "before": before,
        "after": after,
        "diagnosis": out.diagnosis.iter().take(20).collect::<Vec<_>>(),
        "tried": out.tried,
        "split": {"train": out.train.len(), "heldout": out.heldout.len(), "by_time": out.split_by_time, "note": out.split_note},
        "floor": out.floors.iter().map(|f| json!({"joint": f.joint, "residual_rms": f.ms.sqrt(), "white_floor_rms": f.white.sqrt(), "reconstruction_floor_rms": f.reconstruction.sqrt(), "discretisation_floor_rms": f.discretisation.sqrt()})).collect::<Vec<_>>(),
        "stopped_at_floor": out.stopped_at_floor,
        "unexplained": r.unexplained.iter().map(|u| json!({"joint": u.joint, "residual_rms": u.residual_rms, "floor_rms": u.floor_rms})).collect::<Vec<_>>(),
        "unexplained_contact": r.feet.iter().map(|x| x.json()).collect::<Vec<_>>(),
        "search": out.cost,
        "warnings": warnings,
        "notes": notes,
    });
    crate::output::json::stamp(&mut v, "fit");
    v
}

/// One fitted parameter as the text output gives it: `name = value ± stderr unit` (an angle
/// also in degrees, as `gap` prints angles), or, when the data do not determine it
/// (`unidentified`), `name not identified (± stderr unit)` — no value.
/// The human output: angles in degrees (as `gap`), SI in JSON; one before → after figure.
fn fit_text(r: &FitRun) -> String {
    let (out, before, after) = (&r.out, &r.before, &r.after);
    let deg = |rad: f64| rad.to_degrees();
    let mut s = String::from("missing physics\n");
    if out.selected.is_empty() {
        s.push_str(if out.stopped_at_floor {
            "  nothing: the training residual is at its noise floor on every joint (nothing left to explain)\n"
        } else if !out.applied.is_empty() {
            "  nothing beyond its uncertainty: every kept effect is the model's own value within two standard errors, or a body at the bound of its search (see the notes and warnings)\n"
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
                let unit =
                    e.and_then(|e| e.params().iter().find(|p| p.name == k)).map_or("", |p| p.unit);
                let se = x.stderr.get(k).copied().unwrap_or(f64::INFINITY);
                super::report::param_text(k, *v, se, unit, x.unidentified.contains(k))
            })
            .collect();
        s.push_str(&format!("  {:<24} {:<28} {}\n", x.effect, x.joints.join(","), ps.join(", ")));
        for (k, m) in e.map_or(&[][..], |e| e.param_meaning()) {
            s.push_str(&format!("      {k}: {m}\n"));
        }
        let shown = e.map_or(&[][..], |e| e.shown_evidence());
        // `implied_*`: the diagnosis's linearised first guess, before any fit; named so that
        // it is not read as the answer.
        let ev: Vec<String> = ["corr", "explained_share"]
            .iter()
            .chain(shown)
            .filter_map(|k| {
                x.evidence.get(*k).map(|v| match k.strip_prefix("implied_") {
                    Some(_) => format!("screen's first guess {v:.3}"),
                    None => format!("{k} {v:.3}"),
                })
            })
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
        // The timestep's part only when the recordings move in finer time than the model.
        let disc = out.floors.iter().any(|f| f.discretisation > 0.0);
        let f: Vec<String> = out
            .floors
            .iter()
            .map(|f| {
                let d = if disc {
                    format!(" + {:.3}°", deg(f.discretisation.sqrt()))
                } else {
                    String::new()
                };
                format!(
                    "{} {:.3}° + {:.3}°{d}",
                    f.joint,
                    deg(f.white.sqrt()),
                    deg(f.reconstruction.sqrt())
                )
            })
            .collect();
        let parts = if disc {
            "white part of the training residual + command reconstruction and start state + the model's timestep"
        } else {
            "white part of the training residual + command reconstruction and start state"
        };
        s.push_str(&format!("  floor of the fitted model (RMS: {parts}): {}\n", f.join(", ")));
    }
    if !out.split_note.is_empty() {
        s.push_str(&format!("  ({})\n", out.split_note));
    }
    s
}

/// The joints that move against their replay on the held-out episodes before the fit
/// (correlation at most [`gap::cause::MIRRORED_CORRELATION`]): what is fitted on them stands in
/// for a sign, not for physics.
fn mirrored_warning(before: &GapReport) -> Option<String> {
    let list: Vec<String> = before
        .per_joint
        .iter()
        .filter_map(|j| {
            let c = j.corr.filter(|&c| c <= gap::cause::MIRRORED_CORRELATION)?;
            Some(format!("{} (correlation {c:.2})", j.name))
        })
        .collect();
    (!list.is_empty()).then(|| {
        format!(
            "{} move(s) against the replay of the model as given: a reversed encoder or joint \
             axis, or another joint's column — whatever was fitted there stands in for a sign, \
             not for missing physics; correct the recording's sign or the model's axis and fit \
             again",
            list.join(", ")
        )
    })
}

#[cfg(test)]
mod tests {
    use crate::fit::report::param_text;

    /// A parameter the data determine is given with its value; one they do not, with its
    /// standard error only.
    #[test]
    fn an_unidentified_parameter_is_not_given_a_value() {
        assert_eq!(param_text("width", 0.0123, 0.371, "m", false), "width = 0.0123 ± 3.71e-1 m");
        assert_eq!(
            param_text("width", 0.0123, 0.371, "m", true),
            "width not identified (± 3.71e-1 m)"
        );
        assert_eq!(param_text("dmin", 0.66, f64::INFINITY, "", true), "dmin not identified (± ?)");
        assert!(param_text("offset", 0.01, 1e-3, "rad", false).contains("rad (0.5730°)"));
    }
}
