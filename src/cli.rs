//! Command line: thin glue from arguments to the library, and exit codes
//! (0 clean, 1 findings at or above --fail-on, 2 could not do the job).

use std::io::{IsTerminal, Write};
use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

use crate::finding::Severity;
use crate::lint::{LintInput, exit_code, lint};
use crate::output::{self, Format};

#[derive(Parser, Debug)]
#[command(
    name = "modellint",
    version = env!("MODELLINT_VERSION"),
    about = "Find the robot-model mistakes that break sim-to-real transfer, and prove them in MuJoCo.",
    long_about = "modellint checks a MuJoCo MJCF (or URDF) robot model against the real hardware it stands for:\n\
armature vs reflected rotor inertia, PD gains that make joints underdamped, tilted toes, mesh feet,\n\
training ranges that use the hard stops, missing action delay, and more. Each finding can be\n\
confirmed by a short MuJoCo probe simulation. `modellint gap` and `modellint fit` compare the model\n\
with real recordings, name the physics it is missing and fit it.\n\n\
Hardware facts come from a TOML spec beside the model (models/asimov.toml for models/asimov.xml),\n\
else beside a file it includes (a scene's robot file), or --spec; without one modellint says which\n\
rules were skipped or weakened; rule settings from modellint.toml beside the model or in the working directory.\n\n\
Lint cache: each run's result is cached (a few kB, keyed by a hash of the model XML, its includes,\n\
meshes, textures, the spec, the config and the options), so an unchanged re-lint is answered\n\
without compiling (Booster T1 and Unitree H1 scenes: 10-40 ms, bench/cache_cap.sh) instead of a\n\
full MuJoCo compile, as a pre-commit hook re-runs it.\n\
--no-cache disables it; --cache-dir or $MODELLINT_CACHE_DIR moves it; its size is capped at\n\
--cache-max or $MODELLINT_CACHE_MAX_MB megabytes (default 300, least recently used entries evicted first);\n\
`modellint cache clean` empties it.\n\n\
Exit codes: 0 no finding at or above --fail-on; 1 findings; 2 modellint could not do its job.",
    after_help = "Examples:\n  modellint models/asimov.xml\n  modellint robot.xml --spec robot.toml --format sarif > modellint.sarif\n  modellint robot.xml --no-probe --fail-on warning     # pre-commit speed\n  modellint init-spec robot.xml                        # start robot.toml from the model\n  modellint rules                                      # list rule ids\n  modellint rule underdamped-pd-gains                  # a rule's documentation",
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    #[command(subcommand)]
    pub cmd: Option<Cmd>,
    #[command(flatten)]
    pub check: CheckArgs,
}

#[derive(Args, Debug, Clone)]
pub struct CheckArgs {
    /// Models to lint: MJCF (.xml) or URDF (.urdf). With several, the exit code is the highest
    /// of all, and XML files that are not robot models (ROS package.xml, launch files) are
    /// skipped with a note.
    pub models: Vec<PathBuf>,
    /// Hardware spec (TOML), for every model given. Default: <model>.toml beside the model, else
    /// beside a file it includes (a scene's robot file).
    #[arg(long)]
    pub spec: Option<PathBuf>,
    /// Rule configuration. Default: modellint.toml beside the model or in the working directory.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Output format (also `--output-format`). Default: github when GITHUB_ACTIONS=true, else
    /// text. `concise`: one line per finding, `file:line:col: level rule message`.
    #[arg(long, value_enum, alias = "output-format")]
    pub format: Option<Format>,
    /// After the findings, print how many each rule produced (stderr for json and sarif).
    #[arg(long)]
    pub statistics: bool,
    /// Lowest severity that makes the exit code 1.
    #[arg(long, value_parser = ["error", "warning", "warn", "info"])]
    pub fail_on: Option<String>,
    /// Run only these rules or groups (comma-separated or repeated).
    #[arg(long, value_delimiter = ',')]
    pub select: Vec<String>,
    /// Skip these rules or groups.
    #[arg(long, value_delimiter = ',')]
    pub ignore: Vec<String>,
    /// Static pass only: skip the MuJoCo probe simulations (for pre-commit hooks).
    #[arg(long)]
    pub no_probe: bool,
    /// Skip an XML file that is not a robot model (ROS package.xml, launch files) with a note
    /// even when it is the only file given (the pre-commit hook passes only the staged files);
    /// without it a lone non-model is an error (exit 2). With several files they are always
    /// skipped. A hardware spec given with it (a staged `robot.toml`) lints `robot.xml` beside it.
    #[arg(long)]
    pub skip_non_models: bool,
    /// Directory of the lint cache. Default: $MODELLINT_CACHE_DIR, else
    /// $XDG_CACHE_HOME/modellint, else ~/.cache/modellint.
    #[arg(long)]
    pub cache_dir: Option<PathBuf>,
    /// Always lint (compile the model with MuJoCo); neither read nor write the cache.
    #[arg(long)]
    pub no_cache: bool,
    /// Size cap of the lint cache, megabytes (least recently used entries out).
    /// Default: $MODELLINT_CACHE_MAX_MB, else 300.
    #[arg(long, value_name = "MB", value_parser = parse_mb)]
    pub cache_max: Option<f64>,
    #[command(flatten)]
    pub packages: crate::cli_logs::PackageArgs,
    /// Colour in text output and messages: auto, always, never (every subcommand).
    #[arg(long, global = true, default_value = "auto", value_parser = ["auto", "always", "never"])]
    pub color: String,
}

