use super::*;

fn p() -> &'static Path {
    Path::new("rec.csv")
}

const GOOD: &str = "# control_rate_hz: 100\r\n# robot: t1\r\n# plain comment\r\n\
    t, knee.q ,knee.q_cmd,knee.enabled,hip.q,hip.qd\r\n\
    0.0, 0.1, 0.2, 1, -0.5, 0.25\r\n\
    0.013,0.11,0.21,0,-0.4,1e-3\r\n\
    0.02,0.12,0.22,1,-0.3,0\r\n\r\n";

fn parse_err(text: &str) -> RecordingError {
    match parse_csv(p(), text) {
        Ok(r) => panic!("expected an error, parsed {r:?}"),
        Err(e) => e,
    }
}

#[test]
fn parses_crlf_metadata_spaces_and_trailing_blank() {
    let r = parse_csv(p(), GOOD).expect("parses");
    assert_eq!(r.control_rate_hz, Some(100.0));
    assert_eq!(r.meta.get("robot").map(String::as_str), Some("t1"));
    assert_eq!(r.meta.len(), 1);
    assert_eq!(r.t, vec![0.0, 0.013, 0.02]);
    assert_eq!(r.joints.len(), 2);
    let knee = r.joint("knee").expect("knee");
    assert_eq!(knee.q, vec![0.1, 0.11, 0.12]);
    assert_eq!(knee.q_cmd.as_deref(), Some(&[0.2, 0.21, 0.22][..]));
    assert_eq!(knee.enabled.as_deref(), Some(&[true, false, true][..]));
    assert!(knee.qd.is_none());
    assert_eq!(r.joint("hip").and_then(|h| h.qd.clone()), Some(vec![0.25, 1e-3, 0.0]));
    assert!((r.duration() - 0.02).abs() < 1e-15);
    assert!(r.base.is_none());
}

#[test]
fn round_trips_exactly() {
    let mut r = parse_csv(p(), GOOD).expect("parses");
    r.control_t0_s = Some(-0.0025);
    r.meta.insert("note".into(), "a: b, c".into());
    r.t = vec![0.0, 0.1 + 0.2, 1.0 / 3.0];
    r.joints[0].tau = Some(vec![1e-300, -2.5e-8, 123456.789]);
    r.joints[0].kp = Some(vec![75.0; 3]);
    r.joints[0].kd = Some(vec![5.0; 3]);
    r.base = Some(BaseTrace {
        pos: vec![[0.1, -0.2, 0.7]; 3],
        quat: vec![[1.0, 0.0, -0.0, std::f64::consts::FRAC_1_SQRT_2]; 3],
    });
    let text = write_csv(&r);
    let back = parse_csv(p(), &text).expect("re-parses");
    assert_eq!(back, r);
    assert_eq!(write_csv(&back), text);
}

#[test]
fn structural_errors() {
    let e = parse_err("");
    assert_eq!((e.line, e.message.as_str()), (Some(1), "empty file"));
    let e = parse_err("# a: b\n# c: d\n");
    assert_eq!(e.line, Some(2));
    assert!(e.message.contains("no header"), "{e}");
    assert!(parse_err("x.q\n1\n2\n").message.contains("no 't' column"));
    let e = parse_err("t,a.q,a.q\n0,1,1\n1,1,1\n");
    assert!(e.message.contains("duplicate column 'a.q'") && e.line == Some(1), "{e}");
    let e = parse_err("t,a.q,a.vel\n0,1,1\n1,1,1\n");
    assert!(
        e.message.contains("unknown suffix '.vel'") && e.column.as_deref() == Some("a.vel"),
        "{e}"
    );
    // A time stamp or a servo target under another name is told its name.
    let e = parse_err("time,a.q\n0,1\n1,1\n");
    assert!(e.message.contains("name it 't'"), "{e}");
    let e = parse_err("t,a.q,a.q_des\n0,1,1\n1,1,1\n");
    assert!(e.message.contains("name it 'a.q_cmd'"), "{e}");
    let e = parse_err("t,a.q,a.current\n0,1,1\n1,1,1\n");
    assert!(e.message.contains("an extra signal?") && !e.message.contains("q_cmd'"), "{e}");
    let e = parse_err("t,a.qd\n0,1\n1,1\n");
    assert!(e.message.contains("no 'a.q' column"), "{e}");
    let e = parse_err("t,a.q,base.x,base.y,base.z\n0,0,0,0,0\n1,0,0,0,0\n");
    assert!(e.message.contains("missing base.qw"), "{e}");
    let e = parse_err("t,a.q\n0,1\n");
    assert!(e.message.contains("at least 2") && e.line == Some(2), "{e}");
    assert!(parse_err("t,a.q\n").message.contains("found 0"));
    let e = parse_err("t,a.q\n0,1\n\n1,2\n");
    assert_eq!(e.line, Some(3));
}

