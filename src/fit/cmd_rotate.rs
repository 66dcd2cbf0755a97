//! `modellint fit --holdout-by KEY`: the selection run once per value of KEY, that value held
//! out ([`crate::fit::rotation`]), printed fold by fold.

use std::io::Write;

use serde_json::json;

use crate::fit::cmd::{FitArgs, Prepared, fit_progress};
use crate::fit::rotation;
use crate::fit::select::FitOptions;

fn fail(msg: impl std::fmt::Display) -> i32 {
    eprintln!("modellint: {msg}");
    2
}

/// `--holdout-by KEY`: leave-one-group-out over the values of metadata `KEY`
/// ([`crate::fit::rotation`]). Prints every fold's effects and held-out MAE before → after per
/// episode, and the average over all episodes (each held out exactly once).
pub fn rotate(p: &Prepared, key: &str, a: &FitArgs) -> i32 {
    let (robot, recs, opts, unscored) = (&p.loaded.robot, &p.recs, &p.opts, &p.unscored);
    if a.write_model.is_some() || a.write_actuators.is_some() || a.report.is_some() {
        return fail(format!(
            "--holdout-by {key} rotates over every value of `{key}` (one fit per value); give \
             --holdout-by {key}=VALUE to write a model, actuator TOML or report"
        ));
    }
    let values = crate::fit::split::key_values(recs, key);
    if values.len() < 2 {
        return fail(format!(
            "--holdout-by {key}: need at least two values of `{key}` to hold one out (found {})",
            values.len()
        ));
    }
    let t0 = std::time::Instant::now();
    let mut folds = Vec::new();
    for v in &values {
        let (bar, progress) = fit_progress(a.quiet, format!("hold out {key} = {v} · "));
        let f =
            rotation::fold(robot, recs, &FitOptions { progress, ..opts.clone() }, key, v, unscored);
        if let Some(b) = bar {
            b.finish_and_clear();
        }
        let f = match f {
            Ok(f) => f,
            Err(e) => return fail(e),
        };
        for w in &f.outcome.warnings {
            eprintln!("modellint: warning: {key} = {v}: {w}");
        }
        if !a.quiet {
            for n in &f.outcome.notes {
                eprintln!("modellint: note: {key} = {v}: {n}");
            }
        }
        folds.push(f);
    }
    let (avg_b, avg_a) = rotation::mean_mae(folds.iter().flat_map(|f| &f.heldout));
    let n_eps: usize = folds.iter().map(|f| f.heldout.len()).sum();
    let text = if a.json {
        let fs: Vec<_> = folds
            .iter()
            .map(|f| {
                let out = &f.outcome;
                let (b, a) = f.mean();
                json!({
                    "value": f.value,
                    "train": out.train.len(),
                    "selected": out.selected.iter().map(|s| json!({"effect": s.effect, "joints": s.joints, "params": s.params})).collect::<Vec<_>>(),
                    "heldout": f.heldout.iter().map(|e| json!({"source": e.name, "position_mae_before": e.before, "position_mae_after": e.after})).collect::<Vec<_>>(),
                    "position_mae_before": b,
                    "position_mae_after": a,
                    "seconds": f.seconds,
                    "tried": out.tried,
                    "warnings": out.warnings,
                    "notes": out.notes,
                })
            })
            .collect();
        let v = json!({
            "holdout_by": key,
            "folds": fs,
            "position_mae_before": avg_b,
            "position_mae_after": avg_a,
            "episodes": n_eps,
            "seconds": t0.elapsed().as_secs_f64(),
        });
        serde_json::to_string_pretty(&v).unwrap_or_default() + "\n"
    } else {
        let deg = |x: f64| x.to_degrees();
        let mut s = format!(
            "cross-validation by `{key}`: each of {} values held out in turn, the selection run on the others\n",
            values.len()
        );
        for f in &folds {
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
                let ps: Vec<String> =
                    x.params.iter().map(|(k, v)| format!("{k} = {v:.4}")).collect();
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
            t0.elapsed().as_secs_f64()
        ));
        s
    };
    if std::io::stdout().lock().write_all(text.as_bytes()).is_err() {
        return 2;
    }
    0
}
