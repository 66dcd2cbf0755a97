//! Human output through miette: what (message), why (note), what to do (help), with the
//! tightest span underlined and related places labelled.

use miette::{
    GraphicalReportHandler, GraphicalTheme, LabeledSpan, MietteDiagnostic, MietteError,
    MietteSpanContents, NamedSource, SourceCode, SourceSpan, SpanContents,
};

use crate::finding::{Finding, ProbeStatus, Severity};
use crate::model::source::SourceMap;

pub fn render(map: &SourceMap, findings: &[Finding], color: bool) -> String {
    render_titled(map, findings, color, None)
}

/// How many findings of one rule on one model the text output shows in full; the others are
/// grouped one line each after them.
pub const GROUP_FULL: usize = 3;

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
    // Repeated findings of one rule: the first GROUP_FULL in full, the rest one line each in a
    // group at the end, so that a model with many of one problem stays readable.
    let mut shown: std::collections::BTreeMap<&str, usize> = std::collections::BTreeMap::new();
    let mut rest: std::collections::BTreeMap<&str, Vec<&Finding>> =
        std::collections::BTreeMap::new();
    for f in findings {
        let n = shown.entry(f.rule).or_insert(0);
        if *n < GROUP_FULL {
            *n += 1;
            out.push_str(&render_one(map, &handler, f));
        } else {
            rest.entry(f.rule).or_default().push(f);
        }
    }
    for (rule, fs) in &rest {
        out.push_str(&format!(
            "{rule}: {} more finding(s) of this rule ({GROUP_FULL} shown in full above)\n",
            fs.len()
        ));
        for f in fs {
            let p = super::position(map, f.primary);
            let probe = match &f.probe {
                Some(o) => format!(" [{} by probe `{}`]", status_word(o.status), o.name),
                None => String::new(),
            };
            out.push_str(&format!(
                "  {}:{}:{}: {} {}{probe}\n",
                p.file,
                p.line,
                p.column,
                f.severity.as_str(),
                f.message.replace('\n', " ")
            ));
        }
        out.push('\n');
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

fn status_word(s: ProbeStatus) -> &'static str {
    match s {
        ProbeStatus::Confirmed => "confirmed",
        ProbeStatus::Measured => "measured",
        ProbeStatus::Refuted => "refuted",
        ProbeStatus::Inconclusive => "inconclusive",
        ProbeStatus::Skipped => "not run",
    }
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
            ProbeStatus::Measured => "measured by",
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
            first_line(&file.text, f.primary.start, f.primary.end),
        )];
        for l in &f.labels {
            if l.loc.file == f.primary.file && l.loc != f.primary {
                labels.push(LabeledSpan::new_with_span(
                    Some(l.text.clone()),
                    first_line(&file.text, l.loc.start, l.loc.end),
                ));
            }
        }
        d = d.with_labels(labels);
        let report = miette::Report::new(d).with_source_code(NamedSource::new(
            file.path.display().to_string(),
            OneSnippet(file.text.clone()),
        ));
        let _ = handler.render_report(&mut s, report.as_ref());
        s = elide_unlabelled(&s);
    } else {
        let report = miette::Report::new(d);
        let _ = handler.render_report(&mut s, report.as_ref());
    }
    s.push('\n');
    s
}

/// The part of `start..end` on its first line, as miette's (offset, length): a span over several
/// lines (a whole `<body>` or `<default>` block) is shown by its opening line only. Text output
/// only: JSON/SARIF keep the exact location.
fn first_line(text: &str, start: usize, end: usize) -> (usize, usize) {
    let start = start.min(text.len());
    let end = end.clamp(start, text.len());
    let len = text.as_bytes()[start..end].iter().position(|&b| b == b'\n').unwrap_or(end - start);
    (start, len)
}

/// The file's text as miette's source, such that all labels of a finding in one file share one
/// snippet, whose header is the finding's own location (miette heads a snippet with its primary
/// label): miette merges two labels' contexts when `line + line_count` of the first reaches the
/// second, so every context claims to run to the end of the file. [`elide_unlabelled`] then
/// removes the lines between distant labels.
struct OneSnippet(String);

impl SourceCode for OneSnippet {
    fn read_span<'a>(
        &'a self,
        span: &SourceSpan,
        before: usize,
        after: usize,
    ) -> Result<Box<dyn SpanContents<'a> + 'a>, MietteError> {
        let c = self.0.read_span(span, before, after)?;
        let to_the_end = self.0.len().saturating_add(1);
        Ok(Box::new(MietteSpanContents::new(c.data(), *c.span(), c.line(), c.column(), to_the_end)))
    }
}

/// Source lines kept around each labelled line (miette's own context).
const CONTEXT: usize = 1;
/// Runs of at most this many unlabelled lines are shown; longer ones become one `⋮` row.
const MAX_SHOWN_GAP: usize = 2;

/// One row of a rendered miette snippet, classified on its text without colour codes.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Row {
    /// `╭─[file:line:col]`, with the line.
    Header(Option<usize>),
    /// ` 12 │ source text`, with the line number and the width of the number column.
    Source(usize, usize),
    /// `    · ──┬──` under a source line.
    Label,
    Other,
}

fn strip_ansi(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut chars = s.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' && chars.peek() == Some(&'[') {
            for c in chars.by_ref() {
                if c.is_ascii_alphabetic() {
                    break;
                }
            }
        } else {
            out.push(c);
        }
    }
    out
}

