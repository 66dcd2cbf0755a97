//! One lint run: load model, spec and config; run the enabled rules; apply suppressions.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::config::Config;
use crate::error::LoadError;
use crate::finding::{Finding, Severity};
use crate::model::Robot;
use crate::model::source::{SourceMap, UndeclaredName};
use crate::rules::{Context, meta_rules, registry};
use crate::spec::Spec;
use crate::spec_use::SpecSearch;

pub struct LintInput {
    pub model: PathBuf,
    pub spec: Option<PathBuf>,
    pub config: Option<PathBuf>,
    pub select: Vec<String>,
    pub ignore: Vec<String>,
}

pub struct Loaded {
    pub sources: SourceMap,
    pub robot: Robot,
    pub spec: Option<Spec>,
    pub config: Config,
    /// Where the spec was looked for (empty `searched` when given with --spec).
    pub spec_search: SpecSearch,
    /// The model the stance runs simulate, built by the first of them
    /// ([`crate::probe::float::stance_model`]) and shared by the others.
    pub stance: std::sync::OnceLock<crate::probe::float::StanceModel>,
}

/// Loads everything a lint run needs; every failure is a located `LoadError` (exit 2).
pub fn load(input: &LintInput) -> Result<Loaded, LoadError> {
    crate::model::mj::silence_warnings();
    let mut sources = SourceMap::default();
    let config = match input.config.clone().or_else(|| crate::config::discover(&input.model)) {
        Some(p) => crate::config::load(&mut sources, &p)?,
        None => Config::default(),
    };
    let mut config = config;
    config
        .add_cli(&input.select, &input.ignore)
        .map_err(|m| LoadError::plain(Path::new("<command line>"), m))?;
    let spec_search = match &input.spec {
        Some(p) if !p.is_file() => return Err(LoadError::plain(p, "spec file not found".into())),
        Some(p) => SpecSearch { path: Some(p.clone()), searched: vec![] },
        None => crate::spec_use::discover(&input.model),
    };
    let spec_path = spec_search.path.clone();
    // The spec may name the keyframe, so read its robot table before compiling the model.
    let keyframe = spec_path.as_ref().and_then(|p| peek_keyframe(p));
    let robot =
        crate::model::load(&mut sources, &input.model, keyframe.as_ref().map(|k| k.name.as_str()))
            .map_err(|e| match (&keyframe, &spec_path) {
                // A keyframe the model lacks is the spec's mistake: said at its `keyframe` key.
                (Some(k), Some(p)) if e.message.starts_with("keyframe `") => LoadError {
                    file: p.clone(),
                    line: Some(k.line),
                    column: Some(k.column),
                    message: format!("[robot] keyframe: {}", e.message),
                    snippet: None,
                },
                _ => e,
            })?;
    let names: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    let spec = match spec_path {
        Some(p) => Some(crate::spec::load(&mut sources, &p, &names)?),
        None => None,
    };
    Ok(Loaded { sources, robot, spec, config, spec_search, stance: std::sync::OnceLock::new() })
}

/// The spec's `[robot] keyframe` and where its value is (1-based line and column).
struct SpecKeyframe {
    name: String,
    line: usize,
    column: usize,
}

fn peek_keyframe(path: &Path) -> Option<SpecKeyframe> {
    #[derive(serde::Deserialize)]
    struct Peek {
        robot: Option<PeekRobot>,
    }
    #[derive(serde::Deserialize)]
    struct PeekRobot {
        keyframe: Option<toml::Spanned<String>>,
    }
    let text = std::fs::read_to_string(path).ok()?;
    let k = toml::from_str::<Peek>(&text).ok()?.robot?.keyframe?;
    let start = k.span().start.min(text.len());
    let before = &text[..start];
    let line = 1 + before.matches('\n').count();
    let column = 1 + before.rsplit('\n').next().map_or(0, |l| l.chars().count());
    Some(SpecKeyframe { name: k.into_inner(), line, column })
}

