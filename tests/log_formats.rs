//! Readers of real log formats, each on files written in the test by the format's own Python
//! library (tests/py/write_logs.py: numpy, pyarrow, mcap + mcap-ros2-support; PyTorch files,
//! written by the same script with torch, are committed under fixtures/pt), from a
//! `modellint synth` dataset read there with Python's csv module. Each format must give the
//! same `gap` (and `fit`) as the equivalent CSV the same script writes. Skips visibly when
//! python3 or the library is missing (`scripts/setup-py-fixtures.sh` installs them into
//! target/pyfixtures; `$MODELLINT_FIXTURE_PYTHON` names another interpreter).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_modellint")
}

fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("MODELLINT_FIXTURE_PYTHON") {
        return PathBuf::from(p);
    }
    let venv = root().join("target/pyfixtures/bin/python");
    if venv.is_file() { venv } else { PathBuf::from("python3") }
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("modellint-logs-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn model() -> PathBuf {
    root().join("fixtures/gap/arm3.xml")
}

/// A synth dataset of arm3 with a hidden elbow damping (3 episodes of 3 s).
fn synth(dir: &Path) -> PathBuf {
    let ds = dir.join("ds");
    let o = Command::new(bin())
        .args(["synth", model().to_str().unwrap(), "--effects", "viscous_damping@elbow*=0.3"])
        .args(["--episodes", "3", "--duration", "3", "--out"])
        .arg(&ds)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    ds
}

/// Runs the Python writer; `false` (with a visible skip) when python3 or the library is missing.
fn write_logs(fmt: &str, ds: &Path, out: &Path) -> bool {
    let script = root().join("tests/py/write_logs.py");
    let o = match Command::new(python()).arg(&script).args([fmt]).arg(ds).arg(out).output() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("skipping {fmt}: cannot run {}: {e}", python().display());
            return false;
        }
    };
    if o.status.code() == Some(3) {
        eprintln!(
            "skipping {fmt}: {} (run scripts/setup-py-fixtures.sh)",
            String::from_utf8_lossy(&o.stderr).trim()
        );
        return false;
    }
    assert!(o.status.success(), "write_logs.py {fmt}: {}", String::from_utf8_lossy(&o.stderr));
    true
}

fn run(args: &[&str]) -> Output {
    Command::new(bin()).args(args).output().unwrap()
}

fn json_of(o: &Output) -> Value {
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// Equal JSON but for file names (strings naming a source), numbers within `rel`.
fn same(a: &Value, b: &Value, rel: f64, at: &str) {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!((x - y).abs() <= rel * x.abs().max(y.abs()).max(1e-9), "{at}: {x} vs {y}");
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}: lengths");
            for (i, (p, q)) in x.iter().zip(y).enumerate() {
                same(p, q, rel, &format!("{at}[{i}]"));
            }
        }
        (Value::Object(x), Value::Object(y)) => {
            for (k, v) in x {
                if ["file", "files", "source", "episode", "notes", "warnings"].contains(&k.as_str())
                {
                    continue;
                }
                let w = y.get(k).unwrap_or_else(|| panic!("{at}.{k} missing"));
                same(v, w, rel, &format!("{at}.{k}"));
            }
        }
        _ => assert_eq!(a, b, "{at}"),
    }
}

fn gap(inputs: &[&Path], extra: &[&str]) -> Value {
    let m = model();
    let mut args = vec!["gap", m.to_str().unwrap()];
    args.extend(inputs.iter().map(|p| p.to_str().unwrap()));
    args.extend(["--format", "json"]);
    args.extend(extra);
    json_of(&run(&args))
}

fn fit(inputs: &[&Path], extra: &[&str]) -> Value {
    let m = model();
    let mut args = vec!["fit", m.to_str().unwrap()];
    args.extend(inputs.iter().map(|p| p.to_str().unwrap()));
    args.extend(["--format", "json", "--quiet", "--effects", "viscous_damping,armature"]);
    args.extend(extra);
    json_of(&run(&args))
}

