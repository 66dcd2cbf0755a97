//! `fit --report DIR`: ONE self-contained page (`DIR/index.html`, inline SVG, no scripts, no
//! network) that shows what the fit changed on the held-out episodes: the missing physics with
//! uncertainties, the before → after summary, the error per joint before → after, real vs
//! sim-before vs sim-after overlaid per joint, the PSD before → after, and the episodes.
//! Angles in degrees (the JSON output keeps SI).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::fit::effects;
use crate::fit::select::Selected;
use crate::sim2real::gap::GapReport;
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::Episode;
use crate::sim2real::report::episode_names;
use crate::sim2real::svg::{self, BarGroup, Series, esc, line_plot};

const REAL: &str = "#1f77b4";
const BEFORE: &str = "#d62728";
const AFTER: &str = "#2ca02c";
const GREY: &str = "#9a9a9a";

/// Everything the page shows.
pub struct FitReport<'a> {
    pub model: &'a Path,
    pub selected: &'a [Selected],
    pub before: &'a GapReport,
    pub after: &'a GapReport,
    pub recs: &'a [Recording],
    pub eps_before: &'a [Episode],
    pub eps_after: &'a [Episode],
}

fn pct(before: f64, after: f64) -> String {
    if before > 0.0 && before.is_finite() && after.is_finite() {
        format!("{:+.0} %", 100.0 * (after - before) / before)
    } else {
        "n/a".into()
    }
}

/// Four significant digits ("0.001489", "2.000"), scientific outside 1e-4..1e5.
fn sig(v: f64) -> String {
    sig_n(v, 4)
}

