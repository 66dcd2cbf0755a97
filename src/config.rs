//! `modellint.toml`: which rules run, at which level, with which thresholds.
//!
//! ```toml
//! select = ["all"]                 # rule ids or groups; default all
//! ignore = ["collision-visual-mismatch"]
//! fail_on = "error"                # error | warning | info
//! [rules.underdamped-pd-gains]
//! level = "warning"
//! min_damping_ratio = 0.6
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

use crate::error::LoadError;
use crate::finding::Severity;
use crate::model::source::{Loc, SourceMap};
use crate::rules::{RuleMeta, all_meta};

/// A TOML table whose keys and values keep their spans.
type SpannedTable = BTreeMap<Spanned<String>, Spanned<toml::Value>>;

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawConfig {
    select: Option<Vec<Spanned<String>>>,
    ignore: Option<Vec<Spanned<String>>>,
    fail_on: Option<Spanned<String>>,
    #[serde(default)]
    /// Each rule's settings with the spans of their keys and values: an error points at the
    /// bad key's line, not at the `[rules.x]` header.
    rules: BTreeMap<String, Spanned<SpannedTable>>,
}

#[derive(Debug, Clone, Default)]
pub struct RuleSettings {
    pub level: Option<Severity>,
    pub options: BTreeMap<String, f64>,
}

#[derive(Debug, Clone, Default)]
pub struct Config {
    pub path: Option<PathBuf>,
    pub select: Vec<String>,
    pub ignore: Vec<String>,
    pub fail_on: Option<Severity>,
    pub rules: BTreeMap<String, RuleSettings>,
}

fn matches(sel: &str, m: &RuleMeta) -> bool {
    sel == "all" || sel == m.id || sel == m.group
}

impl Config {
    /// Whether a rule runs: selected (default all) and not ignored.
    pub fn enabled(&self, m: &RuleMeta) -> bool {
        let selected = self.select.is_empty() || self.select.iter().any(|s| matches(s, m));
        selected && !self.ignore.iter().any(|s| matches(s, m))
    }
    pub fn level(&self, m: &RuleMeta) -> Severity {
        self.rules.get(m.id).and_then(|r| r.level).unwrap_or(m.default_level)
    }
    pub fn options(&self, m: &RuleMeta) -> BTreeMap<String, f64> {
        self.rules.get(m.id).map(|r| r.options.clone()).unwrap_or_default()
    }
    /// Adds command-line `--select` / `--ignore` entries (validated like the file's).
    pub fn add_cli(&mut self, select: &[String], ignore: &[String]) -> Result<(), String> {
        for s in select.iter().chain(ignore) {
            check_selector(s)?;
        }
        if !select.is_empty() {
            self.select = select.to_vec();
        }
        self.ignore.extend(ignore.iter().cloned());
        Ok(())
    }
}

fn check_selector(s: &str) -> Result<(), String> {
    let metas = all_meta();
    if s == "all" || metas.iter().any(|m| m.id == s || m.group == s) {
        return Ok(());
    }
    let ids: Vec<String> = metas.iter().map(|m| m.id.to_string()).collect();
    let near = crate::util::near_matches(s, &ids);
    Err(format!(
        "unknown rule or group `{s}`{}",
        if near.is_empty() {
            String::new()
        } else {
            format!(" (did you mean {}?)", near.join(", "))
        }
    ))
}

/// Finds `modellint.toml` beside the model, or in the current directory.
pub fn discover(model: &Path) -> Option<PathBuf> {
    let dir = model.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    [dir.join("modellint.toml"), PathBuf::from("modellint.toml")].into_iter().find(|p| p.is_file())
}