#[test]
fn row_errors_name_the_line() {
    let e = parse_err("# k: v\nt,a.q,a.q_cmd\n0,1,1\n0.1,1\n");
    assert_eq!(e.line, Some(4));
    assert!(e.message.contains("truncated"), "{e}");
    assert_eq!(e.to_string(), "rec.csv:4: expected 3 fields, found 2 (truncated line?)");
    let e = parse_err("t,a.q\n0,1\n0.1,1.o\n");
    assert!(
        e.line == Some(3) && e.column.as_deref() == Some("a.q") && e.message.contains("'1.o'"),
        "{e}"
    );
    for bad in ["NaN", "inf", "-infinity"] {
        let e = parse_err(&format!("t,a.q\n0,1\n0.1,{bad}\n"));
        assert!(e.line == Some(3) && e.message.contains("non-finite"), "{e}");
    }
    let e = parse_err("t,a.q\n0,1\n0.2,1\n0.1,1\n");
    assert_eq!(e.line, Some(4));
    assert!(e.message.contains("t = 0.1 s at line 4 is not after t = 0.2 s at line 3"), "{e}");
    let e = parse_err("t,a.q\n0,1\n0,2\n");
    assert!(e.message.contains("not strictly increasing"), "{e}");
    // A row logged twice, character for character, is left out and counted; not when the
    // repeat is further back (the times then go backwards: an error).
    let ok = parse_csv(Path::new("rec.csv"), "t,a.q\n0,1\n0.1,2\n0.1,2\n0.2,3\n").unwrap();
    assert_eq!(ok.t, vec![0.0, 0.1, 0.2]);
    assert_eq!(ok.meta.get(super::KEY_DUPLICATE_ROWS).map(String::as_str), Some("1"));
    assert!(parse_csv(Path::new("rec.csv"), "t,a.q\n0,1\n0.1,2\n0,1\n").is_err());
    let clean = parse_csv(Path::new("rec.csv"), "t,a.q\n0,1\n0.1,2\n").unwrap();
    assert!(clean.meta.is_empty());
    let e = parse_err("t,a.q,a.enabled\n0,1,1\n0.1,1,2\n");
    assert!(e.message.contains("expected 0 or 1"), "{e}");
    let e = parse_err("t,a.q\n0,,\n");
    assert!(e.message.contains("expected 2 fields, found 3"), "{e}");
    let e = parse_err("t,a.q\n0,\n1,1\n");
    assert!(e.message.contains("empty field"), "{e}");
    let e = parse_err("# control_rate_hz: fast\nt,a.q\n0,1\n1,1\n");
    assert_eq!(e.line, Some(1));
}

#[test]
fn split_timing_and_one_tick_errors_name_the_line() {
    let e = parse_err("# robot: a\n# split: test\nt,a.q\n0,1\n1,1\n");
    assert_eq!(e.line, Some(2));
    assert!(e.message.contains("train") && e.message.contains("heldout"), "{}", e.message);
    let e = parse_err("# command_timing: later\nt,a.q\n0,1\n1,1\n");
    assert_eq!(e.line, Some(1));
    let e = parse_err("# x: 1\n# control_rate_hz: 0.5\nt,a.q\n0,1\n0.5,1\n1.9,1\n");
    assert_eq!(e.line, Some(2));
    assert!(e.message.contains("one control tick"), "{}", e.message);
    let e = parse_err("# control_rate_hz: -3\nt,a.q\n0,1\n1,1\n");
    assert_eq!(e.line, Some(1));
    let ok = parse_csv(
        p(),
        "# split: heldout\n# command_timing: sent_after\n# control_rate_hz: 1\nt,a.q\n0,1\n1,1\n",
    )
    .unwrap();
    assert_eq!(ok.split(), Some(Split::Heldout));
    assert_eq!(ok.command_timing(), Some(crate::sim2real::commands::CommandTiming::SentAfter));
}

