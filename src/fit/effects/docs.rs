//! The effects' documentation, from their doc comments ([`EffectMeta::docs`]): the two tables of
//! docs/fitting.md (kept equal to what this module generates by a test; set
//! `MODELLINT_UPDATE_DOCS=1` to rewrite them) and the effect list of `modellint fit --help`.
//!
//! An effect's doc comment is a one-paragraph summary, an optional description, then these
//! sections (`## <name>`, one short paragraph each; `Evidence` may be left out).

use super::{Effect, EffectMeta, all};

/// The sections of an effect's doc comment: (heading, required).
pub const SECTIONS: [(&str, bool); 5] = [
    ("Simulation", true),
    ("Signature", true),
    ("Evidence", false),
    ("Write-back", true),
    ("Isaac Lab / mjlab", true),
];

/// The doc comment's lines (rustdoc gives each a leading space).
fn lines(m: &EffectMeta) -> impl Iterator<Item = &'static str> {
    m.docs.lines().map(|l| l.strip_prefix(' ').unwrap_or(l))
}

/// Joins a paragraph's lines with single spaces.
fn join(ls: &[&str]) -> String {
    ls.iter().map(|l| l.trim()).filter(|l| !l.is_empty()).collect::<Vec<_>>().join(" ")
}

/// The first paragraph of the doc comment, on one line.
pub fn summary(m: &EffectMeta) -> String {
    let ls: Vec<&str> = lines(m).take_while(|l| !l.trim().is_empty()).collect();
    join(&ls)
}

/// Section `name` of the doc comment on one line (`None` when absent or empty).
pub fn section(m: &EffectMeta, name: &str) -> Option<String> {
    let head = format!("## {name}");
    let ls: Vec<&str> = lines(m)
        .skip_while(|l| l.trim() != head)
        .skip(1)
        .take_while(|l| !l.starts_with("## "))
        .collect();
    Some(join(&ls)).filter(|s| !s.is_empty())
}

/// A table cell: `|` escaped (also inside code spans, as GitHub's tables require).
fn cell(s: &str) -> String {
    s.replace('|', "\\|")
}

fn num(v: f64) -> String {
    format!("{v}")
}

/// The fitted parameters with their units and default bounds; the others (held at their
/// defaults) in parentheses.
pub fn params_cell(e: &dyn Effect) -> String {
    let one = |p: &super::ParamDef| {
        let unit = if p.unit.is_empty() { String::new() } else { format!(" {}", p.unit) };
        format!("`{}` ∈ [{}, {}]{unit}", p.name, num(p.lo), num(p.hi))
    };
    let (fit, held) = e.params().split_at(e.fitted().min(e.params().len()));
    let mut s = fit.iter().map(one).collect::<Vec<_>>().join(", ");
    if !held.is_empty() {
        let h: Vec<String> =
            held.iter().map(|p| format!("`{}` = {}", p.name, num(p.default))).collect();
        s.push_str(&format!(" (not fitted: {})", h.join(", ")));
    }
    s
}

/// The effects table of docs/fitting.md.
pub fn effects_table() -> String {
    let mut s = String::from(
        "| id | what | parameters (default bounds) | enters the simulation as | written back | Isaac Lab / mjlab snippet |\n|---|---|---|---|---|---|\n",
    );
    for e in all() {
        let m = e.meta();
        let sec = |n: &str| cell(&section(m, n).unwrap_or_default());
        s.push_str(&format!(
            "| `{}` | {} | {} | {} | {} | {} |\n",
            m.id,
            cell(&summary(m)),
            cell(&params_cell(e)),
            sec("Simulation"),
            sec("Write-back"),
            sec("Isaac Lab / mjlab"),
        ));
    }
    s
}

/// The diagnosis table of docs/fitting.md.
pub fn diagnosis_table() -> String {
    let mut s = String::from("| effect | signature feature | evidence reported |\n|---|---|---|\n");
    for e in all() {
        let m = e.meta();
        s.push_str(&format!(
            "| {} | {} | {} |\n",
            m.id,
            cell(&section(m, "Signature").unwrap_or_default()),
            cell(&section(m, "Evidence").unwrap_or_else(|| "coef, corr".into())),
        ));
    }
    s
}

