//! `gap --report DIR`: one self-contained `index.html` with inline SVG (no scripts, no network;
//! charts in `svg.rs`): recorded-vs-replayed position overlays (legend and axis units say which
//! trace is which: a hinge in degrees, a slide joint in millimetres) of the worst 4 joints, per-joint MAE bars coloured by
//! region (two joints or more), PSD comparison (log scale) of the worst joints, a correlation heat
//! map (joints × episodes) with its colour scale, and the episodes by path relative to their
//! common directory.
//! When a headless chromium is installed, `index.png` is rendered from it as well (optional).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::sim2real::gap::GapReport;
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::Episode;
use crate::sim2real::svg::{self, Series, esc, line_plot};

const REAL: &str = "#1f77b4";
const SIM: &str = "#ff7f0e";

fn region_colour(r: &str) -> &'static str {
    match r {
        "legs" => "#d62728",
        "arms" => "#1f77b4",
        "head" => "#2ca02c",
        "torso" => "#17becf",
        _ => "#7f7f7f",
    }
}

/// Display names of the episodes: paths relative to their common directory (returned too).
pub fn episode_names(sources: &[String]) -> (Vec<String>, Option<PathBuf>) {
    let paths: Vec<&Path> = sources.iter().map(Path::new).collect();
    let mut common: Option<PathBuf> = paths.first().and_then(|p| p.parent()).map(Path::to_path_buf);
    for p in &paths {
        while let Some(c) = &common {
            if p.starts_with(c) {
                break;
            }
            common = c.parent().map(Path::to_path_buf);
        }
    }
    let common = common.filter(|c| !c.as_os_str().is_empty());
    let names = paths
        .iter()
        .map(|p| {
            common
                .as_ref()
                .and_then(|c| p.strip_prefix(c).ok())
                .unwrap_or(p)
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    (names, common)
}

/// Per-joint MAE bars coloured by region (≥ 2 joints; one joint is a sentence, not a chart).
fn bars(r: &GapReport) -> String {
    if r.per_joint.len() < 2 {
        return r.per_joint.first().map_or(String::new(), |j| {
            format!("<p>{}: position MAE {:.2}°</p>", esc(&j.name), j.mae.to_degrees())
        });
    }
    let mut regions: Vec<&str> = r.per_joint.iter().map(|j| j.region.as_str()).collect();
    regions.sort_unstable();
    regions.dedup();
    let legend: Vec<(&str, &str)> = regions.iter().map(|g| (*g, region_colour(g))).collect();
    let groups: Vec<svg::BarGroup> = r
        .per_joint
        .iter()
        .map(|j| svg::BarGroup {
            label: j.name.clone(),
            values: vec![j.mae.to_degrees()],
            tip: format!("{} ({}): {:.2}°", j.name, j.region, j.mae.to_degrees()),
            colours: vec![region_colour(&j.region)],
        })
        .collect();
    svg::bar_chart("Position MAE per joint [deg] (colour = region)", "MAE [deg]", &legend, &groups)
}

fn heat_map(r: &GapReport, names: &[String]) -> String {
    let joints: Vec<String> = r.per_joint.iter().map(|j| j.name.clone()).collect();
    if joints.len() * r.per_episode.len() < 2 {
        return String::new();
    }
    let cell = |ji: usize, ei: usize| {
        r.per_episode[ei].per_joint.iter().find(|j| j.name == joints[ji]).and_then(|j| j.corr)
    };
    format!(
        "<h2>Correlation heat map</h2>{}",
        svg::heat_map(
            "Position correlation, recorded vs replayed (rows: joints, columns: episodes)",
            &joints,
            names,
            &cell
        )
    )
}

/// Writes `dir/index.html` (and `dir/index.png` when chromium is available); returns the html path.
pub fn write(
    dir: &Path,
    r: &GapReport,
    recs: &[Recording],
    eps: &[Episode],
    slides: &[String],
) -> std::io::Result<PathBuf> {
    std::fs::create_dir_all(dir)?;
    let mut html = String::from(
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>modellint gap report</title>\
         <style>body{font-family:sans-serif;margin:20px;max-width:1360px}table{border-collapse:collapse}\
         td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}th{background:#eee}\
         .grid{display:flex;flex-wrap:wrap;gap:8px}</style></head><body>",
    );
    let _ = write!(html, "<h1>Sim-to-real gap</h1><pre>{}</pre>", esc(&r.to_text("gap")));
    let worst: Vec<&str> = r.localisation.joints.iter().take(4).map(|s| s.name.as_str()).collect();
    html.push_str(
        "<h2>Recorded vs replayed, worst joints (episode with the largest error)</h2><p>recorded: \
         the joint position in the recording; replayed: MuJoCo's simulation of the model driven by \
         the recorded commands from the recorded start state. Angles in degrees (a slide joint's \
         positions in mm).</p><div class=\"grid\">",
    );
    for jn in &worst {
        let best = r
            .per_episode
            .iter()
            .enumerate()
            .filter(|(_, e)| e.diverged.is_none())
            .filter_map(|(i, e)| e.per_joint.iter().find(|j| j.name == *jn).map(|j| (i, j.rmse)))
            .filter(|(_, x)| x.is_finite())
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((ei, _)) = best else { continue };
        let (rec, ep) = (&recs[ei], &eps[ei]);
        let (Some(jt), Some(k)) = (rec.joint(jn), ep.joints.iter().position(|x| x == jn)) else {
            continue;
        };
        let t: Vec<f64> = rec.t.iter().map(|x| x - rec.t[0]).collect();
        // A hinge in degrees, a slide joint in millimetres.
        let (unit, factor) = if slides.iter().any(|s| s == jn) {
            ("mm", 1000.0)
        } else {
            ("deg", 180.0 / std::f64::consts::PI)
        };
        let scaled = |v: &[f64]| -> Vec<f64> { v.iter().map(|x| x * factor).collect() };
        let title = format!(
            "{jn}: position, {}",
            rec.source.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default()
        );
        html.push_str(&line_plot(
            &title,
            "time [s]",
            &format!("position [{unit}]"),
            &[
                Series::new(&t, scaled(&jt.q), REAL, "recorded", ""),
                Series::new(&t, scaled(&ep.q_sim[k]), SIM, "replayed (MuJoCo)", ""),
            ],
            false,
        ));
        let err: Vec<f64> = ep.q_sim[k].iter().zip(&jt.q).map(|(s, q)| (s - q) * factor).collect();
        html.push_str(&line_plot(
            &format!("{jn}: position error, replayed − recorded"),
            "time [s]",
            &format!("error [{unit}]"),
            &[Series::new(&t, err, SIM, "replayed − recorded", "")],
            false,
        ));
    }
    html.push_str("</div><h2>Per-joint error</h2>");
    html.push_str(&bars(r));
    html.push_str(
        "<h2>Power spectral density, worst joints (Welch, 4 s Hann, 50 %)</h2><div class=\"grid\">",
    );
    for jn in &worst {
        let Some(i) = r.per_joint.iter().position(|j| j.name == *jn) else { continue };
        let p = &r.psd[i];
        html.push_str(&line_plot(
            &format!("{jn}: position spectrum, KL {:.3}", r.per_joint[i].spectral_kl),
            "frequency [Hz]",
            "position PSD [rad²/Hz]",
            &[
                Series::new(&p.freqs, p.real.clone(), REAL, "recorded", ""),
                Series::new(&p.freqs, p.sim.clone(), SIM, "replayed (MuJoCo)", ""),
            ],
            true,
        ));
    }
    let sources: Vec<String> = r.per_episode.iter().map(|e| e.source.clone()).collect();
    let (names, common) = episode_names(&sources);
    html.push_str("</div>");
    html.push_str(&heat_map(r, &names));
    html.push_str("<h2>Per episode</h2>");
    if let Some(c) = &common {
        let _ = write!(html, "<p>Recordings in <code>{}</code></p>", esc(&c.display().to_string()));
    }
    html.push_str("<table><tr><th>episode</th><th>samples</th><th>MAE [deg]</th><th>RMSE [deg]</th><th>corr</th><th>G</th><th>status</th></tr>");
    for (e, name) in r.per_episode.iter().zip(&names) {
        let _ = write!(
            html,
            "<tr><td style=\"text-align:left\">{}</td><td>{}</td><td>{:.2}</td><td>{:.2}</td><td>{}</td><td>{:.3}</td><td>{}</td></tr>",
            esc(name),
            e.samples,
            e.position_mae.to_degrees(),
            e.position_rmse.to_degrees(),
            e.correlation_mean.map_or("n/a".into(), |c| format!("{c:.3}")),
            e.gap_overall,
            e.diverged.as_deref().map_or("ok".into(), |d| format!("DIVERGED: {}", esc(d)))
        );
    }
    html.push_str("</table></body></html>\n");
    let path = dir.join("index.html");
    std::fs::write(&path, html)?;
    screenshot(&path, &dir.join("index.png"));
    Ok(path)
}

/// Renders a PNG with headless chromium when one is on PATH; silently skipped otherwise.
fn screenshot(html: &Path, png: &Path) {
    for exe in ["chromium", "chromium-browser", "google-chrome"] {
        let found = std::env::var_os("PATH")
            .is_some_and(|p| std::env::split_paths(&p).any(|d| d.join(exe).is_file()));
        if !found {
            continue;
        }
        let Ok(abs) = std::fs::canonicalize(html) else { return };
        let _ = std::process::Command::new(exe)
            .args(["--headless", "--disable-gpu", "--no-sandbox", "--window-size=1400,2400"])
            .arg(format!("--screenshot={}", png.display()))
            .arg(format!("file://{}", abs.display()))
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status();
        return;
    }
}
