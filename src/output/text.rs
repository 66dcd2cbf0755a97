//! Human output through miette: what (message), why (note), what to do (help), with the
//! tightest span underlined and related places labelled.

use miette::{GraphicalReportHandler, GraphicalTheme, LabeledSpan, MietteDiagnostic, NamedSource};

use crate::finding::{Finding, ProbeStatus, Severity};
use crate::model::source::SourceMap;

pub fn render(map: &SourceMap, findings: &[Finding], color: bool) -> String {
    render_titled(map, findings, color, None)
}

/// As `render`; with `model`, the summary line names the model (several models per call).
pub fn render_titled(
    map: &SourceMap,
    findings: &[Finding],
    color: bool,
    model: Option<&str>,
) -> String {
    let theme = if color { GraphicalTheme::unicode() } else { GraphicalTheme::unicode_nocolor() };
    let handler = GraphicalReportHandler::new_themed(theme).with_width(100);
    let mut out = String::new();
    for f in findings {
        out.push_str(&render_one(map, &handler, f));
    }
    let count = |s: Severity| findings.iter().filter(|f| f.severity == s).count();
    out.push_str(&format!(
        "modellint: {}{} error(s), {} warning(s), {} info\n",
        model.map(|m| format!("{m}: ")).unwrap_or_default(),
        count(Severity::Error),
        count(Severity::Warning),
        count(Severity::Info)
    ));
    out
}

fn render_one(map: &SourceMap, handler: &GraphicalReportHandler, f: &Finding) -> String {
    let severity = match f.severity {
        Severity::Error => miette::Severity::Error,
        Severity::Warning => miette::Severity::Warning,
        Severity::Info => miette::Severity::Advice,
    };
    let mut help = String::new();
    if let Some(n) = &f.note {
        help.push_str("why: ");
        help.push_str(n);
    }
    // Labels in other files than the primary one are written as text.
    for l in &f.labels {
        if l.loc.file != f.primary.file {
            let p = super::position(map, l.loc);
            help.push_str(&format!("\nsee {}:{}:{}: {}", p.file, p.line, p.column, l.text));
        }
    }
    if let Some(p) = &f.probe {
        let verb = match p.status {
            ProbeStatus::Confirmed => "confirmed by",
            ProbeStatus::Refuted => "refuted by",
            ProbeStatus::Inconclusive => "inconclusive:",
            ProbeStatus::Skipped => "not probed:",
        };
        help.push_str(&format!("\n{verb} probe `{}` ({} steps): {}", p.name, p.steps, p.note));
    }
    if let Some(h) = &f.help {
        help.push_str("\nfix: ");
        help.push_str(h);
    }
    let mut d = MietteDiagnostic::new(f.message.clone()).with_code(f.rule).with_severity(severity);
    if !help.is_empty() {
        d = d.with_help(help.trim_start_matches('\n').to_string());
    }
    let mut s = String::new();
    if f.primary.file < map.files.len() {
        let file = map.file(f.primary.file);
        let mut labels = vec![LabeledSpan::new_primary_with_span(
            (!f.primary_label.is_empty()).then(|| f.primary_label.clone()),
            (f.primary.start, f.primary.end.saturating_sub(f.primary.start)),
        )];
        for l in &f.labels {
            if l.loc.file == f.primary.file && l.loc != f.primary {
                labels.push(LabeledSpan::new_with_span(
                    Some(l.text.clone()),
                    (l.loc.start, l.loc.end.saturating_sub(l.loc.start)),
                ));
            }
        }
        d = d.with_labels(labels);
        let report = miette::Report::new(d)
            .with_source_code(NamedSource::new(file.path.display().to_string(), file.text.clone()));
        let _ = handler.render_report(&mut s, report.as_ref());
    } else {
        let report = miette::Report::new(d);
        let _ = handler.render_report(&mut s, report.as_ref());
    }
    s.push('\n');
    s
}

/// Renders a load error (exit 2) with its snippet when known.
pub fn render_error(e: &crate::error::LoadError, color: bool) -> String {
    let theme = if color { GraphicalTheme::unicode() } else { GraphicalTheme::unicode_nocolor() };
    let handler = GraphicalReportHandler::new_themed(theme).with_width(100);
    let mut d = MietteDiagnostic::new(format!("{}: {}", e.location(), e.message))
        .with_code("modellint::input");
    let mut s = String::new();
    match &e.snippet {
        Some((text, range)) => {
            d = d.with_label(LabeledSpan::new_primary_with_span(
                Some("here".into()),
                (range.start, range.end - range.start),
            ));
            let report = miette::Report::new(d)
                .with_source_code(NamedSource::new(e.file.display().to_string(), text.clone()));
            let _ = handler.render_report(&mut s, report.as_ref());
        }
        None => {
            let _ = handler.render_report(&mut s, miette::Report::new(d).as_ref());
        }
    }
    s
}