#[derive(Subcommand, Debug, Clone)]
pub enum CacheCmd {
    /// Remove every cached lint result (and compiled models of earlier versions).
    Clean {
        /// Cache directory. Default: $MODELLINT_CACHE_DIR, else $XDG_CACHE_HOME/modellint,
        /// else ~/.cache/modellint.
        #[arg(long, visible_alias = "cache-dir")]
        dir: Option<PathBuf>,
    },
}

#[derive(Subcommand, Debug)]
pub enum Cmd {
    /// List every rule: id, group, default level, probe.
    Rules,
    /// Show one rule's documentation.
    Rule {
        /// Rule id, e.g. underdamped-pd-gains.
        id: String,
    },
    /// Write docs/rules/<id>.md for every rule (from the rules' doc comments).
    GenDocs {
        /// Output directory.
        #[arg(long, default_value = "docs/rules")]
        out: PathBuf,
        /// Only check that the files are current; exit 1 when not.
        #[arg(long)]
        check: bool,
    },
    /// Manage the lint cache (`modellint cache clean`). Its size is capped at
    /// $MODELLINT_CACHE_MAX_MB megabytes (default 300), least recently used entries first out.
    Cache {
        #[command(subcommand)]
        action: CacheCmd,
    },
    /// Write a commented hardware-spec template derived from the model, so the spec-driven
    /// checks run at once (docs/spec.md).
    #[command(long_about = crate::spec_init::LONG_ABOUT)]
    InitSpec {
        /// Model (MJCF or URDF).
        model: PathBuf,
        /// Where to write the spec; `-` for stdout. Default: <model>.toml beside the model, which
        /// `modellint MODEL` then finds by itself.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Replace an existing file.
        #[arg(long)]
        force: bool,
        #[command(flatten)]
        packages: crate::cli_logs::PackageArgs,
    },
    /// Replay real recordings in MuJoCo and measure the sim-to-real gap (the Booster T1 sim-to-real study's replay and metrics).
    Gap(GapCmd),
    /// Name the physics the model is missing from real recordings, fit it, and show the held-out
    /// improvement (`modellint fit --help` lists the effects).
    #[command(after_help = crate::fit::effects::docs::help())]
    Fit(FitCmd),
    /// Recordings of a simulated "real robot" (the model plus hidden effects) through a
    /// simulated logging setup (100 Hz controller, asynchronous 88 Hz recorder, noise, 12-bit
    /// encoder, drops), with the answer key. `modellint synth --help` explains every knob.
    #[command(long_about = crate::synth::cmd::LONG_ABOUT)]
    Synth(crate::synth::cmd::SynthCmd),
    /// Convert a recording to the CSV format: a BAM servo log (adds the servo.kp column), a
    /// NumPy .npz, LeRobot parquet (one CSV per episode: OUT_ep<N>.csv) or MCAP file.
    Convert {
        /// Recording (BAM JSON, .npz, .parquet, .mcap, CSV).
        input: PathBuf,
        /// CSV file to write.
        output: PathBuf,
        #[command(flatten)]
        log: crate::cli_logs::LogArgs,
    },
    /// Print a documentation page (`modellint docs recording-format`); without a topic, list them.
    Docs {
        /// Topic: architecture, ci, conceal-benchmark, fitting, gap, probes, recording-format,
        /// spec, synth.
        topic: Option<String>,
    },
}