/// The effect list of `modellint fit --help`.
pub fn help() -> String {
    let mut s = String::from("Effects (ids for --effects; all by default):\n");
    for e in all() {
        s.push_str(&format!("  {:<24} {}\n", e.id(), summary(e.meta())));
    }
    s.push_str("\nParameters, how each enters the simulation and its write-back: `modellint docs fitting`.");
    s
}

/// The generated tables of docs/fitting.md: (name in the markers, content).
pub fn generated() -> [(&'static str, String); 2] {
    [("diagnosis", diagnosis_table()), ("effects", effects_table())]
}

/// `doc` with the text between `<!-- generated: NAME -->` and `<!-- end generated: NAME -->`
/// replaced by `content` (`None` when the markers are missing).
pub fn splice(doc: &str, name: &str, content: &str) -> Option<String> {
    let (open, close) =
        (format!("<!-- generated: {name} -->\n"), format!("<!-- end generated: {name} -->"));
    let a = doc.find(&open)? + open.len();
    let b = a + doc[a..].find(&close)?;
    // The content is indented like the closing marker (the tables may sit in a list item).
    let line = doc[..b].rfind('\n').map_or(0, |i| i + 1).max(a);
    let indent = &doc[line..b];
    let body: String = content.lines().map(|l| format!("{indent}{l}\n")).collect();
    Some(format!("{}{body}{}", &doc[..a], &doc[line..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_effect_documents_every_required_section() {
        for e in all() {
            let m = e.meta();
            assert!(summary(m).len() > 10, "{}: no summary paragraph", m.id);
            for (name, required) in SECTIONS {
                if required {
                    assert!(section(m, name).is_some(), "{}: no `## {name}` section", m.id);
                }
            }
            // No stray sections: every heading is one of SECTIONS.
            for l in lines(m).filter(|l| l.starts_with("## ")) {
                assert!(SECTIONS.iter().any(|(n, _)| l[3..].trim() == *n), "{}: `{l}`", m.id);
            }
        }
    }

    #[test]
    fn sections_are_read_up_to_the_next_heading() {
        let m = EffectMeta {
            id: "x",
            entry: super::super::Entry::Model,
            params: &[],
            docs: " First line\n of the summary.\n\n More.\n\n ## Signature\n `a|b`\n spans lines\n\n ## Write-back\n joint\n",
        };
        assert_eq!(summary(&m), "First line of the summary.");
        assert_eq!(section(&m, "Signature").as_deref(), Some("`a|b` spans lines"));
        assert_eq!(section(&m, "Write-back").as_deref(), Some("joint"));
        assert_eq!(section(&m, "Evidence"), None);
        assert_eq!(cell("`a|b`"), "`a\\|b`");
    }

    #[test]
    fn splice_replaces_between_markers_keeping_the_indent() {
        let doc = "a\n   <!-- generated: t -->\n   old\n   <!-- end generated: t -->\nb\n";
        let out = splice(doc, "t", "x\ny\n").expect("markers");
        assert_eq!(
            out,
            "a\n   <!-- generated: t -->\n   x\n   y\n   <!-- end generated: t -->\nb\n"
        );
        assert!(splice(doc, "u", "x").is_none());
    }

    #[test]
    fn help_lists_every_effect() {
        let h = help();
        for e in all() {
            assert!(h.contains(&format!("  {} ", e.id())), "{}", e.id());
        }
    }

    /// docs/fitting.md holds exactly the generated tables. `MODELLINT_UPDATE_DOCS=1` rewrites them.
    #[test]
    fn fitting_md_tables_are_generated_from_the_effects() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/fitting.md");
        let doc = std::fs::read_to_string(&path).expect("docs/fitting.md");
        let mut want = doc.clone();
        for (name, table) in generated() {
            want = splice(&want, name, &table)
                .unwrap_or_else(|| panic!("docs/fitting.md: no `<!-- generated: {name} -->`"));
        }
        if want != doc && std::env::var_os("MODELLINT_UPDATE_DOCS").is_some() {
            std::fs::write(&path, &want).expect("write docs/fitting.md");
            return;
        }
        assert!(
            want == doc,
            "docs/fitting.md's effect tables differ from the effects' doc comments; \
             rerun with MODELLINT_UPDATE_DOCS=1 to regenerate them"
        );
    }
}