/// The fitted elbow damping of a fit's JSON.
fn damping(v: &Value) -> f64 {
    let mp = &v["missing_physics"][0];
    assert_eq!(mp["effect"], "viscous_damping", "{v:#}");
    mp["params"].as_object().unwrap().values().next().unwrap().as_f64().unwrap()
}

/// NumPy `.npz` of `dof_pos` / `des_dof_pos` / `dof_vel` in degrees with `t` and
/// `joint_names` (numpy.savez): `--log-units deg` gives the CSV's gap and fit.
#[test]
fn npz_in_degrees_gives_the_csv_gap_and_fit() {
    let dir = tmp("npz");
    let ds = synth(&dir);
    let out = dir.join("out");
    if !write_logs("npz", &ds, &out) {
        return;
    }
    let csv = out.join("csv");
    let npz = out.join("npz");
    let a = gap(&[&csv], &[]);
    // The rate from the file's scalar `control_rate_hz`.
    let b = gap(&[&npz], &["--log-units", "deg"]);
    same(&a, &b, 1e-9, "gap");
    let fa = fit(&[&csv], &[]);
    let fb = fit(&[&npz], &["--log-units", "deg", "--control-hz", "100"]);
    let (da, db) = (damping(&fa), damping(&fb));
    assert!((da - 0.3).abs() < 0.06, "csv fit {da}");
    assert!((da - db).abs() <= 1e-6 * da, "npz fit {db} vs csv {da}");
    // Without the unit the degrees are refused, never read as radians.
    let o = run(&["gap", model().to_str().unwrap(), npz.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("looks like degrees"), "{err}");
    // convert writes the CSV the other commands read.
    let conv = dir.join("ep_00.csv");
    let o = run(&[
        "convert",
        npz.join("ep_00.npz").to_str().unwrap(),
        conv.to_str().unwrap(),
        "--log-units",
        "deg",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let c = gap(&[&conv], &["--control-hz", "100"]);
    let d = gap(&[&csv.join("ep_00.csv")], &[]);
    same(&d, &c, 1e-9, "convert");
    let _ = std::fs::remove_dir_all(&dir);
}

/// PyTorch `.pt` dicts written by torch.save (fixtures/pt/arm3_damping, committed: torch is too
/// large for CI): a strided `dof_pos`, a list of per-row tensors as `des_dof_pos`, names and
/// rate in the dict. The directory of .pt files gives the gap and the fit of the equivalent CSV
/// the same script wrote, and the concealed elbow damping is recovered.
#[test]
fn pt_dicts_give_the_csv_gap_and_fit() {
    let fx = root().join("fixtures/pt/arm3_damping");
    let (csv, pt) = (fx.join("csv"), fx.join("pt"));
    same(&gap(&[&csv], &[]), &gap(&[&pt], &[]), 1e-12, "gap");
    let (fa, fb) = (fit(&[&csv], &[]), fit(&[&pt], &[]));
    let (da, db) = (damping(&fa), damping(&fb));
    assert!((da - 0.3).abs() < 0.06, "csv fit {da}");
    assert_eq!(da, db, "pt fit vs csv fit");
    for k in ["missing_physics", "before", "after"] {
        same(&fa[k], &fb[k], 1e-12, k);
    }
    // The mapping flags apply as to an .npz: the command named by key.
    let o = run(&[
        "gap",
        model().to_str().unwrap(),
        pt.join("ep_00.pt").to_str().unwrap(),
        "--log-command",
        "q_target",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("no array 'q_target'") && err.contains("des_dof_pos"), "{err}");
}

/// A LeRobot dataset (pyarrow: every episode in one parquet file, meta/info.json with fps and
/// joint names): a --log-map TOML renames the joints and says the action is the command in
/// force; the dataset directory gives the CSV's gap and fit.
#[test]
fn lerobot_dataset_gives_the_csv_gap_and_fit() {
    let dir = tmp("lerobot");
    let ds = synth(&dir);
    let out = dir.join("out");
    if !write_logs("lerobot", &ds, &out) {
        return;
    }
    let map = dir.join("map.toml");
    std::fs::write(
        &map,
        "command_timing = \"in_force\"\n[rename]\nmain_shoulder_pitch = \"shoulder_pitch\"\n\
         main_elbow_pitch = \"elbow_pitch\"\nmain_wrist_pitch = \"wrist_pitch\"\n",
    )
    .unwrap();
    let csv = out.join("csv");
    let lr = out.join("lerobot");
    let flag = ["--log-map", map.to_str().unwrap()];
    let a = gap(&[&csv], &[]);
    let b = gap(&[&lr], &flag);
    same(&a, &b, 1e-9, "gap");
    let (da, db) = (damping(&fit(&[&csv], &[])), damping(&fit(&[&lr], &flag)));
    assert!((da - 0.3).abs() < 0.06 && (da - db).abs() <= 1e-6 * da, "{da} vs {db}");
    // Without the renames: the log's names are not the model's, and the message says how.
    let o = run(&["gap", model().to_str().unwrap(), lr.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("main_elbow_pitch") && err.contains("rename"), "{err}");
    // One episode by its index.
    let one = gap(&[&lr], &["--log-map", map.to_str().unwrap(), "--log-episode", "1"]);
    let c = gap(&[&csv.join("ep_01.csv")], &[]);
    same(&c, &one, 1e-9, "episode 1");
    let _ = std::fs::remove_dir_all(&dir);
}

/// LeRobot's own time stamps are float32 (frame_index / fps): a recorder on the control ticks
/// (synth --log-at-ticks, ticks from 0), its stamps stored as float32, gives the CSV's gap (each
/// stamp put back on the fps grid; a float32 a rounding before a tick edge would take the
/// previous tick's command).
#[test]
fn lerobot_float32_stamps_on_the_fps_grid() {
    let dir = tmp("lerobot32");
    let ds = dir.join("ds");
    let o = Command::new(bin())
        .args(["synth", model().to_str().unwrap(), "--log-at-ticks", "--control-phase", "0"])
        .args(["--episodes", "2", "--duration", "3", "--out"])
        .arg(&ds)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.join("out");
    if !write_logs("lerobot32", &ds, &out) {
        return;
    }
    let map = dir.join("map.toml");
    std::fs::write(
        &map,
        "command_timing = \"in_force\"\n[rename]\nmain_shoulder_pitch = \"shoulder_pitch\"\n\
         main_elbow_pitch = \"elbow_pitch\"\nmain_wrist_pitch = \"wrist_pitch\"\n",
    )
    .unwrap();
    let a = gap(&[&out.join("csv")], &[]);
    let b = gap(&[&out.join("lerobot")], &["--log-map", map.to_str().unwrap()]);
    same(&a, &b, 1e-12, "gap");
    let _ = std::fs::remove_dir_all(&dir);
}

/// MCAP written by mcap-ros2-support: /joint_states (JointState per recorded row) and a
/// Float64MultiArray command per control tick, stamped from 1.7·10⁹ s. With the control rate
/// in the mapping, the command in force at each row and the ticks' origin come from the
/// command stamps: the CSV's gap and fit.
#[test]
fn mcap_joint_states_and_commands_give_the_csv_gap_and_fit() {
    let dir = tmp("mcap");
    let ds = synth(&dir);
    let out = dir.join("out");
    if !write_logs("mcap", &ds, &out) {
        return;
    }
    let map = dir.join("map.toml");
    std::fs::write(&map, "control_rate_hz = 100\n").unwrap();
    let csv = out.join("csv");
    let mc = out.join("mcap");
    let flag = ["--log-map", map.to_str().unwrap()];
    let a = gap(&[&csv], &[]);
    let b = gap(&[&mc], &flag);
    same(&a, &b, 1e-9, "gap");
    let (da, db) = (damping(&fit(&[&csv], &[])), damping(&fit(&[&mc], &flag)));
    assert!((da - 0.3).abs() < 0.06 && (da - db).abs() <= 1e-6 * da, "{da} vs {db}");
    // A command topic that is not there is named, with the topics the file has.
    let o = run(&[
        "gap",
        model().to_str().unwrap(),
        mc.join("ep_00.mcap").to_str().unwrap(),
        "--log-command",
        "/cmd",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("no topic '/cmd'") && err.contains("/joint_states"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The rows of a CSV with every `.q`/`.q_cmd` in degrees and `.qd` in deg/s, and a
/// `# units: deg, deg/s` header (plain string handling, not modellint's reader).
fn in_degrees(csv: &str) -> String {
    let mut out = String::from("# units: deg, deg/s\n");
    let mut header: Vec<String> = Vec::new();
    for line in csv.lines() {
        if line.starts_with("# units:") {
            continue;
        }
        if line.starts_with('#') {
            out.push_str(line);
            out.push('\n');
            continue;
        }
        if header.is_empty() {
            header = line.split(',').map(str::to_string).collect();
            out.push_str(line);
            out.push('\n');
            continue;
        }
        let vals: Vec<String> = line
            .split(',')
            .zip(&header)
            .map(|(v, h)| {
                let x: f64 = v.parse().unwrap();
                if h == "t" { v.to_string() } else { format!("{}", x.to_degrees()) }
            })
            .collect();
        out.push_str(&vals.join(","));
        out.push('\n');
    }
    out
}

/// `# units: deg, deg/s` is honoured (the same gap as in radians); an unknown unit and any
/// other unit key are errors at their line.
#[test]
fn csv_unit_declarations_are_honoured() {
    let dir = tmp("units");
    let ds = synth(&dir);
    let rad = ds.join("episodes/ep_00.csv");
    let deg = dir.join("deg.csv");
    std::fs::write(&deg, in_degrees(&std::fs::read_to_string(&rad).unwrap())).unwrap();
    same(&gap(&[&rad], &[]), &gap(&[&deg], &[]), 1e-9, "degrees");
    // --log-units on a CSV that declares its units: two declarations, an error.
    let o = run(&["gap", model().to_str().unwrap(), rad.to_str().unwrap(), "--log-units", "deg"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.code() == Some(2) && err.contains("# units: deg, deg/s"), "{err}");
    let text = std::fs::read_to_string(&deg).unwrap();
    for (bad, want) in [
        ("# units: deg, furlong/s\n", "unknown unit 'furlong/s'"),
        ("# units: mm\n", "applies to no column"),
        ("# units: elbow_pitch.qd=deg\n", "cannot be in deg"),
        ("# time_unit: ms\n", "metadata 'time_unit'"),
    ] {
        let f = dir.join("bad.csv");
        std::fs::write(&f, format!("{bad}{}", &text[text.find('\n').unwrap() + 1..])).unwrap();
        let o = run(&["gap", model().to_str().unwrap(), f.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(&format!("{}:1: ", f.display())) && err.contains(want), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Files of a kind modellint does not read, or JSON that is not a BAM log, are named as what
/// they are, never read as CSV.
#[test]
fn files_of_the_wrong_kind_are_named() {
    let dir = tmp("kinds");
    let ds = synth(&dir);
    let m = model();
    let gap_err = |f: &Path| {
        let o = run(&["gap", m.to_str().unwrap(), f.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let err = gap_err(&ds.join("truth.json"));
    assert!(err.contains("answer key") && err.contains("episodes/"), "{err}");
    assert!(!err.contains("--ignore-columns"), "{err}");
    let other = dir.join("other.json");
    std::fs::write(&other, r#"{"robot": "arm3", "joints": []}"#).unwrap();
    let err = gap_err(&other);
    assert!(err.contains("other.json is JSON with the keys joints, robot"), "{err}");
    assert!(err.contains("not a BAM servo log") && !err.contains("--ignore-columns"), "{err}");
    let bag = dir.join("run.bag");
    std::fs::write(&bag, b"#ROSBAG V2.0\n\0\0\0").unwrap();
    assert!(gap_err(&bag).contains("is a ROS 1 bag"));
    // A legacy-format torch.save file (fixtures/pt, written by torch) is named as such.
    let err = gap_err(&root().join("fixtures/pt/legacy.pt"));
    assert!(err.contains("legacy.pt is a PyTorch file of the legacy format"), "{err}");
    // A torch.save whose pickle calls numpy: the global is named, nothing is run.
    let err = gap_err(&root().join("fixtures/pt/numpy_inside.pt"));
    assert!(err.contains("PyTorch .pt") && err.contains("_reconstruct"), "{err}");
    // numpy.save (one array).
    let py = "import sys, numpy as np; np.save(sys.argv[1] + '/one.npy', np.zeros((4, 2)))";
    match Command::new(python()).args(["-c", py]).arg(&dir).output() {
        Ok(o) if o.status.success() => {
            let err = gap_err(&dir.join("one.npy"));
            assert!(err.contains("is a single NumPy array"), "{err}");
        }
        _ => eprintln!("skipping .npy: numpy not installed for {}", python().display()),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A recording with a command and no control rate is replayed with each goal held from its
/// row's time; `gap` and `fit` say so (stderr and JSON `warnings`), with the interval of the
/// command's changes, and stay silent once the rate is given or `control_rate_hz: none` is
/// declared. The CSVs are fixtures/pt/arm3_damping's with the rate line taken out by plain
/// string handling.
#[test]
fn a_log_without_control_rate_is_a_warning() {
    let dir = tmp("norate");
    let src = root().join("fixtures/pt/arm3_damping/csv");
    let (bare, none) = (dir.join("bare"), dir.join("none"));
    for d in [&bare, &none] {
        std::fs::create_dir_all(d).unwrap();
    }
    for ep in ["ep_00.csv", "ep_01.csv", "ep_02.csv"] {
        let text = std::fs::read_to_string(src.join(ep)).unwrap();
        assert!(text.starts_with("# control_rate_hz: 100\n"), "{ep}");
        let body = &text["# control_rate_hz: 100\n".len()..];
        std::fs::write(bare.join(ep), body).unwrap();
        std::fs::write(none.join(ep), format!("# control_rate_hz: none\n{body}")).unwrap();
    }
    let warned = |v: &Value| {
        v["warnings"].as_array().is_some_and(|w| {
            w.iter().any(|x| x.as_str().unwrap().contains("have a command but no control rate"))
        })
    };
    let m = model();
    let o = run(&["gap", m.to_str().unwrap(), bare.to_str().unwrap(), "--format", "json"]);
    let (v, err) = (json_of(&o), String::from_utf8_lossy(&o.stderr).into_owned());
    assert!(warned(&v), "{v:#}");
    assert!(err.contains("3 of 3 recordings have a command but no control rate"), "{err}");
    // The recorder's rows (≈ 87 Hz) are slower than the 100 Hz controller: the command changes
    // at nearly every row, every 11.5 ms (median).
    assert!(err.contains("changes every 11.5 ms") && err.contains("--control-hz"), "{err}");
    assert!(warned(&fit(&[&bare], &[])));
    // Given or declared: no warning.
    assert!(!warned(&gap(&[&bare], &["--control-hz", "100"])));
    assert!(!warned(&gap(&[&none], &[])));
    assert!(!warned(&gap(&[&src], &[])));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A CSV of other column names read through `--log-map` (the mapping the other formats take):
/// delay_arm2's recording rewritten by text here with a time in milliseconds under `time`,
/// `q_<joint>` / `<joint>_q` positions, `qd` velocities and `u` commands; then as numbered
/// `pos_<i>` / `target_<i>` columns named by `joints`. Each gives the gap of the CSV it was
/// rewritten from. A signal the file does not have is an error naming it, listing the file's
/// columns, with the closest.
#[test]
fn csv_of_other_column_names_through_a_log_map() {
    let dir = tmp("csvmap");
    let fx = root().join("fixtures/gap/delay_arm2");
    let arm = fx.join("arm.xml");
    let text = std::fs::read_to_string(fx.join("none_ep0.csv")).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('t'))
        .map(|l| l.split(',').collect())
        .collect();
    // Original columns: t, shoulder.q, shoulder.qd, shoulder.q_cmd, elbow.q, elbow.qd, elbow.q_cmd.
    let write = |name: &str, header: &str, cols: &[usize], ms: bool| -> PathBuf {
        let mut s = format!("{header}\n");
        for r in &rows {
            let t: f64 = r[0].parse().unwrap();
            let mut f = vec![if ms { format!("{:.3}", t * 1000.0) } else { r[0].to_string() }];
            f.extend(cols.iter().map(|&c| r[c].to_string()));
            s.push_str(&(f.join(",") + "\n"));
        }
        let p = dir.join(name);
        std::fs::write(&p, s).unwrap();
        p
    };
    let map = |name: &str, body: &str| -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, body).unwrap();
        p
    };
    let gap_of = |csv: &Path, extra: &[&str]| -> Value {
        let mut a = vec!["gap", arm.to_str().unwrap(), csv.to_str().unwrap(), "--format", "json"];
        a.extend(extra);
        json_of(&run(&a))
    };
    let reference = gap_of(&fx.join("none_ep0.csv"), &[]);
    let named = write(
        "named.csv",
        "time,q_shoulder,qd_shoulder,u_shoulder,elbow_q,elbow_qd,elbow_u",
        &[1, 2, 3, 4, 5, 6],
        true,
    );
    let m1 = map(
        "named.toml",
        "measured = \"q\"\nvelocity = \"qd\"\ncommand = \"u\"\ntime = \"time\"\ntime_unit = \"ms\"\ncontrol_rate_hz = 100\n",
    );
    let g = gap_of(&named, &["--log-map", m1.to_str().unwrap()]);
    same(&reference, &g, 1e-6, "named columns");
    // Numbered columns without velocities: the CSV without its .qd columns.
    let numbered = write("numbered.csv", "t,pos_0,pos_1,target_0,target_1", &[1, 4, 3, 6], false);
    let plain =
        write("plain.csv", "t,shoulder.q,elbow.q,shoulder.q_cmd,elbow.q_cmd", &[1, 4, 3, 6], false);
    let m2 = map(
        "numbered.toml",
        "measured = \"pos\"\ncommand = \"target\"\njoints = [\"shoulder\", \"elbow\"]\ncontrol_rate_hz = 100\n",
    );
    let a = gap_of(&plain, &["--control-hz", "100"]);
    let b = gap_of(&numbered, &["--log-map", m2.to_str().unwrap()]);
    same(&a, &b, 1e-12, "numbered columns");
    // The same by flags.
    let c = gap_of(
        &numbered,
        &[
            "--log-measured",
            "pos",
            "--log-command",
            "target",
            "--log-joints",
            "shoulder,elbow",
            "--control-hz",
            "100",
        ],
    );
    same(&a, &c, 1e-12, "numbered columns by flags");
    // A misspelt signal: named, with the file's columns and the closest.
    let o = run(&[
        "gap",
        arm.to_str().unwrap(),
        numbered.to_str().unwrap(),
        "--log-map",
        m2.to_str().unwrap(),
        "--log-command",
        "targt",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("numbered.csv:1"), "{err}");
    assert!(err.contains("no command column(s) 'targt'"), "{err}");
    assert!(err.contains("its columns: t, pos_0, pos_1, target_0, target_1"), "{err}");
    assert!(err.contains("did you mean 'target_0'"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