#[derive(Args, Debug)]
pub struct GapCmd {
    /// Model (MJCF or URDF).
    pub model: PathBuf,
    /// Recordings: CSV files, BAM JSON logs, NumPy .npz, LeRobot parquet, MCAP files, or
    /// directories (their recordings, sorted; a dataset directory with episodes/ beside
    /// truth.json, as `synth --out` writes, is read from its episodes/; a LeRobot dataset from
    /// its data/).
    #[arg(required = true)]
    pub recordings: Vec<PathBuf>,
    /// Hardware spec (TOML) for joint regions. Default: <model>.toml beside the model.
    #[arg(long)]
    pub spec: Option<PathBuf>,
    #[command(flatten)]
    pub replay: ReplayArgs,
    /// Output format.
    #[arg(long, value_enum, default_value_t = ResultFormat::Text)]
    pub format: ResultFormat,
    /// Write an HTML report (inline SVG) into this directory.
    #[arg(long)]
    pub report: Option<PathBuf>,
    #[command(flatten)]
    pub packages: crate::cli_logs::PackageArgs,
}

/// `--format` of `gap` and `fit` (the lint's `--format` is [`crate::output::Format`], which
/// adds SARIF and GitHub annotations for findings).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ResultFormat {
    /// Human-readable tables.
    Text,
    /// JSON on stdout.
    Json,
}

#[derive(Args, Debug)]
pub struct FitCmd {
    /// Model (MJCF or URDF).
    pub model: PathBuf,
    /// Deprecated: `--servo xl330` is `--holdout-by kp` (the servo's firmware law, friction
    /// and torque-off braking are ordinary effects now).
    #[arg(long, value_parser = ["xl330"], hide = true)]
    pub servo: Option<String>,
    /// Recordings: CSV files, BAM JSON logs, NumPy .npz, LeRobot parquet, MCAP files, or
    /// directories (their recordings, sorted; a dataset directory with episodes/ beside
    /// truth.json, as `synth --out` writes, is read from its episodes/; a LeRobot dataset from
    /// its data/).
    #[arg(required = true)]
    pub recordings: Vec<PathBuf>,
    /// Hardware spec (TOML) for joint regions. Default: <model>.toml beside the model.
    #[arg(long)]
    pub spec: Option<PathBuf>,
    /// Effects to consider (comma-separated ids); default all.
    #[arg(long, value_delimiter = ',')]
    pub effects: Vec<String>,
    /// Only fit joints matching this glob (e.g. '*knee*').
    #[arg(long)]
    pub joints: Option<String>,
    /// Told fit: no search — fit exactly EFFECT on JOINTS (`+`-separated, `*` for every fitted
    /// joint as one group), repeatable; several are fitted jointly. For when the physics is
    /// known and only its value is wanted, and as the reference a blind search is timed
    /// against. E.g. `--told viscous_damping@left_knee+right_knee`. A body effect with one
    /// place component held at the model's value is `EFFECT~PARAMETER` (`com_offset~along`,
    /// `link_mass~offset`, ...): the floor's rival that tests that component.
    #[arg(long, value_name = "EFFECT@JOINTS")]
    pub told: Vec<String>,
    /// Hold out one episode in N, spread over the sorted list; episodes whose header says
    /// `split: heldout` are held out instead when there are any (a single episode is split in
    /// time windows).
    #[arg(long, default_value_t = 4)]
    pub holdout: usize,
    /// Hold out by a metadata key instead: `KEY=VALUE` holds out the episodes whose metadata
    /// KEY equals VALUE (e.g. `kp=800`, the firmware gain of BAM servo logs); `KEY` alone holds
    /// out every value in turn (one fit per value) and reports each fold and the held-out
    /// error averaged over all episodes.
    #[arg(long, value_name = "KEY[=VALUE]")]
    pub holdout_by: Option<String>,
    /// Multiple shooting: fit on training windows of this length [s] (> 0), each started from
    /// the recorded state. Without it the search replays whole episodes and only the kept dry
    /// friction is re-fitted on 1 s windows at the end.
    #[arg(long)]
    pub window: Option<f64>,
    /// Estimate each episode's start state (first position and velocity of every joint) from
    /// the whole episode, with the first row's noisy reading as its prior, instead of starting
    /// every replay exactly at the first row (`modellint docs fitting`, step 2). Helps a lightly damped
    /// servo. Opt-in: on every benchmark it gives the same answers as the first row
    /// (`modellint docs fitting`, step 2).
    #[arg(long)]
    pub start_estimate: bool,
    #[command(flatten)]
    pub replay: ReplayArgs,
    /// No progress and no notes on stderr (the search's decisions: merges, swaps, drops;
    /// still in the JSON `notes`). Warnings and errors still print.
    #[arg(long, short)]
    pub quiet: bool,
    /// Output format.
    #[arg(long, value_enum, default_value_t = ResultFormat::Text)]
    pub format: ResultFormat,
    /// Write the model with the MuJoCo-expressible fitted values (MJCF text edited in place).
    #[arg(long)]
    pub write_model: Option<PathBuf>,
    /// Write all fitted effects (incl. hook-only ones) as TOML.
    #[arg(long)]
    pub write_actuators: Option<PathBuf>,
    /// Write one HTML report (DIR/index.html): held-out episodes before → after the fit.
    #[arg(long)]
    pub report: Option<PathBuf>,
    #[command(flatten)]
    pub packages: crate::cli_logs::PackageArgs,
}

