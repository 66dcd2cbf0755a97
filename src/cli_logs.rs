//! Command-line flags shared by `gap`, `fit` and `convert` for logs of other formats (NumPy
//! `.npz`, LeRobot parquet, MCAP), and `modellint docs TOPIC`. Thin: flags → [`LogMap`].

use std::path::PathBuf;

use clap::Args;

use crate::sim2real::recording::LogMap;

/// `--package NAME=DIR`, on the commands that load a model (the lint, `init-spec`, `gap`, `fit`,
/// `synth`); the others do not take it.
#[derive(Args, Debug, Clone, Default)]
pub struct PackageArgs {
    /// URDF `package://NAME/...` meshes: the directory of package NAME (repeatable; before
    /// ROS_PACKAGE_PATH).
    #[arg(long, value_name = "NAME=DIR", value_parser = crate::model::urdf_packages::parse_package_arg)]
    pub package: Vec<(String, PathBuf)>,
}

/// How a log that is not modellint's CSV maps onto the model's joints. Each flag overrides the
/// same key of the --log-map file. See `modellint docs recording-format`.
#[derive(Args, Debug, Clone, Default)]
pub struct LogArgs {
    /// TOML file mapping a log's signals onto joints (keys: measured, command, velocity,
    /// effort, time, dt, time_unit, joints, command_joints, skip, units, control_rate_hz,
    /// command_timing, episode, [rename]); a CSV of other column names too (`measured = "q"`
    /// reads q_<joint> / <joint>_q columns, `pos` with `joints` reads pos_0, pos_1, …).
    #[arg(long, value_name = "FILE.toml")]
    pub log_map: Option<PathBuf>,
    /// Array / column / topic of the measured joint positions (default by format: dof_pos,
    /// observation.state, /joint_states).
    #[arg(long, value_name = "KEY")]
    pub log_measured: Option<String>,
    /// Array / column / topic of the position command (default by format: des_dof_pos,
    /// action, a JointState or Float64MultiArray topic named *command*/*cmd*/*target*).
    #[arg(long, value_name = "KEY")]
    pub log_command: Option<String>,
    /// Array / column of the time stamps (MCAP: `log` or `header`).
    #[arg(long, value_name = "KEY")]
    pub log_time: Option<String>,
    /// Sample interval [s] of a log without time stamps.
    #[arg(long, value_name = "SECONDS")]
    pub log_dt: Option<f64>,
    /// The model's joint names of the arrays' columns, in order (comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "JOINT")]
    pub log_joints: Option<Vec<String>>,
    /// Unit of the log's positions and commands: rad (default) or deg (velocities deg/s).
    #[arg(long, value_name = "rad|deg")]
    pub log_units: Option<String>,
    /// Read only this episode of a LeRobot file (its episode_index).
    #[arg(long, value_name = "N")]
    pub log_episode: Option<i64>,
}

impl LogArgs {
    pub fn to_map(&self) -> LogMap {
        LogMap {
            file: self.log_map.clone(),
            measured: self.log_measured.clone(),
            command: self.log_command.clone(),
            time: self.log_time.clone(),
            dt: self.log_dt,
            joints: self.log_joints.clone(),
            units: self.log_units.clone(),
            episode: self.log_episode,
            ..Default::default()
        }
    }
}

/// The documentation pages shipped inside the binary: `modellint docs TOPIC`.
pub const DOCS: &[(&str, &str)] = &[
    ("architecture", include_str!("../docs/architecture.md")),
    ("audit", include_str!("../docs/audit.md")),
    ("ci", include_str!("../docs/ci.md")),
    ("conceal-benchmark", include_str!("../docs/conceal-benchmark.md")),
    ("fitting", include_str!("../docs/fitting.md")),
    ("gap", include_str!("../docs/gap.md")),
    ("probes", include_str!("../docs/probes.md")),
    ("python", include_str!("../docs/python.md")),
    ("recording-format", include_str!("../docs/recording-format.md")),
    ("spec", include_str!("../docs/spec.md")),
    ("synth", include_str!("../docs/synth.md")),
];

/// `modellint docs [TOPIC]`: the page on stdout (0), the list of topics without one (0), an
/// unknown topic with the nearest (2).
pub fn docs(topic: Option<&str>) -> i32 {
    let list = || DOCS.iter().map(|(t, _)| *t).collect::<Vec<_>>().join(", ");
    let Some(topic) = topic else {
        println!("modellint docs TOPIC — topics: {}", list());
        println!("(a rule's page: modellint rule ID)");
        return 0;
    };
    let topic = topic.trim_end_matches(".md").trim_start_matches("docs/");
    match DOCS.iter().find(|(t, _)| *t == topic) {
        Some((_, text)) => {
            print!("{text}");
            0
        }
        None => {
            let names: Vec<String> = DOCS.iter().map(|(t, _)| t.to_string()).collect();
            let near = crate::util::near_matches(topic, &names);
            if crate::rules::find_meta(topic).is_some() {
                eprintln!("modellint: `{topic}` is a rule: modellint rule {topic}");
            } else if near.is_empty() {
                eprintln!("modellint: no docs topic `{topic}`; topics: {}", list());
            } else {
                eprintln!("modellint: no docs topic `{topic}`; did you mean: {}?", near.join(", "));
            }
            2
        }
    }
}
