//! Inline-SVG charts for the HTML reports (`gap --report`, `fit --report`): line plots (linear or
//! log y), grouped bar charts and a heat map with its colour scale. No scripts, no fonts, no
//! network. Axis ticks are round numbers (1, 2, 2.5, 5 × 10^k; decades on a log axis), the axis
//! ends on a tick, and the SVG is made wide enough for its title and last tick label.

use std::fmt::Write as _;

pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// Estimated width of `s` in px at `size` px sans-serif (generous: a label is never clipped).
pub fn text_width(s: &str, size: f64) -> f64 {
    s.chars().count() as f64 * size * 0.62
}

/// Round tick values covering [lo, hi] with about `target` intervals: steps of 1, 2, 2.5 or 5 ×
/// 10^k; the first and last tick enclose the data.
pub fn nice_ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    let (lo, hi) = if hi > lo {
        (lo, hi)
    } else if lo == 0.0 {
        (-1.0, 1.0)
    } else {
        (lo - lo.abs() * 0.1, lo + lo.abs() * 0.1)
    };
    let raw = (hi - lo) / target.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw * 0.999)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).floor();
    let last = (hi / step).ceil();
    (first as i64..=last as i64)
        .map(|k| k as f64 * step)
        .map(|v| if v.abs() < step * 1e-9 { 0.0 } else { v })
        .collect()
}

/// Labels for linear ticks: as many decimals as the step needs, no more.
pub fn tick_labels(ticks: &[f64]) -> Vec<String> {
    let step = if ticks.len() > 1 { (ticks[1] - ticks[0]).abs() } else { 1.0 };
    let mut dec = (-step.log10().floor()).max(0.0) as usize;
    // 2.5 × 10^k needs one more decimal.
    if ((step / 10f64.powi(-(dec as i32))) - (step / 10f64.powi(-(dec as i32))).round()).abs()
        > 1e-6
    {
        dec += 1;
    }
    let big = ticks.iter().any(|t| t.abs() >= 1e5);
    ticks.iter().map(|t| if big { format!("{t:.0e}") } else { format!("{t:.dec$}") }).collect()
}

/// Decade ticks (log10 values) covering [lo, hi] (log10 of the data).
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let a = lo.floor() as i64;
    let mut b = hi.ceil() as i64;
    if b <= a {
        b = a + 1;
    }
    let n = (b - a) as usize;
    let step = n.div_ceil(6).max(1) as i64;
    let a = a - a.rem_euclid(step);
    let mut t: Vec<f64> =
        (0..).map(|k| a + k * step).take_while(|v| *v < b + step).map(|v| v as f64).collect();
    while t.len() > 1 && t[t.len() - 2] >= hi {
        t.pop();
    }
    t
}

/// `10^k` as SVG text (superscript exponent).
fn decade_label(k: f64) -> String {
    format!("10<tspan dy=\"-5\" font-size=\"8\">{}</tspan>", k as i64)
}

pub struct Series<'a> {
    pub x: &'a [f64],
    pub y: Vec<f64>,
    pub colour: &'static str,
    pub label: String,
    /// SVG stroke-dasharray ("" = solid).
    pub dash: &'static str,
}

/// The opening `<svg>` tag of a `w` × `h` figure (text at `font_size`) and its centred bold
/// title.
fn svg_open(w: f64, h: f64, font_size: f64, title: &str) -> String {
    let mut o = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{h:.0}" font-family="sans-serif" font-size="{font_size}">"#
    );
    let _ = write!(
        o,
        r#"<text x="{:.1}" y="16" text-anchor="middle" font-weight="bold" font-size="12">{}</text>"#,
        w / 2.0,
        esc(title)
    );
    o
}

impl<'a> Series<'a> {
    pub fn new(
        x: &'a [f64],
        y: Vec<f64>,
        colour: &'static str,
        label: &str,
        dash: &'static str,
    ) -> Series<'a> {
        Series { x, y, colour, label: label.into(), dash }
    }
    /// Angles `q` [rad] plotted in degrees.
    pub fn degrees(
        x: &'a [f64],
        q: &[f64],
        colour: &'static str,
        label: &str,
        dash: &'static str,
    ) -> Series<'a> {
        Series::new(x, q.iter().map(|v| v.to_degrees()).collect(), colour, label, dash)
    }
}