impl GapCmd {
    /// What `modellint gap` runs ([`crate::sim2real::cmd::gap`]); the Python API parses its
    /// options with these same flags.
    pub fn into_args(self) -> crate::sim2real::cmd::GapArgs {
        crate::sim2real::cmd::GapArgs {
            model: self.model,
            recordings: self.recordings,
            spec: self.spec,
            parse: self.replay.parse_options(),
            replay: self.replay.options(),
            json: self.format == ResultFormat::Json,
            report: self.report,
        }
    }
}

impl FitCmd {
    /// What `modellint fit` runs ([`crate::fit::cmd::run_fit`]); the Python API parses its
    /// options with these same flags.
    pub fn into_args(self) -> crate::fit::cmd::FitArgs {
        let f = self;
        crate::fit::cmd::FitArgs {
            holdout_by: match (&f.servo, &f.holdout_by) {
                (Some(_), None) => {
                    eprintln!(
                        "modellint: note: --servo is deprecated; it means --holdout-by kp (every \
                     firmware gain held out in turn)"
                    );
                    Some("kp".to_string())
                }
                _ => f.holdout_by,
            },
            model: f.model,
            recordings: f.recordings,
            spec: f.spec,
            effects: f.effects,
            joints: f.joints,
            told: f.told,
            holdout: f.holdout,
            window: f.window,
            start_estimate: f.start_estimate,
            parse: f.replay.parse_options(),
            replay: f.replay.options(),
            quiet: f.quiet,
            json: f.format == ResultFormat::Json,
            write_model: f.write_model,
            write_actuators: f.write_actuators,
            report: f.report,
        }
    }
}