crate::declare_rule! {
    /// ## What it does
    /// Reports content after the root element of a model file or an included file, such as a
    /// second `</mujoco>` left by an editing mistake. MuJoCo stops reading at the end of the root
    /// element and loads the model anyway; modellint does the same and points at the junk.
    ///
    /// ## Why is this bad?
    /// Other XML tools (URDF converters, `xmllint`, editors, ROS tooling) reject the file, and
    /// anything written after the root element (a forgotten `<actuator>` block pasted below it)
    /// is silently ignored by MuJoCo.
    ///
    /// ## How it is confirmed
    /// Static: the file parses as XML only up to the end of its root element.
    ///
    /// ## How to fix
    /// Delete the content after the closing root tag, or move it inside the root element.
    pub TrailingXmlContent { id: "trailing-xml-content", group: "engine", level: Severity::Warning, probe: None, options: [] }
}

crate::declare_rule! {
    /// ## What it does
    /// Reports elements whose namespace prefix no `xmlns` declares, such as `<xacro:include>`
    /// and `<xacro:my_camera>` left in a URDF that was never run through xacro (or was edited
    /// after). MuJoCo reads XML without namespaces and its URDF reader skips elements it does not
    /// know, so it loads the model without them; modellint reads the file the same way (each
    /// undeclared `prefix:` of a tag or attribute name taken as part of the name) and points at
    /// the first such element of each prefix, naming the others.
    ///
    /// ## Why is this bad?
    /// Whatever the element stands for (a macro call that adds a camera, a sensor mount, a leg)
    /// is not in the model MuJoCo simulates: its mass and geometry are missing. XML tools that
    /// follow the namespace rules (`xmllint`, most editors and XML libraries) reject the file.
    ///
    /// ## How it is confirmed
    /// Static: the file parses as XML only once the undeclared prefixes are read as part of the
    /// names (at most `MAX_UNDECLARED_PREFIXES`, 8, distinct prefixes per file).
    ///
    /// ## How to fix
    /// Expand the file with xacro (`xacro robot.urdf.xacro > robot.urdf`), or delete the
    /// leftover elements and write what they stood for as links and joints.
    pub UndeclaredXmlPrefix { id: "undeclared-xml-prefix", group: "engine", level: Severity::Warning, probe: None, options: [] }
}

/// One finding per file and prefix, at the first element, naming the others.
fn undeclared_prefix_findings(l: &Loaded, findings: &mut Vec<Finding>) {
    let meta = &UndeclaredXmlPrefix::META;
    if !l.config.enabled(meta) {
        return;
    }
    let mut groups: Vec<(usize, &str, Vec<&UndeclaredName>)> = Vec::new();
    for u in &l.sources.undeclared {
        match groups.iter_mut().find(|g| g.0 == u.0.file && g.1 == u.2) {
            Some(g) => g.2.push(u),
            None => groups.push((u.0.file, &u.2, vec![u])),
        }
    }
    for (_, prefix, tags) in groups {
        let names: Vec<String> = tags.iter().take(4).map(|t| format!("`<{}>`", t.1)).collect();
        let more =
            if tags.len() > 4 { format!(" and {} more", tags.len() - 4) } else { String::new() };
        let msg = format!(
            "{} element{} use{} the prefix `{prefix}:`, which no xmlns declares: {}{more}; MuJoCo does not read {} (what {} stand{} for is not in the model)",
            tags.len(),
            if tags.len() == 1 { "" } else { "s" },
            if tags.len() == 1 { "s" } else { "" },
            names.join(", "),
            if tags.len() == 1 { "it" } else { "them" },
            if tags.len() == 1 { "it" } else { "they" },
            if tags.len() == 1 { "s" } else { "" },
        );
        let note = if prefix == "xacro" {
            "an unexpanded xacro macro: the file was not (or not entirely) produced by a xacro run"
        } else {
            "MuJoCo reads XML without namespaces and skips elements it does not know"
        };
        findings.push(
            Finding::new(meta.id, l.config.level(meta), msg, tags[0].0)
                .label(format!("prefix `{prefix}:` declared nowhere"))
                .note(note)
                .help("expand the file with xacro, or write what the elements stand for as links and joints"),
        );
    }
}