#[test]
fn degrees_are_rejected_with_adjustable_threshold() {
    let text = "t,knee.q\n0,10\n0.01,45\n0.02,90\n";
    let e = parse_err(text);
    assert_eq!(e.line, Some(3));
    assert!(e.message.contains("looks like degrees"), "{e}");
    let ok = parse_csv_with(
        p(),
        text,
        &ParseOptions { max_abs_rad: f64::INFINITY, ..Default::default() },
    );
    assert!(ok.is_ok());
    let e = parse_err("t,knee.q,knee.q_cmd\n0,0,0\n0.01,0,-30\n");
    assert_eq!(e.column.as_deref(), Some("knee.q_cmd"));
}

#[test]
fn joint_name_validation_suggests_near_matches() {
    let r = parse_csv(p(), "t,Left_Knee_Pitc.q,Waist.q\n0,0,0\n1,0,0\n").expect("parses");
    let model: Vec<String> = ["Left_Knee_Pitch", "Right_Knee_Pitch", "Waist", "AAHead_yaw"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let e = r.validate_joint_names(&model).expect_err("unknown joint");
    assert!(
        e.message.contains("unknown joint 'Left_Knee_Pitc' (did you mean 'Left_Knee_Pitch'"),
        "{e}"
    );
    assert!(!e.message.contains("Waist"), "{e}");
    let r2 = parse_csv(p(), "t,waist.q,Zzz.q\n0,0,0\n1,0,0\n").expect("parses");
    let e = r2.validate_joint_names(&model).expect_err("unknown");
    assert!(e.message.contains("'waist' (did you mean 'Waist'?)"), "{e}");
    assert!(e.message.ends_with("unknown joint 'Zzz'"), "{e}");
    let r3 = parse_csv(p(), "t,Waist.q\n0,0\n1,0\n").expect("parses");
    assert!(r3.validate_joint_names(&model).is_ok());
}

/// A log's joint names as robot software writes them (a `_joint` suffix, CamelCase, `l_`/`r_`
/// for left/right, a name cut short) are matched to the model's; a name like none of them gets
/// no suggestion.
#[test]
fn joint_name_suggestions_see_through_naming_conventions() {
    let model: Vec<String> =
        ["shoulder_pitch", "elbow_pitch", "wrist_pitch", "left_knee", "right_knee"]
            .iter()
            .map(|s| s.to_string())
            .collect();
    let msg = |log: &str| {
        let r = parse_csv(p(), &format!("t,{log}.q\n0,0\n1,0\n")).expect("parses");
        r.validate_joint_names(&model).expect_err("unknown").message
    };
    for (log, want) in [
        ("Elbow_Pitch_joint", "(did you mean 'elbow_pitch'?)"),
        ("ElbowPitch", "(did you mean 'elbow_pitch'?)"),
        ("elbow", "(did you mean 'elbow_pitch'?)"),
        ("l_knee", "(did you mean 'left_knee'?)"),
        // Both knees contain `knee`: both are offered, the closer first.
        ("knee", "(did you mean 'left_knee', 'right_knee'?)"),
        ("gripper", "unknown joint 'gripper'"),
        // Too short to look inside other names.
        ("el", "unknown joint 'el'"),
    ] {
        let m = msg(log);
        assert!(m.ends_with(want), "{log}: {m}");
    }
}

#[test]
fn derived_velocities_exact_for_quadratic_on_irregular_grid() {
    let t = vec![0.0, 0.004, 0.011, 0.015, 0.022, 0.03];
    let q: Vec<f64> = t.iter().map(|&x| 1.0 + 2.0 * x - 3.0 * x * x).collect();
    let mut r = Recording {
        source: p().into(),
        meta: BTreeMap::new(),
        control_rate_hz: None,
        control_t0_s: None,
        t: t.clone(),
        joints: vec![JointTrace::new("a", q)],
        base: None,
    };
    let mut keep = JointTrace::new("b", vec![0.0; 6]);
    keep.qd = Some(vec![7.0; 6]);
    r.joints.push(keep);
    r.derive_velocities();
    let qd = r.joints[0].qd.as_ref().expect("derived");
    for i in 1..t.len() - 1 {
        assert!(
            (qd[i] - (2.0 - 6.0 * t[i])).abs() < 1e-9,
            "i={i} {} vs {}",
            qd[i],
            2.0 - 6.0 * t[i]
        );
    }
    assert!((qd[0] - (2.0 - 3.0 * 0.004)).abs() < 1e-9);
    assert_eq!(r.joints[1].qd, Some(vec![7.0; 6]));
}

#[test]
fn extra_columns_are_an_error_unless_ignored_by_pattern() {
    let text = "t,knee.q,imu.wx,knee.temperature,battery\n0,0.1,5,40,24\n0.01,0.2,6,41,x\n";
    // Unknown suffix / not a column name at all: an error naming the column and the way out.
    let e = parse_err(text);
    assert_eq!((e.line, e.column.as_deref()), (Some(1), Some("imu.wx")), "{e}");
    assert!(e.message.contains("--ignore-columns '*.wx'"), "{e}");
    let skip = |g: &[&str]| ParseOptions {
        ignore_columns: g.iter().map(|s| s.to_string()).collect(),
        ..Default::default()
    };
    let e = parse_csv_with(p(), text, &skip(&["imu.*", "*.temperature"])).unwrap_err();
    assert_eq!(e.column.as_deref(), Some("battery"), "{e}");
    assert!(e.message.contains("--ignore-columns 'battery'"), "{e}");
    // Skipped columns are not parsed (battery's 'x' is no error) and leave no joint behind.
    let r = parse_csv_with(p(), text, &skip(&["imu.*", "*.temperature", "battery"])).unwrap();
    assert_eq!(r.joints.len(), 1);
    assert_eq!((r.joints[0].name.as_str(), r.joints[0].q.clone()), ("knee", vec![0.1, 0.2]));
    // A pattern cannot hide the time column; a bad pattern is an error.
    let r = parse_csv_with(p(), text, &skip(&["*", "battery"])).unwrap_err();
    assert!(r.message.contains("no joint column"), "{r}");
    assert!(parse_csv_with(p(), text, &skip(&["a[", "battery"])).is_err());
}

/// With the model's joints given, a misspelt joint is reported at the header line, before its
/// values are checked (a log in degrees under a wrong name used to report the degrees first).
#[test]
fn unknown_joints_are_reported_at_the_header_before_any_value() {
    let text = "# robot: r\nt,shouldr.q,elbow.q\n0,57.3,0\n0.01,57.3,0\n";
    let model = vec!["shoulder".to_string(), "elbow".to_string()];
    let opts = ParseOptions { model_joints: Some(model.clone()), ..Default::default() };
    let e = parse_csv_with(p(), text, &opts).unwrap_err();
    assert_eq!((e.line, e.column.as_deref()), (Some(2), Some("shouldr.q")), "{e}");
    assert!(e.message.contains("unknown joint 'shouldr' (did you mean 'shoulder'?)"), "{e}");
    // Without the model's joints: the values are checked (degrees), the names later.
    assert!(parse_err(text).message.contains("looks like degrees"));
    let fixed = text.replace("shouldr", "shoulder").replace("57.3", "1");
    assert!(parse_csv_with(p(), &fixed, &opts).is_ok());
}

/// `# units:` converts to SI before the checks: bare units by column kind, patterns per column
/// (winning over a bare unit); all-SI declarations are left as they are.
#[test]
fn unit_declarations_convert_to_si() {
    let text = "# units: deg, deg/s, t=ms, hip.q=rad\nt,knee.q,knee.qd,knee.q_cmd,hip.q\n\
                0,90,180,45,0.5\n10,-90,0,0,0.25\n";
    let r = parse_csv(p(), text).expect("parses");
    let knee = r.joint("knee").unwrap();
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
    assert!(close(knee.q[0], std::f64::consts::FRAC_PI_2) && close(knee.q[1], -knee.q[0]));
    assert!(close(knee.qd.as_ref().unwrap()[0], std::f64::consts::PI));
    assert!(close(knee.q_cmd.as_ref().unwrap()[0], std::f64::consts::FRAC_PI_4));
    assert_eq!(r.joint("hip").unwrap().q, vec![0.5, 0.25]);
    assert!(close(r.t[1], 0.01));
    assert!(!r.meta.contains_key("units"));
    assert_eq!(
        r.meta.get("converted_from_units").map(String::as_str),
        Some("deg, deg/s, t=ms, hip.q=rad")
    );
    // Round trip: the written CSV is in SI, says so above the declaration it was converted
    // from (a reader took that `deg` for the unit of its radians), and reads back the same.
    let written = write_csv(&r);
    let said = "# values in SI units (rad, rad/s, s, N·m; m, m/s, N on a slide joint) - converted \
                on reading from the units below\n# converted_from_units: deg";
    assert!(written.contains(said), "{written}");
    let back = parse_csv(p(), &written).expect("re-parses");
    assert_eq!((&back.joints, &back.meta, &back.t), (&r.joints, &r.meta, &r.t));
    let si = parse_csv(p(), "# units: rad, rad/s\nt,a.q\n0,0.1\n1,0.2\n").unwrap();
    assert_eq!(si.meta.get("units").map(String::as_str), Some("rad, rad/s"));
    for (decl, want) in [
        ("furlong", "unknown unit 'furlong'"),
        ("a.q=rpm", "cannot be in rpm"),
        ("b.*=deg", "names no column"),
        ("m", "applies to no column"),
    ] {
        let e = parse_err(&format!("# robot: x\n# units: {decl}\nt,a.q\n0,0.1\n1,0.2\n"));
        assert_eq!(e.line, Some(2), "{e}");
        assert!(e.message.contains(want), "{decl}: {e}");
    }
    let e = parse_err("# time_unit: ms\nt,a.q\n0,0.1\n1,0.2\n");
    assert!(e.line == Some(1) && e.message.contains("one key"), "{e}");
}

/// A --log-map TOML: unknown keys at their line; flags override the file.
#[test]
fn log_map_files_and_flags() {
    let dir = std::env::temp_dir().join(format!("modellint-logmap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("map.toml");
    std::fs::write(&f, "units = \"deg\"\ncommand = \"a\"\n[rename]\nx = \"y\"\n").unwrap();
    let flags = LogMap { file: Some(f.clone()), command: Some("b".into()), ..Default::default() };
    let m = flags.resolve().unwrap();
    assert_eq!((m.units.as_deref(), m.command.as_deref()), (Some("deg"), Some("b")));
    assert_eq!(m.rename.get("x").map(String::as_str), Some("y"));
    std::fs::write(&f, "units = \"deg\"\n\ncomand = \"a\"\n").unwrap();
    let e = flags.resolve().unwrap_err();
    assert_eq!(e.line, Some(3), "{e}");
    assert!(e.message.contains("comand"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A file's kind comes from its first bytes; the kinds not read are named with what to do.
#[test]
fn kinds_by_magic_bytes() {
    let k = |name: &str, b: &[u8]| sniff(Path::new(name), b);
    assert_eq!(k("x.csv", b"t,a.q\n0,1\n"), Kind::Text);
    assert_eq!(k("x.csv", b"\xef\xbb\xbf  {\"a\": 1}"), Kind::Json);
    assert_eq!(k("x.bin", b"PAR1\0\0"), Kind::Parquet);
    assert_eq!(k("x", b"\x89MCAP0\r\n"), Kind::Mcap);
    assert_eq!(k("x.csv", b"#ROSBAG V2.0\n"), Kind::Ros1Bag);
    assert_eq!(k("x.db3", b"SQLite format 3\0"), Kind::Sqlite);
    assert_eq!(k("x.h5", b"\x89HDF\r\n\x1a\n"), Kind::Hdf5);
    assert_eq!(k("x.pkl", b"\x80\x04\x95"), Kind::Pickle);
    assert_eq!(k("x.pt", b"\x80\x02\x8a"), Kind::LegacyPyTorch);
    assert_eq!(k("x.npy", b"\x93NUMPY\x01\x00"), Kind::Npy);
    assert_eq!(k("x.dat", b"ab\0cd"), Kind::Binary);
    let opts = ParseOptions::default();
    for (name, bytes, want) in [
        ("run.db3", &b"SQLite format 3\0"[..], "run.db3 is an SQLite database"),
        ("run.h5", &b"\x89HDF\r\n\x1a\n"[..], "run.h5 is an HDF5 file"),
        ("run.pkl", &b"\x80\x04\x95"[..], "run.pkl is a Python pickle"),
    ] {
        let e = read_log(Path::new(name), bytes, &opts).unwrap().unwrap_err();
        assert!(e.message.contains(want), "{e}");
    }
    assert!(read_log(Path::new("x.csv"), b"t,a.q\n", &opts).is_none());
}

/// A CSV of other column names through a mapping: the longest key first (`pos_des_0` is the
/// command's, not joint `des_0`'s position), numbered columns named by `joints`, a skipped
/// joint's columns left out, `[rename]`, a rate from the mapping; errors at the header line.
#[test]
fn csv_columns_through_a_log_map() {
    let map = LogMap {
        measured: Some("pos".into()),
        command: Some("pos_des".into()),
        joints: Some(vec!["a".into(), "b".into(), "c".into()]),
        skip: vec!["c".into()],
        rename: [("b".to_string(), "bb".to_string())].into(),
        control_rate_hz: Some(50.0),
        ..Default::default()
    };
    let opts = ParseOptions { log_map: map.clone(), ..Default::default() };
    let text = "# robot: x\nt,pos_0,pos_1,pos_2,pos_des_0,pos_des_1,pos_des_2\n0,0.1,0.2,9,0.1,0.2,9\n0.02,0.1,0.2,9,0.1,0.2,9\n";
    let r = parse_csv_with(Path::new("m.csv"), text, &opts).unwrap();
    let names: Vec<&str> = r.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["a", "bb"]);
    assert_eq!(r.joints[1].q, vec![0.2, 0.2]);
    assert_eq!(r.joints[1].q_cmd, Some(vec![0.2, 0.2]));
    assert_eq!(r.control_rate_hz, Some(50.0));
    // The file declares the rate too: one place only (an error at the header line).
    let e = parse_csv_with(Path::new("m.csv"), &format!("# control_rate_hz: 50\n{text}"), &opts)
        .unwrap_err();
    assert!(e.line == Some(3) && e.message.contains("already"), "{e}");
    // A time under another name, with the mapping's unit.
    let opts = ParseOptions {
        log_map: LogMap {
            measured: Some("q".into()),
            time: Some("stamp_ms".into()),
            time_unit: Some("ms".into()),
            ..Default::default()
        },
        ..Default::default()
    };
    let r = parse_csv_with(Path::new("m.csv"), "stamp_ms,q_a,b_q\n0,1,2\n20,1,2\n", &opts).unwrap();
    assert_eq!(r.t, vec![0.0, 0.02]);
    assert_eq!(r.joints.iter().map(|j| j.name.as_str()).collect::<Vec<_>>(), ["a", "b"]);
    let e = parse_csv_with(Path::new("m.csv"), "stamp,q_a\n0,1\n20,1\n", &opts).unwrap_err();
    assert!(e.line == Some(1) && e.message.contains("did you mean 'stamp'"), "{e}");
}

/// An error the reader raises on a mapped CSV names the column as the file writes it, not as
/// the mapping rewrote it (`'target_elbow'`, not `'elbow.q_cmd'`), in the message and in the
/// error's column.
#[test]
fn log_map_errors_name_the_column_as_written() {
    let opts = ParseOptions {
        log_map: LogMap {
            measured: Some("pos".into()),
            command: Some("target".into()),
            time: Some("time".into()),
            ..Default::default()
        },
        ..Default::default()
    };
    let head = "time,pos_elbow,target_elbow\n0,0.1,0.1\n";
    let e =
        parse_csv_with(Path::new("m.csv"), &format!("{head}0.01,0.1,abc\n"), &opts).unwrap_err();
    assert_eq!(e.line, Some(3), "{e}");
    assert!(e.message.contains("column 'target_elbow'"), "{e}");
    assert!(!e.message.contains("elbow.q_cmd"), "{e}");
    assert_eq!(e.column.as_deref(), Some("target_elbow"));
    // Degrees in the measured column.
    let e = parse_csv_with(Path::new("m.csv"), &format!("{head}0.01,50,0.1\n"), &opts).unwrap_err();
    assert!(e.message.contains("column 'pos_elbow'") && !e.message.contains("elbow.q'"), "{e}");
    // Time running backwards: the time column as written.
    let e = parse_csv_with(Path::new("m.csv"), &format!("{head}-1,0.1,0.1\n"), &opts).unwrap_err();
    assert_eq!(e.column.as_deref(), Some("time"), "{e}");
}