/// How `gap` and `fit` replay the recordings.
#[derive(Args, Debug)]
pub struct ReplayArgs {
    /// Control rate [Hz] of the robot's controller: one command per tick at
    /// control_t0_s + k/rate, taken from the rows inside that tick (without control_t0_s the
    /// ticks' phase is found from where the command changes between rows). Default: the
    /// recording's `control_rate_hz`; without one, each goal is held from its own timestamp.
    #[arg(long)]
    pub control_hz: Option<f64>,
    /// What a row's q_cmd is: `in-force` (the command in force at the row's time, the usual
    /// logger) or `sent-after` (the command sent right after the sample). Default: the
    /// recording's `command_timing` key, else in-force. See `modellint docs recording-format`.
    #[arg(long, value_parser = ["in-force", "sent-after"])]
    pub command_timing: Option<String>,
    /// Floating base: fixed (pinned), recorded (driven from base.* columns) or free.
    #[arg(long, default_value = "fixed", value_parser = ["fixed", "recorded", "free"])]
    pub base: String,
    /// CSV columns to skip, as glob patterns on the header name (comma-separated or repeated),
    /// e.g. `--ignore-columns 'imu.*,*.temperature'`: a log's extra signals. Without it any
    /// column that is not t, base.* or <joint>.<q|qd|q_cmd|tau|kp|kd|enabled> is an error.
    #[arg(long, value_delimiter = ',', value_name = "GLOB")]
    pub ignore_columns: Vec<String>,
    /// Joints (glob patterns on joint names, comma-separated or repeated) that an actuator of
    /// the model drives but that are recorded without their <joint>.q_cmd column (BAM: without
    /// `goal_position`): replayed following their recorded positions as their command, and left
    /// out of the scores and of the fit, with a note (a warning names the scored joints in
    /// the same kinematic chain: they feel the left-out joint's servo lag). Without it such a
    /// joint is an error at the header line: its positions would be taken for the command. A
    /// joint no actuator drives (a passive joint) needs no command and no flag.
    #[arg(long, value_delimiter = ',', value_name = "JOINT")]
    pub no_command: Vec<String>,
    #[command(flatten)]
    pub log: crate::cli_logs::LogArgs,
}

impl ReplayArgs {
    /// How the recordings are read (`--ignore-columns`, `--no-command`).
    pub fn parse_options(&self) -> crate::sim2real::recording::ParseOptions {
        crate::sim2real::recording::ParseOptions {
            ignore_columns: self.ignore_columns.clone(),
            no_command: self.no_command.clone(),
            log_map: self.log.to_map(),
            ..Default::default()
        }
    }
    /// The replay options these flags ask for.
    pub fn options(&self) -> crate::sim2real::replay::ReplayOptions {
        use crate::sim2real::replay::BaseMode;
        crate::sim2real::replay::ReplayOptions {
            control_hz: self.control_hz,
            command_timing: self
                .command_timing
                .as_deref()
                .and_then(crate::sim2real::commands::CommandTiming::parse),
            base: match self.base.as_str() {
                "recorded" => BaseMode::Recorded,
                "free" => BaseMode::Free,
                _ => BaseMode::Fixed,
            },
            ..Default::default()
        }
    }
}

fn parse_mb(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("`{s}` is not a size in megabytes (a number ≥ 0)")),
    }
}

fn use_color(choice: &str) -> bool {
    match choice {
        "always" => true,
        "never" => false,
        _ => std::io::stdout().is_terminal() && std::env::var_os("NO_COLOR").is_none(),
    }
}

impl Cli {
    /// The `--package NAME=DIR` mappings of the command run (only a model's loaders take them).
    pub fn packages(&self) -> Vec<(String, std::path::PathBuf)> {
        let p = match &self.cmd {
            None => &self.check.packages,
            Some(Cmd::InitSpec { packages, .. }) => packages,
            Some(Cmd::Gap(g)) => &g.packages,
            Some(Cmd::Fit(f)) => &f.packages,
            Some(Cmd::Synth(s)) => &s.packages,
            Some(_) => return Vec::new(),
        };
        p.package.clone()
    }
}