/// Runs the static rules and applies inline suppressions.
pub fn run_rules(l: &Loaded) -> Vec<Finding> {
    let mut findings = Vec::new();
    let trailing = &TrailingXmlContent::META;
    if l.config.enabled(trailing) {
        for loc in &l.sources.trailing {
            let junk: String =
                l.sources.file(loc.file).text[loc.start..loc.end].chars().take(40).collect();
            let junk = junk.lines().next().unwrap_or("").to_string();
            findings.push(
                Finding::new(trailing.id, l.config.level(trailing), format!("content after the root element is ignored: `{junk}`"), *loc)
                    .label("MuJoCo stops reading before this")
                    .note("MuJoCo loads the file up to the end of its root element; other XML tools reject it, and anything written here is silently ignored")
                    .help("delete the content after the closing root tag, or move it inside the root element"),
            );
        }
    }
    undeclared_prefix_findings(l, &mut findings);
    // The static foot rules of a model whose qpos0 places joints past their stops (no
    // keyframe) judge it there and at the nearest pose the robot can take, and report what
    // holds at both (`rules::contact::pose`): the clamped copy is built once, for them only.
    let mut foot_robot: Option<Option<Robot>> = None;
    for rule in registry() {
        let meta = rule.meta();
        if !l.config.enabled(meta) {
            continue;
        }
        let cx = |robot| Context {
            robot,
            spec: l.spec.as_ref(),
            sources: &l.sources,
            options: l.config.options(meta),
            meta,
            level: l.config.level(meta),
        };
        let clamped = if crate::rules::contact::pose::FOOT_RULES.contains(&meta.id) {
            foot_robot
                .get_or_insert_with(|| crate::rules::contact::pose::foot_rules_robot(&l.robot))
                .as_ref()
        } else {
            None
        };
        match clamped {
            None => rule.check(&cx(&l.robot), &mut findings),
            Some(c) => {
                let (mut at_qpos0, mut at_clamped) = (Vec::new(), Vec::new());
                rule.check(&cx(&l.robot), &mut at_qpos0);
                rule.check(&cx(c), &mut at_clamped);
                findings.extend(crate::rules::contact::pose::at_both(at_qpos0, at_clamped));
            }
        }
    }
    apply_suppressions(l, findings)
}

fn apply_suppressions(l: &Loaded, findings: Vec<Finding>) -> Vec<Finding> {
    let idx = &l.robot.src;
    let mut used = vec![false; idx.suppressions.len()];
    let known: Vec<&str> = crate::rules::all_meta().iter().map(|m| m.id).collect();
    let mut out = Vec::new();
    'f: for f in findings {
        for elems in idx.elems.values() {
            for e in elems {
                let covers = |loc: crate::model::source::Loc| {
                    loc.file == e.full.file && loc.start >= e.full.start && loc.end <= e.full.end
                };
                if !(covers(f.primary) || f.element_loc.is_some_and(covers)) {
                    continue;
                }
                for &s in &e.suppressions {
                    if idx.suppressions[s].rules.iter().any(|r| r == f.rule) {
                        used[s] = true;
                        continue 'f;
                    }
                }
            }
        }
        out.push(f);
    }
    let unused = &meta_rules::UnusedSuppression::META;
    let invalid = &meta_rules::InvalidSuppression::META;
    for (i, s) in idx.suppressions.iter().enumerate() {
        for r in &s.rules {
            if !known.contains(&r.as_str()) {
                if l.config.enabled(invalid) {
                    // The ids closest to the misspelling, as `--select` and `rule` offer them.
                    let ids: Vec<String> = known.iter().map(|k| k.to_string()).collect();
                    let near = crate::util::near_matches(r, &ids);
                    let hint = if near.is_empty() {
                        String::new()
                    } else {
                        format!(" (did you mean {}?)", near.join(", "))
                    };
                    out.push(
                        Finding::new(
                            invalid.id,
                            l.config.level(invalid),
                            format!("suppression names unknown rule `{r}`{hint}"),
                            s.loc,
                        )
                        .help("use an id from `modellint rules`"),
                    );
                }
            } else if !used[i]
                && l.config.enabled(unused)
                && l.config.enabled(crate::rules::find_meta(r).unwrap_or(unused))
            {
                out.push(
                    Finding::new(
                        unused.id,
                        l.config.level(unused),
                        format!("suppression of `{r}` matched no finding"),
                        s.loc,
                    )
                    .note(format!("reason given: {}", s.reason))
                    .help("remove the comment if the problem was fixed"),
                );
            }
        }
    }
    for (loc, msg) in &idx.bad_suppressions {
        if l.config.enabled(invalid) {
            out.push(Finding::new(invalid.id, l.config.level(invalid), msg.clone(), *loc));
        }
    }
    sort_findings(&mut out);
    out
}