fn classify(raw: &str) -> Row {
    let t = strip_ansi(raw);
    let trimmed = t.trim_start();
    if let Some(rest) = trimmed.strip_prefix("╭─[") {
        // `[path:line:col]`: the line is the second number from the end.
        let inner = rest.trim_end().trim_end_matches(']');
        let mut parts = inner.rsplitn(3, ':');
        let _col = parts.next();
        return Row::Header(parts.next().and_then(|l| l.parse().ok()));
    }
    if trimmed.starts_with('·') {
        return Row::Label;
    }
    let digits = trimmed.chars().take_while(char::is_ascii_digit).count();
    if digits > 0
        && trimmed[digits..].starts_with(" │")
        && let Ok(n) = trimmed[..digits].parse()
    {
        return Row::Source(n, t.len() - trimmed.len() + digits);
    }
    Row::Other
}

/// Trims a rendered snippet to the relevant lines: miette shows every line between the first
/// and the last label of a file (a whole `<body>` tree between a joint and its mirror, a whole
/// `<default>` block). Kept: each labelled line and the header's line with `CONTEXT` lines
/// around them; a longer run of other lines becomes one `⋮` row. Text output only.
fn elide_unlabelled(rendered: &str) -> String {
    let lines: Vec<&str> = rendered.split('\n').collect();
    let rows: Vec<Row> = lines.iter().map(|l| classify(l)).collect();
    let mut anchors = std::collections::BTreeSet::new();
    for (i, r) in rows.iter().enumerate() {
        match r {
            Row::Header(Some(n)) => {
                anchors.insert(*n);
            }
            Row::Source(n, _) if rows.get(i + 1) == Some(&Row::Label) => {
                anchors.insert(*n);
            }
            _ => {}
        }
    }
    let near = |n: usize| anchors.range(n.saturating_sub(CONTEXT)..=n + CONTEXT).next().is_some();
    let mut out: Vec<String> = Vec::with_capacity(lines.len());
    let mut i = 0;
    while i < lines.len() {
        if let Row::Source(n, width) = rows[i]
            && !near(n)
        {
            // A run of unlabelled source lines (label rows always follow a kept line).
            let mut j = i;
            while let Some(Row::Source(m, _)) = rows.get(j)
                && !near(*m)
            {
                j += 1;
            }
            if j - i > MAX_SHOWN_GAP {
                out.push(format!("{:>width$} │", "⋮"));
            } else {
                out.extend(lines[i..j].iter().map(|l| l.to_string()));
            }
            i = j;
            continue;
        }
        out.push(lines[i].to_string());
        i += 1;
    }
    out.join("\n")
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::source::Loc;

    /// A 60-line file: `<body name="a">` on line 5 holding lines 6..=30, `<joint name="b"/>` on
    /// line 50.
    fn long_file() -> (SourceMap, Loc, Loc) {
        let mut text = String::new();
        for i in 1..=60 {
            let line = match i {
                5 => "  <body name=\"a\">".to_string(),
                31 => "  </body>".to_string(),
                50 => "  <joint name=\"b\"/>".to_string(),
                _ => format!("    <geom name=\"g{i}\"/>"),
            };
            text.push_str(&line);
            text.push('\n');
        }
        let start = |needle: &str| text.find(needle).unwrap();
        let body = Loc { file: 0, start: start("<body"), end: start("</body>") + "</body>".len() };
        let joint = Loc { file: 0, start: start("<joint") + 1, end: start("<joint") + 6 };
        let mut map = SourceMap::default();
        map.add("m.xml".into(), text);
        (map, body, joint)
    }

    fn numbered_lines(out: &str) -> Vec<usize> {
        out.lines()
            .filter_map(|l| match classify(l) {
                Row::Source(n, _) => Some(n),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn a_long_span_and_distant_labels_show_only_their_lines() {
        let (map, body, joint) = long_file();
        let f = Finding::new("mirror-asymmetry", Severity::Warning, "joint b", joint)
            .label("here")
            .secondary(body, "the whole body");
        for color in [false, true] {
            let out = render(&map, std::slice::from_ref(&f), color);
            let shown = numbered_lines(&out);
            // The block's opening tag and the joint, each with one line of context.
            assert_eq!(shown, vec![4, 5, 6, 49, 50, 51], "{out}");
            assert_eq!(out.matches('⋮').count(), 1, "{out}");
            // The header still names the primary location.
            assert!(strip_ansi(&out).contains("[m.xml:50:4]"), "{out}");
        }
    }

    #[test]
    fn short_gaps_are_shown_not_elided() {
        let (map, _, joint) = long_file();
        let near = Loc { file: 0, start: joint.start - 40, end: joint.start - 35 };
        let f = Finding::new("mirror-asymmetry", Severity::Warning, "joint b", joint)
            .label("here")
            .secondary(near, "two lines up");
        let out = render(&map, &[f], false);
        assert_eq!(numbered_lines(&out), vec![47, 48, 49, 50, 51], "{out}");
        assert!(!out.contains('⋮'), "{out}");
    }

    #[test]
    fn first_line_clips_at_the_newline() {
        assert_eq!(first_line("ab\ncd", 0, 5), (0, 2));
        assert_eq!(first_line("ab\ncd", 3, 5), (3, 2));
        assert_eq!(first_line("ab", 1, 99), (1, 1));
        assert_eq!(first_line("ab", 9, 1), (2, 0));
    }
}