pub fn run() -> i32 {
    crate::model::mj::silence_warnings();
    let cli = Cli::parse();
    crate::output::set_color_choice(&cli.check.color);
    crate::model::urdf_packages::set_packages(cli.packages());
    match cli.cmd {
        Some(Cmd::Rules) => {
            let mut out = String::new();
            for m in crate::rules::all_meta() {
                out.push_str(&format!(
                    "{:<28} {:<10} {:<8} {}\n",
                    m.id,
                    m.group,
                    m.default_level.as_str(),
                    m.probe.map(|p| format!("probe: {p}")).unwrap_or_default()
                ));
            }
            print!("{out}");
            0
        }
        Some(Cmd::Rule { id }) => match crate::rules::find_meta(&id) {
            Some(m) => {
                print!("{}", crate::rules::doc_page(m));
                0
            }
            None => {
                let ids: Vec<String> =
                    crate::rules::all_meta().iter().map(|m| m.id.to_string()).collect();
                let near = crate::util::near_matches(&id, &ids);
                if near.is_empty() {
                    eprintln!(
                        "modellint: no rule `{id}`, and no rule id is close to it; `modellint rules` lists them all"
                    );
                } else {
                    eprintln!("modellint: no rule `{id}`; did you mean: {}?", near.join(", "));
                }
                2
            }
        },
        Some(Cmd::GenDocs { out, check }) => crate::rules::gen_docs(&out, check),
        Some(Cmd::Cache { action: CacheCmd::Clean { dir } }) => {
            match dir.or_else(crate::model::cache::default_dir) {
                Some(d) => {
                    let (n, bytes) = crate::model::cache::clean(&d);
                    println!(
                        "modellint: removed {n} cache entr{} ({:.1} MB) from {}",
                        if n == 1 { "y" } else { "ies" },
                        bytes as f64 / 1048576.0,
                        d.display()
                    );
                    0
                }
                None => {
                    eprintln!("modellint: no cache directory (set --dir or $MODELLINT_CACHE_DIR)");
                    2
                }
            }
        }
        Some(Cmd::InitSpec { model, output, force, .. }) => {
            crate::spec_init::run(&model, output.as_deref(), force)
        }
        Some(Cmd::Gap(g)) => crate::sim2real::cmd::run_gap(g.into_args()),
        Some(Cmd::Fit(f)) => crate::fit::cmd::run_fit(f.into_args()),
        Some(Cmd::Synth(s)) => crate::synth::cmd::run(s),
        Some(Cmd::Convert { input, output, log }) => {
            crate::sim2real::cmd::run_convert(&input, &output, &log.to_map())
        }
        Some(Cmd::Docs { topic }) => crate::cli_logs::docs(topic.as_deref()),
        None => check(cli.check),
    }
}

fn check(a: CheckArgs) -> i32 {
    // Among several paths, or as the hook runs: a staged spec stands for its model. Alone, a
    // spec given as the model is the error that says how to pass it (--spec).
    let (models, notes) = if a.models.len() > 1 || a.skip_non_models {
        crate::spec_use::models_for_args(&a.models)
    } else {
        (a.models.clone(), Vec::new())
    };
    eprint!("{}", notes.concat());
    let a = CheckArgs { models, ..a };
    let color = use_color(&a.color);
    let err_color = color && std::io::stderr().is_terminal();
    if a.models.is_empty() {
        eprintln!(
            "modellint: no model given. Usage: modellint <MODEL.xml>... [--spec SPEC.toml]; see --help"
        );
        return 2;
    }
    let format = a.format.unwrap_or_else(|| {
        if std::env::var("GITHUB_ACTIONS").is_ok_and(|v| v == "true") {
            Format::Github
        } else {
            Format::Text
        }
    });
    if let Some(mb) = a.cache_max {
        crate::model::cache::set_max_mb(mb);
    }
    let cache_dir = if a.no_cache {
        None
    } else {
        a.cache_dir.clone().or_else(crate::model::cache::default_dir)
    };
    // Everything else that shapes what is printed joins the key of the lint cache.
    let opts = vec![format!(
        "{format:?} {color} {err_color} {} {} {:?} {:?} {:?} {} {:?} {}",
        crate::output::color_on_stderr(),
        a.statistics,
        a.fail_on,
        a.select,
        a.ignore,
        a.no_probe,
        a.packages.package,
        a.skip_non_models
    )];
    let key = cache_dir
        .as_ref()
        .and_then(|_| crate::lint_cache::key(&a.models, &a.spec, &a.config, &opts));
    let hit =
        cache_dir.as_deref().zip(key.as_deref()).and_then(|(d, k)| crate::lint_cache::load(d, k));
    let run = hit.unwrap_or_else(|| {
        let run = check_models(&a, format, color, err_color);
        if let (Some(d), Some(k)) = (&cache_dir, &key) {
            crate::lint_cache::store(d, k, &run);
        }
        run
    });
    eprint!("{}", run.stderr);
    if std::io::stdout().lock().write_all(run.stdout.as_bytes()).is_err() {
        return 2;
    }
    run.code
}