pub fn load(map: &mut SourceMap, path: &Path) -> Result<Config, LoadError> {
    let file = crate::model::source::read_source(map, path)?;
    let text = map.file(file).text.clone();
    let at = |map: &SourceMap, span: std::ops::Range<usize>, msg: String| {
        LoadError::at(map, Loc { file, start: span.start, end: span.end }, msg)
    };
    let raw: RawConfig = toml::from_str(&text).map_err(|e| {
        at(map, e.span().unwrap_or(0..0), format!("invalid modellint.toml: {}", e.message()))
    })?;
    let mut cfg = Config { path: Some(path.to_path_buf()), ..Default::default() };
    for (list, out) in [(&raw.select, &mut cfg.select), (&raw.ignore, &mut cfg.ignore)] {
        for s in list.iter().flatten() {
            check_selector(s.get_ref()).map_err(|m| at(map, s.span(), m))?;
            out.push(s.get_ref().clone());
        }
    }
    if let Some(f) = &raw.fail_on {
        cfg.fail_on = Some(Severity::parse(f.get_ref()).ok_or_else(|| {
            at(
                map,
                f.span(),
                format!("fail_on must be error, warning or info; got `{}`", f.get_ref()),
            )
        })?);
    }
    let metas = all_meta();
    for (id, table) in &raw.rules {
        let Some(meta) = metas.iter().find(|m| m.id == id) else {
            let ids: Vec<String> = metas.iter().map(|m| m.id.to_string()).collect();
            let near = crate::util::near_matches(id, &ids);
            return Err(at(
                map,
                table.span(),
                format!(
                    "[rules.{id}]: no rule has this id{}",
                    if near.is_empty() {
                        String::new()
                    } else {
                        format!(" (did you mean {}?)", near.join(", "))
                    }
                ),
            ));
        };
        let mut rs = RuleSettings::default();
        for (skey, sval) in table.get_ref() {
            let (key, val) = (skey.get_ref().as_str(), sval.get_ref());
            // `key = value`: the key and its value.
            let span = skey.span().start..sval.span().end.max(skey.span().end);
            if key == "level" {
                let s = val.as_str().unwrap_or("");
                rs.level = Some(Severity::parse(s).ok_or_else(|| {
                    at(
                        map,
                        span.clone(),
                        format!("[rules.{id}] level must be error, warning or info; got {val}"),
                    )
                })?);
                continue;
            }
            let Some(o) = meta.options.iter().find(|o| o.name == key) else {
                let names: Vec<&str> = meta.options.iter().map(|o| o.name).collect();
                return Err(at(
                    map,
                    span,
                    format!(
                        "[rules.{id}] has no option `{key}` (options: level, {})",
                        names.join(", ")
                    ),
                ));
            };
            let x = val.as_float().or_else(|| val.as_integer().map(|i| i as f64));
            match x {
                Some(x) if x.is_finite() && !o.allowed.is_empty() && !o.allowed.contains(&x) => {
                    let one_of: Vec<String> = o.allowed.iter().map(|a| a.to_string()).collect();
                    return Err(at(
                        map,
                        span,
                        format!(
                            "[rules.{id}] {key} must be one of {}, got {val}",
                            one_of.join(", ")
                        ),
                    ));
                }
                Some(x) if x.is_finite() && !o.domain.contains(x) => {
                    return Err(at(
                        map,
                        span,
                        format!(
                            "[rules.{id}] {key} must be {}{}, got {val}",
                            o.domain.describe(),
                            if o.unit.is_empty() {
                                String::new()
                            } else {
                                format!(" ({})", o.unit)
                            }
                        ),
                    ));
                }
                Some(x) if x.is_finite() => {
                    rs.options.insert(o.name.to_string(), x);
                }
                _ => {
                    let unit =
                        if o.unit.is_empty() { String::new() } else { format!(" ({})", o.unit) };
                    let how = if val.is_str() {
                        " (a string: write the number without quotes)"
                    } else {
                        ""
                    };
                    let what = match o.domain.describe() {
                        d if d == "any finite number" => d,
                        d => format!("a number {d}"),
                    };
                    return Err(at(
                        map,
                        span,
                        format!("[rules.{id}] {key} must be {what}{unit}; got {val}{how}"),
                    ));
                }
            }
        }
        cfg.rules.insert(id.clone(), rs);
    }
    Ok(cfg)
}
