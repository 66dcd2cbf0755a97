//! `modellint fit --holdout-by KEY`: the selection run once per value of KEY, that value held
//! out ([`crate::fit::rotation`]), printed fold by fold.

use std::io::Write;

use serde_json::json;

use crate::error::CmdError;
use crate::fit::cmd::{FitArgs, Prepared, fit_progress};
use crate::fit::rotation;
use crate::fit::select::{FitOptions, Progress};
use crate::sink::{Sink, Stderr};

fn fail(msg: impl std::fmt::Display) -> i32 {
    eprintln!("modellint: {msg}");
    2
}

/// The folds of a `--holdout-by KEY` rotation, in the order of KEY's values.
pub struct Rotation {
    pub key: String,
    pub values: Vec<String>,
    pub folds: Vec<rotation::Fold>,
    /// Wall time of the whole rotation [s].
    pub seconds: f64,
}

/// Runs the rotation: one fit per value of `key`, that value held out. Each fold's warnings and
/// notes go to `sink` prefixed `KEY = VALUE: `; `fold_progress(Some(value))` gives the
/// progress callback of a fold as it starts, `fold_progress(None)` says it ended.
pub fn rotate_run(
    p: &Prepared,
    key: &str,
    a: &FitArgs,
    sink: &dyn Sink,
    fold_progress: &mut dyn FnMut(Option<&str>) -> Option<Progress>,
) -> Result<Rotation, CmdError> {
    let (robot, recs, opts, unscored) = (&p.loaded.robot, &p.recs, &p.opts, &p.unscored);
    if a.write_model.is_some() || a.write_actuators.is_some() || a.report.is_some() {
        return Err(CmdError::Message(format!(
            "--holdout-by {key} rotates over every value of `{key}` (one fit per value); give \
             --holdout-by {key}=VALUE to write a model, actuator TOML or report"
        )));
    }
    let values = crate::fit::split::key_values(recs, key);
    if values.is_empty() {
        let mut keys: Vec<&str> =
            recs.iter().flat_map(|r| r.meta.keys().map(String::as_str)).collect();
        keys.sort_unstable();
        keys.dedup();
        let found = if keys.is_empty() {
            "they have no `# key: value` metadata".to_string()
        } else {
            format!("their keys: {}", keys.join(", "))
        };
        return Err(CmdError::Message(format!(
            "--holdout-by {key}: no recording has the key `{key}` ({found})"
        )));
    }
    if values.len() < 2 {
        return Err(CmdError::Message(format!(
            "--holdout-by {key}: need at least two values of `{key}` to hold one out (found {})",
            values.len()
        )));
    }
    let t0 = std::time::Instant::now();
    let mut folds = Vec::new();
    for v in &values {
        let progress = fold_progress(Some(v));
        let f =
            rotation::fold(robot, recs, &FitOptions { progress, ..opts.clone() }, key, v, unscored);
        fold_progress(None);
        if opts.cancel.as_ref().is_some_and(|c| c.is_set()) {
            return Err(CmdError::Message("the fit was cancelled".into()));
        }
        let f = f.map_err(|e| CmdError::Message(e.to_string()))?;
        for w in &f.outcome.warnings {
            sink.warning(&format!("{key} = {v}: {w}"));
        }
        for n in &f.outcome.notes {
            sink.note(&format!("{key} = {v}: {n}"));
        }
        folds.push(f);
    }
    Ok(Rotation { key: key.to_string(), values, folds, seconds: t0.elapsed().as_secs_f64() })
}