/// Lints every model: what `check` prints (stdout, stderr) and its exit code.
fn check_models(
    a: &CheckArgs,
    format: Format,
    color: bool,
    err_color: bool,
) -> crate::lint_cache::Entry {
    let multi = a.models.len() > 1;
    let cli_fail_on = a.fail_on.as_deref().and_then(Severity::parse);
    let mut err = String::new();
    let mut runs = Vec::new();
    let mut skipped = Vec::new();
    let mut errors = Vec::new();
    let mut code = 0;
    // A scene and the robot file it includes, both given: the robot is linted once, inside the
    // scene (which has the floor and the spec search of both).
    let canon = |p: &std::path::Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let included: Vec<(PathBuf, PathBuf)> = if multi {
        a.models
            .iter()
            .flat_map(|m| {
                crate::spec_use::includes(m).into_iter().map(move |i| (canon(&i), m.clone()))
            })
            .collect()
    } else {
        Vec::new()
    };
    let mut seen_models: Vec<PathBuf> = Vec::new();
    for model in &a.models {
        let c = canon(model);
        if seen_models.contains(&c) {
            continue;
        }
        seen_models.push(c.clone());
        if let Some((_, by)) = included.iter().find(|(i, by)| *i == c && canon(by) != c) {
            let why = format!("included by {} (linted there)", by.display());
            err.push_str(&format!("modellint: skipping {}: {why}\n", model.display()));
            skipped.push(output::NotLinted::skipped(model, why));
            continue;
        }
        if (multi || a.skip_non_models)
            && let Some(why) = crate::lint::not_a_model(model)
        {
            err.push_str(&format!("modellint: skipping {}: {why}\n", model.display()));
            skipped.push(output::NotLinted::skipped(model, why));
            continue;
        }
        let input = LintInput {
            model: model.clone(),
            spec: a.spec.clone(),
            config: a.config.clone(),
            select: a.select.clone(),
            ignore: a.ignore.clone(),
        };
        let loaded = match crate::lint::load(&input) {
            Ok(l) => l,
            Err(e) => {
                err.push_str(&output::text::render_error(&e, err_color));
                errors.push(output::NotLinted::from_error(model, &e));
                code = 2;
                continue;
            }
        };
        if let Some(note) = crate::lint::missing_spec_note(&loaded) {
            err.push_str(&note);
        }
        let findings = lint(&loaded, !a.no_probe);
        let fail_on = cli_fail_on.or(loaded.config.fail_on).unwrap_or(Severity::Error);
        code = code.max(exit_code(&findings, fail_on));
        runs.push((model.display().to_string(), loaded, findings));
    }
    // Two scenes that include one robot file report its findings once: a finding of one rule at
    // one place with one message is kept the first time only.
    let mut seen_findings = std::collections::BTreeSet::new();
    for (_, l, fs) in runs.iter_mut() {
        crate::lint::drop_repeated(&mut seen_findings, l, fs);
    }
    let reports: Vec<output::Report> = runs
        .iter()
        .map(|(m, l, f)| output::Report {
            model: m.clone(),
            sources: &l.sources,
            findings: f,
            spec: Some(crate::lint::spec_info(l)),
        })
        .collect();
    let text = if multi {
        output::render_many(format, &reports, &skipped, &errors, color)
    } else {
        match reports.first() {
            Some(r) if format == Format::Json => {
                output::json::render(r.sources, &r.model, r.findings, r.spec.as_ref())
            }
            Some(r) => output::render(format, r.sources, &r.model, r.findings, color),
            None => String::new(),
        }
    };
    let mut text = text;
    if a.statistics {
        let all: Vec<&crate::finding::Finding> =
            reports.iter().flat_map(|r| r.findings.iter()).collect();
        let stats = output::statistics(&all);
        if matches!(format, Format::Json | Format::Sarif) {
            err.push_str(&stats);
        } else {
            text.push_str(&stats);
        }
    }
    crate::lint_cache::Entry { stdout: text, stderr: err, code }
}