/// Line plot with round ticks, grid, legend under the title; `log_y` plots log10(y). The
/// first series is drawn last, on top of the others (the measured trace, which a fitted
/// simulation's line would otherwise hide where they agree); the legend keeps the given order.
pub fn line_plot(
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[Series],
    log_y: bool,
) -> String {
    let (mut w, h, ml, mr, mt, mb) = (600.0, 290.0, 64.0, 28.0, 44.0, 40.0);
    w = f64::max(w, text_width(title, 12.0) + 20.0);
    let tr = |v: f64| if log_y { if v > 0.0 { v.log10() } else { f64::NAN } } else { v };
    let (mut x0, mut x1, mut y0, mut y1) =
        (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
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
    let mut o = svg_open(w, h, 11.0, title);
    if !(x0.is_finite() && y0.is_finite()) {
        o.push_str("<text x=\"20\" y=\"70\">no data</text></svg>");
        return o;
    }
    let xt = nice_ticks(x0, x1, 6);
    let yt = if log_y { log_ticks(y0, y1) } else { nice_ticks(y0, y1, 5) };
    let (x0, x1) = (xt[0], xt[xt.len() - 1]);
    let (y0, y1) = (yt[0], yt[yt.len() - 1]);
    let pw = w - ml - mr;
    let ph = h - mt - mb;
    let px = |x: f64| ml + (x - x0) / (x1 - x0) * pw;
    let py = |y: f64| mt + ph - (y - y0) / (y1 - y0) * ph;
    let ylabels: Vec<String> =
        if log_y { yt.iter().map(|k| decade_label(*k)).collect() } else { tick_labels(&yt) };
    for (v, lab) in yt.iter().zip(&ylabels) {
        let y = py(*v);
        let _ = write!(
            o,
            r##"<line x1="{ml}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#e4e4e4"/>"##,
            ml + pw
        );
        let _ = write!(
            o,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="end">{lab}</text>"#,
            ml - 5.0,
            y + 4.0
        );
    }
    for (v, lab) in xt.iter().zip(tick_labels(&xt)) {
        let x = px(*v);
        let _ = write!(
            o,
            r##"<line x1="{x:.1}" y1="{mt}" x2="{x:.1}" y2="{:.1}" stroke="#e4e4e4"/>"##,
            mt + ph
        );
        let _ = write!(
            o,
            r#"<text x="{x:.1}" y="{:.1}" text-anchor="middle">{lab}</text>"#,
            mt + ph + 15.0
        );
    }
    let _ = write!(
        o,
        r##"<rect x="{ml}" y="{mt}" width="{pw:.1}" height="{ph:.1}" fill="none" stroke="#888"/>"##
    );
    let _ = write!(
        o,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
        ml + pw / 2.0,
        h - 6.0,
        esc(xlabel)
    );
    let _ = write!(
        o,
        r#"<text x="13" y="{:.1}" transform="rotate(-90 13 {:.1})" text-anchor="middle">{}</text>"#,
        mt + ph / 2.0,
        mt + ph / 2.0,
        esc(ylabel)
    );
    let dash_of = |s: &Series| {
        if s.dash.is_empty() { String::new() } else { format!(r#" stroke-dasharray="{}""#, s.dash) }
    };
    for s in series.iter().rev() {
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
        let _ = write!(
            o,
            r#"<path d="{d}" fill="none" stroke="{}" stroke-width="1.3"{}/>"#,
            s.colour,
            dash_of(s)
        );
    }
    // Legend between the title and the plot.
    let mut lx = ml;
    for s in series {
        let _ = write!(
            o,
            r#"<line x1="{lx:.1}" y1="31" x2="{:.1}" y2="31" stroke="{}" stroke-width="2"{}/>"#,
            lx + 18.0,
            s.colour,
            dash_of(s)
        );
        let _ = write!(o, r#"<text x="{:.1}" y="35">{}</text>"#, lx + 22.0, esc(&s.label));
        lx += 32.0 + text_width(&s.label, 11.0);
    }
    o.push_str("</svg>");
    o
}

pub struct BarGroup {
    pub label: String,
    pub values: Vec<f64>,
    pub tip: String,
    /// Colour per value; empty: the legend's colours in order.
    pub colours: Vec<&'static str>,
}

/// Grouped vertical bars (value i in the colour of `legend[i]` unless the group sets colours),
/// y axis from 0 with round ticks.
pub fn bar_chart(
    title: &str,
    ylabel: &str,
    legend: &[(&str, &str)],
    groups: &[BarGroup],
) -> String {
    let k = groups.iter().map(|g| g.values.len()).max().unwrap_or(1).max(1) as f64;
    let bw = if k > 1.0 { 11.0 } else { 16.0 };
    let gw = bw * k + 8.0;
    let label_h =
        groups.iter().map(|g| text_width(&g.label, 10.0)).fold(0.0, f64::max) * 0.87 + 12.0;
    let (ml, mr, mt) = (64.0, 24.0, 44.0);
    let mb = label_h.max(30.0);
    let ph = 200.0;
    let h = mt + ph + mb;
    let legend_w: f64 = legend.iter().map(|(l, _)| 32.0 + text_width(l, 11.0)).sum();
    let w = (ml + gw * groups.len() as f64 + mr + label_h * 0.5)
        .max(text_width(title, 12.0) + 20.0)
        .max(ml + legend_w + mr);
    let vmax = groups
        .iter()
        .flat_map(|g| g.values.iter())
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let yt = nice_ticks(0.0, if vmax > 0.0 { vmax } else { 1.0 }, 4);
    let top = yt[yt.len() - 1];
    let py = |v: f64| mt + ph - v / top * ph;
    let mut o = svg_open(w, h, 11.0, title);
    let mut lx = ml;
    for (l, c) in legend {
        let _ = write!(
            o,
            r#"<rect x="{lx:.1}" y="25" width="14" height="10" fill="{c}"/><text x="{:.1}" y="35">{}</text>"#,
            lx + 18.0,
            esc(l)
        );
        lx += 32.0 + text_width(l, 11.0);
    }
    for (v, lab) in yt.iter().zip(tick_labels(&yt)) {
        let y = py(*v);
        let _ = write!(
            o,
            r##"<line x1="{ml}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#e4e4e4"/>"##,
            ml + gw * groups.len() as f64
        );
        let _ = write!(
            o,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="end">{lab}</text>"#,
            ml - 5.0,
            y + 4.0
        );
    }
    let _ = write!(
        o,
        r#"<text x="13" y="{:.1}" transform="rotate(-90 13 {:.1})" text-anchor="middle">{}</text>"#,
        mt + ph / 2.0,
        mt + ph / 2.0,
        esc(ylabel)
    );
    for (gi, g) in groups.iter().enumerate() {
        let x = ml + gw * gi as f64 + 4.0;
        for (i, v) in g.values.iter().enumerate() {
            let c = g
                .colours
                .get(i)
                .copied()
                .or_else(|| legend.get(i).map(|l| l.1))
                .unwrap_or("#7f7f7f");
            let bh = if v.is_finite() { (v / top * ph).max(0.0) } else { 0.0 };
            let _ = write!(
                o,
                r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{bh:.1}" fill="{c}"><title>{}</title></rect>"#,
                x + bw * i as f64,
                mt + ph - bh,
                bw - 1.0,
                esc(&g.tip)
            );
        }
        let (tx, ty) = (x + gw / 2.0 - 4.0, mt + ph + 8.0);
        let _ = write!(
            o,
            r#"<text x="{tx:.1}" y="{ty:.1}" transform="rotate(60 {tx:.1} {ty:.1})" font-size="10">{}</text>"#,
            esc(&g.label)
        );
    }
    let _ = write!(
        o,
        r##"<line x1="{ml}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#333"/>"##,
        mt + ph,
        ml + gw * groups.len() as f64,
        mt + ph
    );
    let _ =
        write!(o, r##"<line x1="{ml}" y1="{mt}" x2="{ml}" y2="{:.1}" stroke="#333"/>"##, mt + ph);
    o.push_str("</svg>");
    o
}

/// Diverging colour for a correlation in [-1, 1]: red −1, white 0, green +1.
pub fn corr_colour(c: f64) -> String {
    let c = c.clamp(-1.0, 1.0);
    let k = (255.0 * (1.0 - c.abs())).round() as u8;
    if c >= 0.0 {
        format!("rgb({k},{},{k})", 160 + (95.0 * (1.0 - c)).round() as u8)
    } else {
        format!("rgb(255,{k},{k})")
    }
}

/// Heat map: `rows` × `cols` cells (None = grey), with a colour scale from −1 to +1 beside it.
/// Column labels are 1-based indices; `col_tips` name them in the tooltip.
pub fn heat_map(
    title: &str,
    rows: &[String],
    col_tips: &[String],
    cell: &dyn Fn(usize, usize) -> Option<f64>,
) -> String {
    let nc = col_tips.len().max(1);
    let cw = (600.0 / nc as f64).clamp(4.0, 26.0);
    let ch = 15.0;
    let ml = rows.iter().map(|r| text_width(r, 10.0)).fold(40.0, f64::max) + 10.0;
    let mt = 50.0;
    let grid_w = cw * nc as f64;
    let scale_x = ml + grid_w + 24.0;
    let w = (scale_x + 60.0).max(text_width(title, 12.0) + 20.0);
    let gh = ch * rows.len() as f64;
    let h = mt + gh.max(130.0) + 30.0;
    let mut o = svg_open(w, h, 10.0, title);
    let _ = write!(
        o,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">episode</text>"#,
        ml + grid_w / 2.0,
        mt - 22.0
    );
    let every = (nc as f64 * 12.0 / grid_w).ceil().max(1.0) as usize;
    for c in (0..nc).filter(|c| c % every == 0 || *c == nc - 1) {
        let _ = write!(
            o,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            ml + cw * (c as f64 + 0.5),
            mt - 6.0,
            c + 1
        );
    }
    for (ri, r) in rows.iter().enumerate() {
        let y = mt + ch * ri as f64;
        let _ = write!(
            o,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"#,
            ml - 5.0,
            y + 11.0,
            esc(r)
        );
        for (ci, tip) in col_tips.iter().enumerate() {
            let v = cell(ri, ci);
            let fill = v.map_or("#cccccc".to_string(), corr_colour);
            let t = v.map_or("n/a".into(), |v| format!("{v:.3}"));
            let _ = write!(
                o,
                r#"<rect x="{:.1}" y="{y:.1}" width="{:.1}" height="{:.1}" fill="{fill}"><title>{} / {}: {t}</title></rect>"#,
                ml + cw * ci as f64,
                cw - 0.5,
                ch - 1.0,
                esc(r),
                esc(tip)
            );
        }
    }
    // Colour scale: −1 at the bottom, +1 at the top, 0 in the middle.
    let sh = 120.0;
    let steps = 40;
    for i in 0..steps {
        let v = 1.0 - 2.0 * (i as f64 + 0.5) / steps as f64;
        let _ = write!(
            o,
            r#"<rect x="{scale_x:.1}" y="{:.1}" width="14" height="{:.2}" fill="{}"/>"#,
            mt + sh * i as f64 / steps as f64,
            sh / steps as f64 + 0.3,
            corr_colour(v)
        );
    }
    let _ = write!(
        o,
        r##"<rect x="{scale_x:.1}" y="{mt}" width="14" height="{sh}" fill="none" stroke="#888"/>"##
    );
    for (v, lab) in [(1.0, "+1"), (0.5, "0.5"), (0.0, "0"), (-0.5, "−0.5"), (-1.0, "−1")] {
        let y = mt + sh * (1.0 - v) / 2.0;
        let _ = write!(
            o,
            r##"<line x1="{:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#333"/><text x="{:.1}" y="{:.1}">{lab}</text>"##,
            scale_x + 14.0,
            scale_x + 18.0,
            scale_x + 20.0,
            y + 4.0
        );
    }
    let _ = write!(
        o,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">corr</text>"#,
        scale_x + 7.0,
        mt - 6.0
    );
    let _ = write!(
        o,
        r##"<rect x="{:.1}" y="{:.1}" width="14" height="10" fill="#cccccc"/><text x="{:.1}" y="{:.1}">n/a</text>"##,
        scale_x,
        mt + sh + 10.0,
        scale_x + 18.0,
        mt + sh + 19.0
    );
    o.push_str("</svg>");
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_enclose_the_data() {
        assert_eq!(nice_ticks(0.0, 5.449, 5), vec![0.0, 2.0, 4.0, 6.0]);
        assert_eq!(
            tick_labels(&nice_ticks(-0.013, 0.021, 4)),
            vec!["-0.02", "-0.01", "0.00", "0.01", "0.02", "0.03"]
        );
        let t = nice_ticks(0.0, 9.0, 4);
        assert_eq!(t, vec![0.0, 2.5, 5.0, 7.5, 10.0]);
        assert_eq!(tick_labels(&t), vec!["0.0", "2.5", "5.0", "7.5", "10.0"]);
        assert_eq!(tick_labels(&[0.0, 0.01, 0.02]), vec!["0.00", "0.01", "0.02"]);
        assert_eq!(tick_labels(&[0.0, 20.0, 40.0]), vec!["0", "20", "40"]);
        // A constant series still gets an axis.
        assert!(nice_ticks(3.0, 3.0, 4).len() >= 2);
    }

    #[test]
    fn log_ticks_are_whole_decades_enclosing_the_data() {
        assert_eq!(log_ticks(-1.4, 0.3), vec![-2.0, -1.0, 0.0, 1.0]);
        assert_eq!(log_ticks(-9.2, -2.1), vec![-10.0, -8.0, -6.0, -4.0, -2.0]);
        let t = log_ticks(-14.5, -1.2);
        assert!(
            t.first().unwrap() <= &-14.5 && t.last().unwrap() >= &-1.2 && t.len() <= 9,
            "{t:?}"
        );
        assert!(t.iter().all(|v| v.fract() == 0.0));
    }

    /// The first series (the real trace) is drawn last, over the others; the legend keeps the
    /// given order.
    #[test]
    fn the_first_series_is_drawn_on_top() {
        let x = [0.0, 1.0, 2.0];
        let svg = line_plot(
            "t",
            "x",
            "y",
            &[
                Series::new(&x, vec![0.0, 1.0, 0.0], "#111111", "real", ""),
                Series::new(&x, vec![0.0, 1.0, 0.1], "#222222", "sim", ""),
            ],
            false,
        );
        let path = |c: &str| svg.find(&format!(r#"fill="none" stroke="{c}""#)).unwrap();
        assert!(path("#111111") > path("#222222"), "{svg}");
        assert!(svg.find(">real<").unwrap() < svg.find(">sim<").unwrap(), "{svg}");
    }

    #[test]
    fn titles_fit_in_the_svg() {
        let title = "Position MAE per joint, held-out episodes: before → after the fit [deg]";
        let svg = bar_chart(
            title,
            "MAE [deg]",
            &[("before", "#999"), ("after", "#2ca02c")],
            &[BarGroup {
                label: "a".into(),
                values: vec![1.0, 0.5],
                tip: String::new(),
                colours: vec![],
            }],
        );
        let w: f64 =
            svg.split("width=\"").nth(1).unwrap().split('"').next().unwrap().parse().unwrap();
        assert!(
            w >= text_width(title, 12.0),
            "svg width {w} for a title of {} px",
            text_width(title, 12.0)
        );
    }
}