/// `n` significant digits.
fn sig_n(v: f64, n: i32) -> String {
    if !v.is_finite() {
        return "?".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let mag = v.abs().log10().floor() as i32;
    if (-4..5).contains(&mag) {
        let dec = (n - 1 - mag).max(0) as usize;
        format!("{v:.dec$}")
    } else {
        let d = (n - 1).max(0) as usize;
        format!("{v:.d$e}")
    }
}

/// A fitted parameter as text: value ± standard error and unit (an angle also in degrees), or
/// "not identified".
pub(crate) fn param_text(k: &str, v: f64, se: f64, unit: &str, unidentified: bool) -> String {
    let pm = if se.is_finite() { format!(" ± {se:.2e}") } else { " ± ?".into() };
    if unidentified {
        let u = if unit.is_empty() { String::new() } else { format!(" {unit}") };
        return format!("{k} not identified ({}{u})", pm.trim_start());
    }
    match unit {
        "rad" => format!("{k} = {v:.6}{pm} rad ({:.4}°)", v.to_degrees()),
        "" => format!("{k} = {v:.4}{pm}"),
        _ => format!("{k} = {v:.4}{pm} {unit}"),
    }
}

fn missing_physics(sel: &[Selected]) -> String {
    let mut h = String::from("<h2>Missing physics</h2>");
    if sel.is_empty() {
        h.push_str("<p>Nothing: no candidate effect improved the held-out error beyond noise.</p>");
        return h;
    }
    h.push_str(
        "<table><tr><th>effect</th><th>joints</th><th>parameter</th><th>value ± standard error</th><th>identifiable</th>\
         <th>held-out RMSE before → after [deg]</th><th>change</th></tr>",
    );
    for s in sel {
        let e = effects::by_id(&s.effect);
        let rows: Vec<(String, String)> = s
            .params
            .iter()
            .map(|(k, v)| {
                let unit =
                    e.and_then(|e| e.params().iter().find(|p| p.name == k)).map_or("", |p| p.unit);
                let se = s.stderr.get(k).copied().unwrap_or(f64::INFINITY);
                let se =
                    if se.is_finite() { format!(" ± {}", sig_n(se, 2)) } else { " ± ?".into() };
                let value =
                    if s.unidentified.contains(k) { "not identified".to_string() } else { sig(*v) };
                (k.clone(), format!("{value}{se} {unit}"))
            })
            .collect();
        let n = rows.len().max(1);
        for (i, (k, v)) in rows.iter().enumerate() {
            h.push_str("<tr>");
            if i == 0 {
                let _ = write!(
                    h,
                    "<td rowspan=\"{n}\" class=\"l\">{}</td><td rowspan=\"{n}\" class=\"l\">{}</td>",
                    esc(&s.effect),
                    esc(&s.joints.join(", "))
                );
            }
            let meaning = e
                .and_then(|e| e.param_meaning().iter().find(|(n, _)| n == k))
                .map_or(String::new(), |(_, m)| format!("<br><small>{}</small>", esc(m)));
            let _ = write!(h, "<td class=\"l\">{}{meaning}</td><td>{}</td>", esc(k), esc(v));
            if i == 0 {
                let _ = write!(
                    h,
                    "<td rowspan=\"{n}\">{}</td><td rowspan=\"{n}\">{:.3} → {:.3}</td><td rowspan=\"{n}\">{}</td>",
                    if s.identifiable { "yes" } else { "no" },
                    s.heldout_rmse_before.to_degrees(),
                    s.heldout_rmse_after.to_degrees(),
                    pct(s.heldout_rmse_before, s.heldout_rmse_after)
                );
            }
            h.push_str("</tr>");
        }
    }
    h.push_str("</table><p class=\"note\">Standard errors from the fit's Jacobian, inflated for the autocorrelation of the residuals; \"identifiable: no\" means the data do not determine every parameter.</p>");
    h
}

fn summary(b: &GapReport, a: &GapReport) -> String {
    let mut h = String::from(
        "<h2>Held-out episodes: before → after</h2><table><tr><th>metric</th><th>before</th><th>after</th><th>change</th></tr>",
    );
    let rows: [(&str, f64, f64, usize); 5] = [
        ("position MAE [deg]", b.position_mae.to_degrees(), a.position_mae.to_degrees(), 3),
        ("position RMSE [deg]", b.position_rmse.to_degrees(), a.position_rmse.to_degrees(), 3),
        ("velocity RMSE [deg/s]", b.velocity_rmse.to_degrees(), a.velocity_rmse.to_degrees(), 2),
        ("correlation", b.correlation_mean, a.correlation_mean, 3),
        ("gap score (0 = no gap)", b.gap_overall, a.gap_overall, 3),
    ];
    for (name, x, y, d) in rows {
        let change =
            if name.starts_with("correlation") { format!("{:+.3}", y - x) } else { pct(x, y) };
        let _ = write!(
            h,
            "<tr><td class=\"l\">{name}</td><td>{x:.d$}</td><td>{y:.d$}</td><td>{change}</td></tr>"
        );
    }
    h.push_str("</table>");
    h
}

fn per_joint(b: &GapReport, a: &GapReport) -> String {
    let mut h = String::from("<h2>Error per joint: before → after</h2>");
    let pairs: Vec<(&str, f64, f64)> = b
        .per_joint
        .iter()
        .filter_map(|jb| {
            a.per_joint
                .iter()
                .find(|ja| ja.name == jb.name)
                .map(|ja| (jb.name.as_str(), jb.mae.to_degrees(), ja.mae.to_degrees()))
        })
        .collect();
    if pairs.len() >= 2 {
        let groups: Vec<BarGroup> = pairs
            .iter()
            .map(|(n, x, y)| BarGroup {
                label: n.to_string(),
                values: vec![*x, *y],
                tip: format!("{n}: {x:.3}° → {y:.3}°"),
                colours: vec![],
            })
            .collect();
        h.push_str(&svg::bar_chart(
            "Position MAE per joint, held-out episodes [deg]",
            "MAE [deg]",
            &[("before the fit", GREY), ("after the fit", AFTER)],
            &groups,
        ));
    }
    h.push_str("<table><tr><th>joint</th><th>MAE before [deg]</th><th>MAE after [deg]</th><th>change</th></tr>");
    for (n, x, y) in &pairs {
        let _ = write!(
            h,
            "<tr><td class=\"l\">{}</td><td>{x:.3}</td><td>{y:.3}</td><td>{}</td></tr>",
            esc(n),
            pct(*x, *y)
        );
    }
    h.push_str("</table>");
    h
}

/// Joints to plot: the fitted ones first, then the largest errors before the fit; at most 6.
fn joints_to_plot(r: &FitReport) -> Vec<String> {
    let mut js: Vec<String> = Vec::new();
    for s in r.selected {
        for j in &s.joints {
            if !js.contains(j) && r.before.per_joint.iter().any(|p| &p.name == j) {
                js.push(j.clone());
            }
        }
    }
    let mut rest: Vec<_> = r.before.per_joint.iter().filter(|p| !js.contains(&p.name)).collect();
    rest.sort_by(|a, b| b.mae.total_cmp(&a.mae));
    js.extend(rest.into_iter().map(|p| p.name.clone()));
    js.truncate(6);
    js
}

fn overlays(r: &FitReport, joints: &[String]) -> String {
    let mut h = String::from(
        "<h2>Recorded vs replayed, before and after the fit (held-out episode with the largest error before)</h2><p>recorded: the joint position in the recording; replayed before / after: MuJoCo's simulation of the model as given / of the fitted model, driven by the recorded commands. Angles in degrees.</p><div class=\"grid\">",
    );
    for jn in joints {
        let worst = r
            .before
            .per_episode
            .iter()
            .enumerate()
            .filter(|(_, e)| e.diverged.is_none())
            .filter_map(|(i, e)| e.per_joint.iter().find(|j| &j.name == jn).map(|j| (i, j.rmse)))
            .filter(|(_, x)| x.is_finite())
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((ei, _)) = worst else { continue };
        let (Some(rec), Some(eb), Some(ea)) =
            (r.recs.get(ei), r.eps_before.get(ei), r.eps_after.get(ei))
        else {
            continue;
        };
        let (Some(jt), Some(kb), Some(ka)) = (
            rec.joint(jn),
            eb.joints.iter().position(|x| x == jn),
            ea.joints.iter().position(|x| x == jn),
        ) else {
            continue;
        };
        let t: Vec<f64> = rec.t.iter().map(|x| x - rec.t[0]).collect();
        let file =
            rec.source.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
        h.push_str(&line_plot(
            &format!("{jn}: position, {file}"),
            "time [s]",
            "position [deg]",
            &[
                Series::degrees(&t, &jt.q, REAL, "recorded", ""),
                Series::degrees(&t, &eb.q_sim[kb], BEFORE, "replayed before", "5 3"),
                Series::degrees(&t, &ea.q_sim[ka], AFTER, "replayed after", ""),
            ],
            false,
        ));
        // The error over time: where in the episode the fit closed the gap, and where not.
        let err = |sim: &[f64]| -> Vec<f64> {
            sim.iter().zip(&jt.q).map(|(s, q)| (s - q).to_degrees()).collect()
        };
        h.push_str(&line_plot(
            &format!("{jn}: error replayed − recorded, {file}"),
            "time [s]",
            "position error [deg]",
            &[
                Series::new(&t, err(&ea.q_sim[ka]), AFTER, "after", ""),
                Series::new(&t, err(&eb.q_sim[kb]), BEFORE, "before", "5 3"),
            ],
            false,
        ));
    }
    h.push_str("</div>");
    h
}

fn spectra(r: &FitReport, joints: &[String]) -> String {
    let mut h = String::from(
        "<h2>Power spectral density before → after (Welch, 256-sample Hann, 50 % overlap)</h2><div class=\"grid\">",
    );
    for jn in joints {
        let (Some(ib), Some(ia)) = (
            r.before.per_joint.iter().position(|j| &j.name == jn),
            r.after.per_joint.iter().position(|j| &j.name == jn),
        ) else {
            continue;
        };
        let (Some(pb), Some(pa)) = (r.before.psd.get(ib), r.after.psd.get(ia)) else { continue };
        h.push_str(&line_plot(
            &format!(
                "{jn}: spectral KL {:.3} → {:.3}",
                r.before.per_joint[ib].spectral_kl, r.after.per_joint[ia].spectral_kl
            ),
            "frequency [Hz]",
            "position PSD [rad²/Hz]",
            &[
                Series::new(&pb.freqs, pb.real.clone(), REAL, "recorded", ""),
                Series::new(&pb.freqs, pb.sim.clone(), BEFORE, "replayed before", "5 3"),
                Series::new(&pa.freqs, pa.sim.clone(), AFTER, "replayed after", ""),
            ],
            true,
        ));
    }
    h.push_str("</div>");
    h
}

fn episodes(b: &GapReport, a: &GapReport) -> String {
    let sources: Vec<String> = b.per_episode.iter().map(|e| e.source.clone()).collect();
    let (names, common) = episode_names(&sources);
    let mut h = String::from("<h2>Held-out episodes</h2>");
    if let Some(c) = &common {
        let _ = write!(h, "<p>Recordings in <code>{}</code></p>", esc(&c.display().to_string()));
    }
    h.push_str("<table><tr><th>episode</th><th>samples</th><th>MAE before → after [deg]</th><th>correlation before → after</th><th>status</th></tr>");
    for ((eb, ea), name) in b.per_episode.iter().zip(&a.per_episode).zip(&names) {
        let c = |x: Option<f64>| x.map_or("n/a".into(), |c| format!("{c:.3}"));
        let status = match (&eb.diverged, &ea.diverged) {
            (None, None) => "ok".to_string(),
            (Some(d), _) => format!("before: DIVERGED: {}", esc(d)),
            (_, Some(d)) => format!("after: DIVERGED: {}", esc(d)),
        };
        let _ = write!(
            h,
            "<tr><td class=\"l\">{}</td><td>{}</td><td>{:.3} → {:.3}</td><td>{} → {}</td><td>{status}</td></tr>",
            esc(name),
            eb.samples,
            eb.position_mae.to_degrees(),
            ea.position_mae.to_degrees(),
            c(eb.correlation_mean),
            c(ea.correlation_mean)
        );
    }
    h.push_str("</table>");
    h
}

/// The page as a string (deterministic: same input, same bytes).
pub fn html(r: &FitReport) -> String {
    let model = r.model.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
    let mut h = String::from("<!doctype html><html><head><meta charset=\"utf-8\">");
    let _ = write!(h, "<title>modellint fit: {}</title>", esc(&model));
    h.push_str(
        "<style>body{font-family:sans-serif;margin:20px;max-width:1360px}table{border-collapse:collapse;margin:6px 0}\
         td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}th{background:#eee}td.l{text-align:left}\
         .grid{display:flex;flex-wrap:wrap;gap:10px}.note{color:#555;font-size:90%}.big{font-size:120%}</style></head><body>",
    );
    let _ = write!(h, "<h1>Fit: {}</h1>", esc(&model));
    let (b, a) = (r.before.position_mae.to_degrees(), r.after.position_mae.to_degrees());
    let _ = write!(
        h,
        "<p class=\"big\">Held-out position MAE <b>{b:.3}° → {a:.3}°</b> ({}) on {} episode{} the fit did not see.</p>",
        pct(b, a),
        r.before.per_episode.len(),
        if r.before.per_episode.len() == 1 { "" } else { "s" }
    );
    h.push_str(&missing_physics(r.selected));
    h.push_str(&summary(r.before, r.after));
    h.push_str(&per_joint(r.before, r.after));
    let joints = joints_to_plot(r);
    h.push_str(&overlays(r, &joints));
    h.push_str(&spectra(r, &joints));
    h.push_str(&episodes(r.before, r.after));
    h.push_str("</body></html>\n");
    h
}

/// Writes `dir/index.html`; returns its path.
pub fn write(dir: &Path, r: &FitReport) -> std::io::Result<PathBuf> {
    std::fs::create_dir_all(dir)?;
    let path = dir.join("index.html");
    std::fs::write(&path, html(r))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn significant_digits() {
        assert_eq!(sig(0.001489), "0.001489");
        assert_eq!(sig(1.999817), "2.000");
        assert_eq!(sig(123.4), "123.4");
        assert_eq!(sig(8.73e-6), "8.730e-6");
        assert_eq!(sig_n(0.0004718, 2), "0.00047");
    }
}