/// The rotation as `fit --holdout-by KEY --format json` prints it.
pub fn rotation_json(r: &Rotation) -> serde_json::Value {
    let (avg_b, avg_a) = rotation::mean_mae(r.folds.iter().flat_map(|f| &f.heldout));
    let n_eps: usize = r.folds.iter().map(|f| f.heldout.len()).sum();
    let fs: Vec<_> = r
        .folds
        .iter()
        .map(|f| {
            let out = &f.outcome;
            let (b, a) = f.mean();
            json!({
                "value": f.value,
                "train": out.train.len(),
                "selected": out.selected.iter().map(|s| json!({"effect": s.effect, "joints": s.joints, "params": s.params, "unidentified": s.unidentified})).collect::<Vec<_>>(),
                "heldout": f.heldout.iter().map(|e| json!({"source": e.name, "position_mae_before": e.before, "position_mae_after": e.after})).collect::<Vec<_>>(),
                "position_mae_before": b,
                "position_mae_after": a,
                "seconds": f.seconds,
                "tried": out.tried,
                "unexplained": f.unexplained.iter().map(|u| json!({"joint": u.joint, "residual_rms": u.residual_rms, "floor_rms": u.floor_rms})).collect::<Vec<_>>(),
                "unexplained_contact": f.feet.iter().map(|x| x.json()).collect::<Vec<_>>(),
                "warnings": out.warnings,
                "notes": out.notes,
            })
        })
        .collect();
    json!({
        "holdout_by": r.key,
        "folds": fs,
        "position_mae_before": avg_b,
        "position_mae_after": avg_a,
        "episodes": n_eps,
        "seconds": r.seconds,
    })
}

/// `--holdout-by KEY`: leave-one-group-out over the values of metadata `KEY`
/// ([`crate::fit::rotation`]). Prints every fold's effects and held-out MAE before → after per
/// episode, and the average over all episodes (each held out exactly once).
pub fn rotate(p: &Prepared, key: &str, a: &FitArgs) -> i32 {
    let mut bar: Option<indicatif::ProgressBar> = None;
    let mut fold_progress = |v: Option<&str>| match v {
        Some(v) => {
            let (b, progress) = fit_progress(a.quiet, format!("hold out {key} = {v} · "));
            bar = b;
            progress
        }
        None => {
            if let Some(b) = bar.take() {
                b.finish_and_clear();
            }
            None
        }
    };
    let r = match rotate_run(p, key, a, &Stderr::new(a.quiet), &mut fold_progress) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    let (values, folds) = (&r.values, &r.folds);
    let (avg_b, avg_a) = rotation::mean_mae(folds.iter().flat_map(|f| &f.heldout));
    let n_eps: usize = folds.iter().map(|f| f.heldout.len()).sum();
    let text = if a.json {
        serde_json::to_string_pretty(&rotation_json(&r)).unwrap_or_default() + "\n"
    } else {
        let deg = |x: f64| x.to_degrees();
        let mut s = format!(
            "cross-validation by `{key}`: each of {} values held out in turn, the selection run on the others\n",
            values.len()
        );
        for f in folds {
            let out = &f.outcome;
            s.push_str(&format!(
                "\n{key} = {} held out ({} episodes; trained on {}; {:.0} s)\n",
                f.value,
                f.heldout.len(),
                out.train.len(),
                f.seconds
            ));
            if out.selected.is_empty() {
                s.push_str("  missing physics: nothing kept\n");
            }
            for x in &out.selected {
                // A parameter the fold's data do not determine is said so, not given a value.
                let ps: Vec<String> = x
                    .params
                    .iter()
                    .map(|(k, v)| {
                        if x.unidentified.contains(k) {
                            format!("{k} not identified")
                        } else {
                            format!("{k} = {v:.4}")
                        }
                    })
                    .collect();
                s.push_str(&format!(
                    "  {:<24} {:<12} {}\n",
                    x.effect,
                    x.joints.join(","),
                    ps.join(", ")
                ));
            }
            for e in &f.heldout {
                s.push_str(&format!(
                    "    {:<32} position MAE {:.2}° → {:.2}°\n",
                    e.name,
                    deg(e.before),
                    deg(e.after)
                ));
            }
            let (b, a) = f.mean();
            s.push_str(&format!(
                "  held-out position MAE (mean over its episodes) {:.2}° → {:.2}°\n",
                deg(b),
                deg(a)
            ));
        }
        s.push_str(&format!(
            "\nheld-out position MAE, mean over the {} episodes (each held out once): {:.2}° → {:.2}°  ({:.0} s)\n",
            n_eps,
            deg(avg_b),
            deg(avg_a),
            r.seconds
        ));
        s
    };
    if std::io::stdout().lock().write_all(text.as_bytes()).is_err() {
        return 2;
    }
    0
}
