//! The BAM XL330 held-out experiment as a library routine: fit on the logs of three firmware
//! gains, evaluate on the fourth, rotate all four, and report (markdown) against BAM's published
//! anchors. Used by `modellint fit --servo xl330` and `examples/bam_fit.rs`.

use std::time::Instant;

use crate::fit::servo::EffectSet;
use crate::fit::servo_fit::{self, FitOpts, FoldReport, ServoLog};
use crate::model::Robot;
use crate::sim2real::replay::{self, ReplayOptions};

/// Runs every fold and returns the markdown report and the fold reports.
pub fn run(
    robot: &Robot,
    logs: &[ServoLog],
    o: &FitOpts,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<(String, Vec<FoldReport>), String> {
    let t0 = Instant::now();
    let mut out = String::new();
    let all: Vec<usize> = (0..logs.len()).collect();
    progress(&format!(
        "{} logs; optimiser {:?}, {} evals per fit",
        logs.len(),
        o.optimiser,
        o.max_evals
    ));

    // Nominal figures on all logs: the rig's linear MuJoCo actuator (no duty clip) and the
    // firmware law with its clip (ServoHook, no friction).
    let recs: Vec<_> = logs.iter().map(|l| l.rec.clone()).collect();
    let rp = replay::Replayer::new(robot);
    let lin: Vec<f64> = replay::replay_all(&rp, &recs, &ReplayOptions::default(), None)
        .into_iter()
        .zip(logs)
        .map(|(e, l)| {
            let Ok(e) = e else { return f64::NAN };
            servo_fit::mae(
                &e.q_sim[0].iter().zip(&l.rec.joints[0].q).map(|(s, r)| s - r).collect::<Vec<_>>(),
            )
        })
        .collect();
    let nominal = EffectSet(vec![]);
    let nom: Vec<f64> = servo_fit::residuals(robot, logs, &all, &nominal, &[])
        .iter()
        .map(|r| servo_fit::mae(r))
        .collect();
    let avg = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    progress(&format!(
        "nominal on all logs: linear rig {:.2}°, firmware law {:.2}° ({:.2} s)",
        avg(&lin).to_degrees(),
        avg(&nom).to_degrees(),
        t0.elapsed().as_secs_f64()
    ));
    if o.max_evals == 0 {
        for (i, l) in logs.iter().enumerate() {
            progress(&format!(
                "{} kp {} {:<16} linear {:.2}° law {:.2}°",
                l.name,
                l.kp,
                l.trajectory,
                lin[i].to_degrees(),
                nom[i].to_degrees()
            ));
        }
        return Ok((out, Vec::new()));
    }

    let mut folds = Vec::new();
    for kp in servo_fit::gains(logs) {
        let (train, test) = servo_fit::split_by_kp(logs, kp);
        progress(&format!(
            "fold: hold out kp {kp} ({} train / {} test logs)",
            train.len(),
            test.len()
        ));
        let f = servo_fit::forward_select(robot, logs, &train, &test, o, &|s| progress(s));
        progress(&format!("  fold done in {:.1} s", f.seconds));
        folds.push(f);
    }

    out.push_str("\n## BAM XL330: forward selection, fit on 3 gains, held-out MAE on the 4th\n");
    out.push('\n');
    out.push_str("| held-out kp | effects chosen | parameters (± stderr) | nominal held-out MAE | fitted held-out MAE | fold time |");
    out.push('\n');
    out.push_str("|---|---|---|---|---|---|");
    out.push('\n');
    let mut per_log = vec![f64::NAN; logs.len()];
    for f in &folds {
        let c = &f.chosen;
        let params: Vec<String> = (0..c.x.len())
            .map(|k| {
                format!(
                    "{} = {:.4} ± {:.4} {}",
                    c.param_names[k], c.x[k], c.stderr[k], c.param_units[k]
                )
                .trim_end()
                .to_string()
            })
            .collect();
        out.push_str(&format!(
            "| {} | {} | {} | {:.2}° | **{:.2}°** | {:.0} s |",
            f.held_out_kp,
            EffectSet(c.effects.clone()).names(),
            params.join("; "),
            f.nominal.test_mae.to_degrees(),
            c.test_mae.to_degrees(),
            f.seconds
        ));
        out.push('\n');
        for (k, &i) in f.test.iter().enumerate() {
            per_log[i] = c.test_mae_per_log[k];
        }
    }
    out.push_str("\n### Every candidate fitted alone on the nominal model (round 1): what each effect buys\n");
    out.push('\n');
    out.push_str(&format!(
        "| effect | {} |",
        folds
            .iter()
            .map(|f| format!("hold-out kp {}: params → train / held-out MAE", f.held_out_kp))
            .collect::<Vec<_>>()
            .join(" | ")
    ));
    out.push('\n');
    out.push_str(&format!("|---|{}", "---|".repeat(folds.len())));
    out.push('\n');
    for e in &o.candidates {
        let cells: Vec<String> = folds
            .iter()
            .map(|f| match f.trials.iter().find(|t| t.round == 1 && t.effect == *e) {
                Some(t) => format!(
                    "{} → {:.2}° / {:.2}°",
                    e.params()
                        .iter()
                        .zip(&t.x)
                        .map(|(p, v)| format!("{} {:.4}", p.name, v))
                        .collect::<Vec<_>>()
                        .join(", "),
                    t.train_mae.to_degrees(),
                    t.test_mae.to_degrees()
                ),
                None => "–".into(),
            })
            .collect();
        out.push_str(&format!("| {} | {} |", e.name(), cells.join(" | ")));
        out.push('\n');
    }
    out.push_str("\n### Held-out MAE per log\n");
    out.push('\n');
    out.push_str("| log | kp | trajectory | linear rig (no clip) | nominal firmware law | fitted (held out) |");
    out.push('\n');
    out.push_str("|---|---|---|---|---|---|");
    out.push('\n');
    for (i, l) in logs.iter().enumerate() {
        out.push_str(&format!(
            "| {} | {} | {} | {:.2}° | {:.2}° | {:.2}° |",
            l.name,
            l.kp,
            l.trajectory,
            lin[i].to_degrees(),
            nom[i].to_degrees(),
            per_log[i].to_degrees()
        ));
        out.push('\n');
    }
    out.push_str("\n### Average over the 16 logs (whole-log position MAE)\n");
    out.push('\n');
    out.push_str("| model | average MAE |");
    out.push('\n');
    out.push_str("|---|---|");
    out.push('\n');
    out.push_str("| BAM no friction (BAM's 5 ms resampling) | 8.05° |");
    out.push('\n');
    out.push_str("| BAM M1, Coulomb + viscous (BAM's 5 ms resampling) | 4.69° |");
    out.push('\n');
    out.push_str("| BAM M3, load-dependent (BAM's 5 ms resampling) | 3.96° |");
    out.push('\n');
    out.push_str(&format!(
        "| modellint rig, linear actuator, no clip (log timestamps) | {:.2}° |",
        avg(&lin).to_degrees()
    ));
    out.push('\n');
    out.push_str(&format!(
        "| modellint nominal firmware law, no friction (log timestamps) | {:.2}° |",
        avg(&nom).to_degrees()
    ));
    out.push('\n');
    out.push_str(&format!(
        "| **modellint fitted, each log held out (log timestamps)** | **{:.2}°** |",
        avg(&per_log).to_degrees()
    ));
    out.push('\n');
    out.push_str("\nBAM's figures are fitted on all logs and evaluated on their 5 ms resampling; ours are held-out and at the logs' own timestamps.");
    out.push('\n');
    out.push_str(&format!("total time {:.0} s\n", t0.elapsed().as_secs_f64()));
    Ok((out, folds))
}