/// The findings of one model: static rules, then (unless `probe` is false) the probes.
pub fn lint(l: &Loaded, probe: bool) -> Vec<Finding> {
    let mut findings = run_rules(l);
    if probe {
        confirm(l, &mut findings);
    }
    findings
}

/// Runs the probes: the claim of every finding that carries one, and the whole-model sanity run
/// (whose misbehaviour is the finding `unstable-simulation`), all in parallel.
pub fn confirm(l: &Loaded, findings: &mut Vec<Finding>) {
    use crate::probe::{Plan, WholeModelSanity};
    use crate::rules::control::unstable_simulation::{UnstableSimulation, finding};
    let sanity = l.config.enabled(&UnstableSimulation::META);
    let mut plan = Plan::new(l);
    if sanity {
        plan.add::<WholeModelSanity>(());
    }
    let runs = crate::probe::confirm(findings, plan);
    if sanity
        && let Some(run) = runs.get::<WholeModelSanity>(())
        && let Some(f) = finding(l, l.config.level(&UnstableSimulation::META), run)
    {
        findings.push(f);
    }
    sort_findings(findings);
}

/// The note for a run without a spec, or with one that leaves rules without their facts (None:
/// every rule has what it needs).
pub fn missing_spec_note(l: &Loaded) -> Option<String> {
    let enabled = |id: &str| crate::rules::find_meta(id).is_some_and(|m| l.config.enabled(m));
    if let Some(spec) = &l.spec {
        let (mut skipped, mut weakened) = crate::spec_use::waiting(spec, &l.robot);
        skipped.retain(|(id, _)| enabled(id));
        weakened.retain(|(id, _)| enabled(id));
        let path = l.spec_search.path.as_deref().unwrap_or(Path::new("spec"));
        return crate::spec_use::waiting_note(&l.robot.path, path, &skipped, &weakened);
    }
    Some(crate::spec_use::missing_note(&l.robot.path, &l.spec_search, &enabled))
}

/// Why a path given among several is not linted: its root element is not `<mujoco>` or
/// `<robot>` (ROS `package.xml`, launch files, …). `None`: lint it (unreadable files included,
/// so that the loader reports them).
pub fn not_a_model(path: &Path) -> Option<String> {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("toml")) {
        return Some(
            "a TOML file (a spec or rule configuration) with no model of its name beside it".into(),
        );
    }
    let tag = crate::model::source::root_tag(path)?;
    (tag != "mujoco" && tag != "robot").then(|| {
        format!("root element <{tag}> is not a robot model (MJCF <mujoco> or URDF <robot>)")
    })
}

/// Deterministic order: file, position, rule id, message.
pub fn sort_findings(v: &mut [Finding]) {
    v.sort_by(|a, b| {
        (a.primary.file, a.primary.start, a.rule, &a.message).cmp(&(
            b.primary.file,
            b.primary.start,
            b.rule,
            &b.message,
        ))
    });
}

/// Exit status for a set of findings: 1 when any is at or above `fail_on`.
pub fn exit_code(findings: &[Finding], fail_on: Severity) -> i32 {
    if findings.iter().any(|f| f.severity >= fail_on) { 1 } else { 0 }
}

