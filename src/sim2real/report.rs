//! `--report DIR`: one self-contained `index.html` with inline SVG (no scripts, no network):
//! real-vs-sim overlays of the worst 4 joints, per-joint MAE bars coloured by region, PSD
//! comparison (log scale) of the worst joints and a correlation heat map (joints × episodes).
//! When a headless chromium is installed, `index.png` is rendered from it as well (optional).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::sim2real::gap::GapReport;
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::Episode;

const REAL: &str = "#1f77b4";
const SIM: &str = "#ff7f0e";

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

fn region_colour(r: &str) -> &'static str {
    match r {
        "legs" => "#d62728",
        "arms" => "#1f77b4",
        "head" => "#2ca02c",
        "torso" => "#17becf",
        _ => "#7f7f7f",
    }
}

struct Series<'a> {
    x: &'a [f64],
    y: Vec<f64>,
    colour: &'static str,
    label: &'static str,
}

/// A line plot; `log_y` plots log10(y) (non-positive values dropped).
fn line_plot(title: &str, xlabel: &str, ylabel: &str, series: &[Series], log_y: bool) -> String {
    let (w, h, ml, mr, mt, mb) = (560.0, 260.0, 60.0, 10.0, 24.0, 36.0);
    let tr = |v: f64| if log_y { if v > 0.0 { v.log10() } else { f64::NAN } } else { v };
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for s in series {
        for (x, y) in s.x.iter().zip(&s.y) {
            let y = tr(*y);
            if x.is_finite() && y.is_finite() {
                x0 = x0.min(*x);
                x1 = x1.max(*x);
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
        }
    }
    let mut o = format!(r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="11">"#);
    let _ = write!(o, r#"<text x="{}" y="15" text-anchor="middle" font-weight="bold">{}</text>"#, w / 2.0, esc(title));
    if !(x0.is_finite() && y0.is_finite()) {
        o.push_str("<text x=\"20\" y=\"60\">no data</text></svg>");
        return o;
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if y1 <= y0 {
        y1 = y0 + 1e-9;
    }
    let pw = w - ml - mr;
    let ph = h - mt - mb;
    let px = |x: f64| ml + (x - x0) / (x1 - x0) * pw;
    let py = |y: f64| mt + ph - (y - y0) / (y1 - y0) * ph;
    let _ = write!(o, r##"<rect x="{ml}" y="{mt}" width="{pw}" height="{ph}" fill="none" stroke="#999"/>"##);
    for k in 0..=4 {
        let yv = y0 + (y1 - y0) * k as f64 / 4.0;
        let lab = if log_y { format!("1e{yv:.1}") } else { format!("{yv:.3}") };
        let _ = write!(o, r#"<text x="{}" y="{}" text-anchor="end">{lab}</text>"#, ml - 4.0, py(yv) + 4.0);
        let xv = x0 + (x1 - x0) * k as f64 / 4.0;
        let _ = write!(o, r#"<text x="{}" y="{}" text-anchor="middle">{xv:.2}</text>"#, px(xv), h - mb + 14.0);
    }
    let _ = write!(o, r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#, ml + pw / 2.0, h - 4.0, esc(xlabel));
    let _ = write!(o, r#"<text x="12" y="{}" transform="rotate(-90 12 {})" text-anchor="middle">{}</text>"#, mt + ph / 2.0, mt + ph / 2.0, esc(ylabel));
    for (si, s) in series.iter().enumerate() {
        let n = s.x.len().min(s.y.len());
        let step = (n / 1500).max(1);
        let mut d = String::new();
        let mut pen = false;
        for i in (0..n).step_by(step) {
            let y = tr(s.y[i]);
            if !(s.x[i].is_finite() && y.is_finite()) {
                pen = false;
                continue;
            }
            let _ = write!(d, "{}{:.1},{:.1} ", if pen { "L" } else { "M" }, px(s.x[i]), py(y));
            pen = true;
        }
        let _ = write!(o, r#"<path d="{d}" fill="none" stroke="{}" stroke-width="1.2"/>"#, s.colour);
        let _ = write!(o, r#"<text x="{}" y="{}" fill="{}">{}</text>"#, ml + 8.0 + 60.0 * si as f64, mt + 14.0, s.colour, s.label);
    }
    o.push_str("</svg>");
    o
}

fn bars(r: &GapReport) -> String {
    let n = r.per_joint.len().max(1);
    let (bw, ml, h, mt, mb) = (22.0, 50.0, 300.0, 24.0, 120.0);
    let w = ml + bw * n as f64 + 20.0;
    let vmax = r.per_joint.iter().map(|j| j.mae.to_degrees()).filter(|x| x.is_finite()).fold(0.0, f64::max).max(1e-9);
    let ph = h - mt - mb;
    let mut o = format!(r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="11">"#);
    let _ = write!(o, r#"<text x="{ml}" y="15" font-weight="bold">Position MAE per joint [deg] (colour = region)</text>"#);
    for (i, j) in r.per_joint.iter().enumerate() {
        let v = j.mae.to_degrees();
        let bh = if v.is_finite() { v / vmax * ph } else { 0.0 };
        let x = ml + bw * i as f64;
        let _ = write!(
            o,
            r#"<rect x="{x}" y="{}" width="{}" height="{bh}" fill="{}"><title>{} ({}): {v:.2}°</title></rect>"#,
            mt + ph - bh,
            bw - 4.0,
            region_colour(&j.region),
            esc(&j.name),
            esc(&j.region)
        );
        let _ = write!(o, r#"<text x="{}" y="{}" font-size="9" text-anchor="middle">{v:.1}</text>"#, x + bw / 2.0 - 2.0, mt + ph - bh - 2.0);
        let (tx, ty) = (x + bw / 2.0, mt + ph + 6.0);
        let _ = write!(o, r#"<text x="{tx}" y="{ty}" transform="rotate(60 {tx} {ty})" font-size="10">{}</text>"#, esc(&j.name));
    }
    let _ = write!(o, r##"<line x1="{ml}" y1="{}" x2="{}" y2="{}" stroke="#333"/>"##, mt + ph, w - 20.0, mt + ph);
    let _ = write!(o, r#"<text x="{}" y="{}" text-anchor="end">{vmax:.1}</text>"#, ml - 4.0, mt + 4.0);
    o.push_str("</svg>");
    o
}

fn heat_map(r: &GapReport) -> String {
    let joints: Vec<&str> = r.per_joint.iter().map(|j| j.name.as_str()).collect();
    let ne = r.per_episode.len().max(1);
    let cell = (600.0 / ne as f64).clamp(3.0, 24.0);
    let (ml, mt) = (170.0, 30.0);
    let w = ml + cell * ne as f64 + 20.0;
    let h = mt + 14.0 * joints.len() as f64 + 30.0;
    let mut o = format!(r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="10">"#);
    let _ = write!(o, r#"<text x="10" y="15" font-weight="bold">Correlation real vs sim (rows: joints, columns: episodes; green +1, white 0, red −1)</text>"#);
    for (ji, jn) in joints.iter().enumerate() {
        let y = mt + 14.0 * ji as f64;
        let _ = write!(o, r#"<text x="{}" y="{}" text-anchor="end">{}</text>"#, ml - 4.0, y + 10.0, esc(jn));
        for (ei, ep) in r.per_episode.iter().enumerate() {
            let c = ep.per_joint.iter().find(|j| j.name == *jn).and_then(|j| j.corr);
            let fill = match c {
                None => "#cccccc".to_string(),
                Some(c) => {
                    let c = c.clamp(-1.0, 1.0);
                    let k = (255.0 * (1.0 - c.abs())) as u8;
                    if c >= 0.0 { format!("rgb({k},{},{k})", 160 + (95.0 * (1.0 - c)) as u8) } else { format!("rgb(255,{k},{k})") }
                }
            };
            let tip = c.map_or("n/a".into(), |c| format!("{c:.3}"));
            let _ = write!(
                o,
                r#"<rect x="{}" y="{y}" width="{cell}" height="13" fill="{fill}"><title>{} / {}: {tip}</title></rect>"#,
                ml + cell * ei as f64,
                esc(jn),
                esc(&ep.source)
            );
        }
    }
    o.push_str("</svg>");
    o
}

/// Writes `dir/index.html` (and `dir/index.png` when chromium is available); returns the html path.
pub fn write(dir: &Path, r: &GapReport, recs: &[Recording], eps: &[Episode]) -> std::io::Result<PathBuf> {
    std::fs::create_dir_all(dir)?;
    let mut html = String::from(
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>modellint gap report</title>\
         <style>body{font-family:sans-serif;margin:20px;max-width:1300px}table{border-collapse:collapse}\
         td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}th{background:#eee}\
         .grid{display:flex;flex-wrap:wrap;gap:8px}</style></head><body>",
    );
    let _ = write!(html, "<h1>Sim-to-real gap</h1><pre>{}</pre>", esc(&r.to_text("gap")));
    let worst: Vec<&str> = r.localisation.joints.iter().take(4).map(|s| s.name.as_str()).collect();
    html.push_str("<h2>Real vs simulated, worst joints (episode with the largest error)</h2><div class=\"grid\">");
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
        let (Some(jt), Some(k)) = (rec.joint(jn), ep.joints.iter().position(|x| x == jn)) else { continue };
        let t: Vec<f64> = rec.t.iter().map(|x| x - rec.t[0]).collect();
        let title = format!("{jn} — {}", rec.source.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default());
        html.push_str(&line_plot(
            &title,
            "time [s]",
            "position [deg]",
            &[
                Series { x: &t, y: jt.q.iter().map(|v| v.to_degrees()).collect(), colour: REAL, label: "real" },
                Series { x: &t, y: ep.q_sim[k].iter().map(|v| v.to_degrees()).collect(), colour: SIM, label: "sim" },
            ],
            false,
        ));
    }
    html.push_str("</div><h2>Per-joint error</h2>");
    html.push_str(&bars(r));
    html.push_str("<h2>Power spectral density, worst joints (Welch, 256 Hann, 50 %)</h2><div class=\"grid\">");
    for jn in &worst {
        let Some(i) = r.per_joint.iter().position(|j| j.name == *jn) else { continue };
        let p = &r.psd[i];
        html.push_str(&line_plot(
            &format!("{jn}: KL {:.3}", r.per_joint[i].spectral_kl),
            "frequency [Hz]",
            "PSD [rad²/Hz] (log10)",
            &[
                Series { x: &p.freqs, y: p.real.clone(), colour: REAL, label: "real" },
                Series { x: &p.freqs, y: p.sim.clone(), colour: SIM, label: "sim" },
            ],
            true,
        ));
    }
    html.push_str("</div><h2>Correlation heat map</h2>");
    html.push_str(&heat_map(r));
    html.push_str("<h2>Per episode</h2><table><tr><th>episode</th><th>samples</th><th>MAE [deg]</th><th>RMSE [deg]</th><th>corr</th><th>G</th><th>status</th></tr>");
    for e in &r.per_episode {
        let _ = write!(
            html,
            "<tr><td style=\"text-align:left\">{}</td><td>{}</td><td>{:.2}</td><td>{:.2}</td><td>{}</td><td>{:.3}</td><td>{}</td></tr>",
            esc(&e.source),
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
            .args(["--headless", "--disable-gpu", "--no-sandbox", "--window-size=1300,2400"])
            .arg(format!("--screenshot={}", png.display()))
            .arg(format!("file://{}", abs.display()))
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status();
        return;
    }
}