/// For the subcommands (gap, fit, synth): load a model and its spec with no rule selection, or
/// print the located error to stderr. `Err` carries the exit code (2).
pub fn load_for_command(model: &Path, spec: Option<PathBuf>) -> Result<Loaded, i32> {
    load_for_api(model, spec).map_err(|e| {
        eprint!("{}", crate::output::text::render_error(&e, crate::output::color_on_stderr()));
        2
    })
}

/// [`load_for_command`] returning the error instead of printing it.
pub fn load_for_api(model: &Path, spec: Option<PathBuf>) -> Result<Loaded, LoadError> {
    let input = LintInput {
        model: model.to_path_buf(),
        spec,
        config: None,
        select: vec![],
        ignore: vec![],
    };
    load(&input)
}

/// The spec in use, where it was looked for and, without one, the rules skipped or weakened
/// (the JSON's `spec`).
pub fn spec_info(l: &Loaded) -> crate::output::SpecInfo {
    let enabled = |id: &str| crate::rules::find_meta(id).is_some_and(|m| l.config.enabled(m));
    let (skipped, weakened): (Vec<&str>, Vec<&str>) = match &l.spec {
        None => (
            crate::spec_use::SKIPPED.iter().map(|r| r.0).collect(),
            crate::spec_use::WEAKENED.iter().map(|r| r.0).collect(),
        ),
        Some(spec) => {
            let (s, w) = crate::spec_use::waiting(spec, &l.robot);
            (s.iter().map(|r| r.0).collect(), w.iter().map(|r| r.0).collect())
        }
    };
    let ids = |v: Vec<&str>| v.into_iter().filter(|id| enabled(id)).map(str::to_string).collect();
    crate::output::SpecInfo {
        path: l.spec_search.path.as_ref().map(|p| p.display().to_string()),
        searched: l.spec_search.searched.iter().map(|p| p.display().to_string()).collect(),
        skipped_rules: ids(skipped),
        weakened_rules: ids(weakened),
    }
}

/// A finding of one rule at one place (canonical file, line, column) with one message.
pub type FindingKey = (&'static str, PathBuf, usize, usize, String);

/// Keeps the first of repeated findings (two scenes that include one robot file report its
/// findings once); `seen` carries what earlier models reported.
pub fn drop_repeated(seen: &mut BTreeSet<FindingKey>, l: &Loaded, findings: &mut Vec<Finding>) {
    findings.retain(|f| {
        let p = crate::output::position(&l.sources, f.primary);
        let at = std::fs::canonicalize(&p.file).unwrap_or_else(|_| PathBuf::from(&p.file));
        seen.insert((f.rule, at, p.line, p.column, f.message.clone()))
    });
}

/// `modellint MODEL --format json` for one model (`Err`: what makes that exit 2), returned
/// instead of printed: the Python API's `lint`. `cache_dir`: the lint cache, as the CLI's
/// `--cache-dir` (None: no cache); a hit answers without compiling (src/lint_cache.rs).
pub fn lint_json(
    input: &LintInput,
    probe: bool,
    cache_dir: Option<&Path>,
) -> Result<String, LoadError> {
    let opts =
        [format!("api-json probe={probe}"), format!("{:?} {:?}", input.select, input.ignore)];
    let key = cache_dir.and_then(|_| {
        crate::lint_cache::key(
            std::slice::from_ref(&input.model),
            &input.spec,
            &input.config,
            &opts,
        )
    });
    let hit = cache_dir.zip(key.as_deref()).and_then(|(d, k)| crate::lint_cache::load(d, k));
    if let Some(hit) = hit {
        return Ok(hit.stdout);
    }
    let loaded = load(input)?;
    let mut findings = lint(&loaded, probe);
    drop_repeated(&mut BTreeSet::new(), &loaded, &mut findings);
    let model = input.model.display().to_string();
    let info = spec_info(&loaded);
    let out = crate::output::json::render(&loaded.sources, &model, &findings, Some(&info));
    if let (Some(d), Some(k)) = (cache_dir, &key) {
        let entry =
            crate::lint_cache::Entry { stdout: out.clone(), stderr: String::new(), code: 0 };
        crate::lint_cache::store(d, k, &entry);
    }
    Ok(out)
}
