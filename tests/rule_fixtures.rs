//! Fixtures are tests: every rule has `fixtures/rules/<id>/invalid*.xml` (must produce that
//! rule's finding; rendered output is a reviewed snapshot `*.snap`) and `valid*.xml` (must
//! produce none of it). A spec `<stem>.toml` beside a fixture is used for it. For a rule with a
//! probe, `<stem>.probed.snap` is the output with the probe simulations run.
//! Set UPDATE_SNAPSHOTS=1 to rewrite snapshots, then review the diff.

use std::path::{Path, PathBuf};

use modellint::lint::{LintInput, load, run_rules};
use modellint::output::text;
use modellint::rules::all_meta;

fn fixtures(id: &str) -> Vec<PathBuf> {
    let dir = Path::new("fixtures/rules").join(id);
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "xml" || e == "urdf"))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

fn lint_one(path: &Path, id: &str) -> (Vec<modellint::finding::Finding>, String) {
    lint_probed(path, id, id == "unstable-simulation")
}

/// As `lint_one`; with `probe`, the probe simulations run (the rule `unstable-simulation`
/// exists only as a probe, so its plain snapshot is probed too).
fn lint_probed(path: &Path, id: &str, probe: bool) -> (Vec<modellint::finding::Finding>, String) {
    let input = LintInput {
        model: path.to_path_buf(),
        spec: None,
        config: None,
        select: vec![id.to_string()],
        ignore: vec![],
    };
    let loaded =
        load(&input).unwrap_or_else(|e| panic!("fixture {} failed to load: {e}", path.display()));
    let mut findings = run_rules(&loaded);
    if probe {
        modellint::lint::confirm(&loaded, &mut findings);
    }
    let rendered = text::render(&loaded.sources, &findings, false);
    (findings, rendered)
}

#[test]
fn every_rule_has_docs_and_fixtures() {
    for m in all_meta() {
        if m.group == "engine" {
            continue;
        }
        for h in
            ["## What it does", "## Why is this bad?", "## How it is confirmed", "## How to fix"]
        {
            assert!(m.docs.contains(h), "rule {} docs lack `{h}`", m.id);
        }
        let fx = fixtures(m.id);
        let name = |p: &PathBuf| p.file_name().unwrap().to_string_lossy().to_string();
        assert!(
            fx.iter().any(|p| name(p).starts_with("invalid")),
            "rule {} has no invalid fixture",
            m.id
        );
        assert!(
            fx.iter().any(|p| name(p).starts_with("valid")),
            "rule {} has no valid fixture",
            m.id
        );
    }
}

#[test]
fn fixtures_produce_exactly_their_findings() {
    let update = std::env::var_os("UPDATE_SNAPSHOTS").is_some();
    let mut failures = Vec::new();
    for m in all_meta() {
        for path in fixtures(m.id) {
            let stem = path.file_stem().unwrap().to_string_lossy().to_string();
            let (findings, rendered) = lint_one(&path, m.id);
            let mine = findings.iter().filter(|f| f.rule == m.id).count();
            if stem.starts_with("valid") {
                if mine != 0 {
                    failures.push(format!(
                        "{}: expected no `{}` finding, got:\n{rendered}",
                        path.display(),
                        m.id
                    ));
                }
                continue;
            }
            if mine == 0 {
                failures.push(format!(
                    "{}: expected a `{}` finding, got none",
                    path.display(),
                    m.id
                ));
                continue;
            }
            let snap = path.with_extension("snap");
            if update {
                std::fs::write(&snap, &rendered).unwrap();
            } else {
                match std::fs::read_to_string(&snap) {
                    Ok(s) if s == rendered => {}
                    Ok(s) => failures.push(format!(
                        "{}: snapshot differs\n--- expected\n{s}\n--- got\n{rendered}",
                        snap.display()
                    )),
                    Err(_) => failures.push(format!(
                        "{}: missing snapshot (run with UPDATE_SNAPSHOTS=1)",
                        snap.display()
                    )),
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// Snapshots with the probes run, for every invalid fixture of a rule with a probe: what each
/// probe concluded about each finding is reviewed like the rest of the output. Every such rule
/// has at least one fixture whose findings the probe really checked (confirmed, refuted or
/// measured; a fact is never refuted), and a
/// finding's claim is for the probe its rule names.
#[test]
fn probed_fixtures_match_their_snapshots() {
    use modellint::finding::ProbeStatus;
    let update = std::env::var_os("UPDATE_SNAPSHOTS").is_some();
    let mut failures = Vec::new();
    for m in all_meta() {
        let Some(probe) = m.probe else { continue };
        if m.id == "unstable-simulation" {
            continue; // its plain snapshot is the probed one
        }
        let mut decided = 0;
        for path in fixtures(m.id) {
            if !path.file_name().unwrap().to_string_lossy().starts_with("invalid") {
                continue;
            }
            let (findings, rendered) = lint_probed(&path, m.id, true);
            for f in findings.iter().filter(|f| f.rule == m.id) {
                let named = |n: &str| n == probe || m.also_probes.contains(&n);
                if let Some(c) = &f.claim {
                    assert!(named(c.probe_name()), "{}: claim of {}", path.display(), m.id);
                }
                if let Some(p) = &f.probe {
                    assert!(named(&p.name), "{}", path.display());
                    // A fact is never refuted.
                    assert!(
                        !(f.fact && p.status == ProbeStatus::Refuted),
                        "{}: fact refuted: {}",
                        path.display(),
                        f.message
                    );
                    if matches!(
                        p.status,
                        ProbeStatus::Confirmed | ProbeStatus::Refuted | ProbeStatus::Measured
                    ) {
                        decided += 1;
                    }
                }
            }
            let snap = path.with_extension("probed.snap");
            if update {
                std::fs::write(&snap, &rendered).unwrap();
                continue;
            }
            match std::fs::read_to_string(&snap) {
                Ok(s) if s == rendered => {}
                Ok(s) => failures.push(format!(
                    "{}: snapshot differs\n--- expected\n{s}\n--- got\n{rendered}",
                    snap.display()
                )),
                Err(_) => failures.push(format!(
                    "{}: missing snapshot (run with UPDATE_SNAPSHOTS=1)",
                    snap.display()
                )),
            }
        }
        if decided == 0 {
            failures.push(format!(
                "rule {}: no fixture finding was confirmed, refuted or measured by `{probe}`",
                m.id
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// Text output shows the relevant lines, not a long span whole: in every snippet box, each
/// source line shown is within 2 lines of a labelled line or of the box's header line (the
/// finding's location); the lines between distant labels are one `⋮` row.
#[test]
fn snippets_show_only_lines_near_their_labels() {
    let mut elided = 0;
    let mut boxes = 0;
    for m in all_meta() {
        for path in fixtures(m.id) {
            if !path.file_name().unwrap().to_string_lossy().starts_with("invalid") {
                continue;
            }
            let (_, rendered) = lint_one(&path, m.id);
            elided += rendered.matches('⋮').count();
            boxes += check_near_labels(&path, &rendered);
        }
    }
    // The mirror-asymmetry and armature fixtures label lines far apart in one file.
    assert!(elided >= 5, "expected elided runs in the fixtures, got {elided}");
    assert!(boxes >= 20, "only {boxes} snippet boxes checked");
}

/// Checks one rendered report; returns the number of snippet boxes it holds.
fn check_near_labels(path: &Path, rendered: &str) -> usize {
    let lines: Vec<&str> = rendered.lines().collect();
    let source_line = |l: &str| -> Option<usize> {
        let t = l.trim_start();
        let digits = t.chars().take_while(|c| c.is_ascii_digit()).count();
        (digits > 0 && t[digits..].starts_with(" │")).then(|| t[..digits].parse().ok())?
    };
    let is_label = |l: &str| l.trim_start().starts_with('·');
    let mut boxes = 0;
    let mut i = 0;
    while i < lines.len() {
        let Some(head) = lines[i].trim_start().strip_prefix("╭─[") else {
            i += 1;
            continue;
        };
        boxes += 1;
        let head_line: usize =
            head.trim_end_matches(']').rsplit(':').nth(1).unwrap().parse().unwrap();
        let end = (i..lines.len()).find(|&k| lines[k].trim_start().starts_with('╰')).unwrap();
        let mut anchors = vec![head_line];
        for k in i + 1..end {
            if let Some(n) = source_line(lines[k])
                && is_label(lines[k + 1])
            {
                anchors.push(n);
            }
        }
        for line in &lines[i + 1..end] {
            if let Some(n) = source_line(line) {
                let d = anchors.iter().map(|a| a.abs_diff(n)).min().unwrap();
                assert!(
                    d <= 2,
                    "{}: line {n} is shown {d} lines away from any label:\n{rendered}",
                    path.display()
                );
            }
        }
        i = end + 1;
    }
    boxes
}

/// Foot friction has no expectation until the user states one: MuJoCo's default friction 1 on
/// the feet is not reported (nor their condim 6), and stating the intended friction in
/// modellint.toml makes the same deviation a warning.
#[test]
fn foot_friction_is_judged_only_against_a_stated_value() {
    use modellint::finding::Severity;
    let model = PathBuf::from("fixtures/rules/foot-collision-geometry/valid_default_friction.xml");
    let run = |config: Option<PathBuf>| {
        let input = LintInput {
            model: model.clone(),
            spec: None,
            config,
            select: vec!["foot-collision-geometry".into()],
            ignore: vec![],
        };
        let loaded = load(&input).unwrap();
        run_rules(&loaded)
    };
    let friction = |fs: &[modellint::finding::Finding]| {
        fs.iter()
            .filter(|f| f.message.contains("sliding friction"))
            .map(|f| f.severity)
            .collect::<Vec<_>>()
    };
    // Without a stated value there is no expectation: one robot's identified friction (the
    // Asimov 0.6) is not another's.
    let plain = run(None);
    assert_eq!(friction(&plain), vec![], "no friction finding without a stated value");
    assert!(
        plain.iter().all(|f| f.severity == Severity::Info),
        "no warning without a stated value"
    );
    let stated = run(Some(PathBuf::from("fixtures/config/foot_friction_stated.toml")));
    assert_eq!(friction(&stated), vec![Severity::Warning, Severity::Warning]);
}

/// Torsional and rolling friction (condim 6) on the feet are a design choice until the user
/// states the intended contact dimension: a point-foot quadruped's condim-6 spheres and a
/// humanoid's condim-6 sole points get no condim finding; with `condim = 3` stated in
/// modellint.toml the same feet are warnings, one per foot, at dim 6 as MuJoCo combines it.
#[test]
fn foot_condim_is_judged_only_against_a_stated_value() {
    use modellint::finding::Severity;
    let run = |model: &str, config: Option<&str>| {
        let input = LintInput {
            model: PathBuf::from(model),
            spec: None,
            config: config.map(PathBuf::from),
            select: vec!["foot-collision-geometry".into()],
            ignore: vec![],
        };
        let loaded = load(&input).unwrap();
        run_rules(&loaded)
            .into_iter()
            .filter(|f| f.message.contains("condim"))
            .map(|f| (f.severity, f.measured.map(|q| q.value), f.expected.map(|q| q.value)))
            .collect::<Vec<_>>()
    };
    let stated = Some("fixtures/config/foot_condim_stated.toml");
    for (model, feet) in [
        ("fixtures/rules/foot-collision-geometry/valid_point_foot_condim6.xml", 4),
        ("fixtures/rules/foot-collision-geometry/valid_default_friction.xml", 2),
    ] {
        assert_eq!(
            run(model, None),
            vec![],
            "{model}: condim 6 is no defect without a stated condim"
        );
        assert_eq!(
            run(model, stated),
            vec![(Severity::Warning, Some(6.0), Some(3.0)); feet],
            "{model}: condim 6 against a stated 3"
        );
    }
    // Frictionless feet need no stated intent: they stay a warning.
    let c1 = run("fixtures/rules/foot-collision-geometry/invalid_condim1_no_floor.xml", None);
    assert!(!c1.is_empty() && c1.iter().all(|f| f.0 == Severity::Warning && f.1 == Some(1.0)));
}

/// MuJoCo 3.17 actuator physics: the same reflected inertia written on the joint or on the
/// actuator (armature × gear²) gives the same verdict, and the same ζ.
#[test]
fn armature_placement_does_not_change_the_verdict() {
    let findings = |path: &str, id: &str| {
        let p = Path::new(path);
        let spec = p.with_extension("toml");
        let input = LintInput {
            model: p.to_path_buf(),
            spec: spec.is_file().then_some(spec),
            config: None,
            select: vec![id.to_string()],
            ignore: vec![],
        };
        let loaded = load(&input).unwrap();
        run_rules(&loaded)
            .into_iter()
            .filter(|f| f.rule == id)
            .map(|f| (f.measured.map(|q| (q.value * 1e6).round()), f.severity))
            .collect::<Vec<_>>()
    };
    let dir = "fixtures/rules/armature-mismatch";
    let mut a = findings(&format!("{dir}/invalid.xml"), "armature-mismatch");
    let mut b = findings(&format!("{dir}/invalid_actuator_placement.xml"), "armature-mismatch");
    a.sort_by(|x, y| format!("{x:?}").cmp(&format!("{y:?}")));
    b.sort_by(|x, y| format!("{x:?}").cmp(&format!("{y:?}")));
    assert_eq!(a.len(), 3);
    assert_eq!(a, b);
    assert!(findings(&format!("{dir}/valid.xml"), "armature-mismatch").is_empty());
    assert!(
        findings(&format!("{dir}/valid_actuator_placement.xml"), "armature-mismatch").is_empty()
    );
    // ζ = kd / (2√(kp·I)): kd = 1 + 0.1, kp = 100 either way (hand-computed: 25·2², 0.25·2² + 0.025·2²).
    let z = |path: &str| {
        let input = LintInput {
            model: path.into(),
            spec: None,
            config: None,
            select: vec!["underdamped-pd-gains".into()],
            ignore: vec![],
        };
        let loaded = load(&input).unwrap();
        let f = run_rules(&loaded).into_iter().find(|f| f.rule == "underdamped-pd-gains").unwrap();
        (f.data["kd"], f.data["kp"], f.data["inertia"], f.data["zeta"])
    };
    let (kd1, kp1, i1, z1) = z("fixtures/rules/underdamped-pd-gains/invalid.xml");
    let (kd2, kp2, i2, z2) =
        z("fixtures/rules/underdamped-pd-gains/invalid_actuator_placement.xml");
    assert!((kd1 - 1.1).abs() < 1e-12 && (kd2 - 1.1).abs() < 1e-12, "{kd1} {kd2}");
    assert!((kp1 - 100.0).abs() < 1e-9 && (kp2 - 100.0).abs() < 1e-9);
    assert!((i1 - i2).abs() < 1e-12 && (z1 - z2).abs() < 1e-12);
    // I = capsule about its end (hand-computed by MuJoCo's mass matrix) + armature 0.02.
    assert!(i1 > 0.02);
}

/// Effective armature and damping as MuJoCo 3.17 applies them, against hand-computed values
/// (see the comment in the fixture), and the mass matrix MuJoCo builds from them.
#[test]
fn effective_armature_and_damping_from_actuators_and_tendons() {
    let input = LintInput {
        model: "fixtures/model/actuator_physics.xml".into(),
        spec: None,
        config: None,
        select: vec![],
        ignore: vec![],
    };
    let l = load(&input).unwrap();
    let r = &l.robot;
    let j1 = r.joint("j1").unwrap();
    let j2 = r.joint("j2").unwrap();
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
    assert!(close(j1.armature, 0.217), "{}", j1.armature);
    // j2 also has a passive dcmotor (no control input): back-EMF 0.05²/2 × 1² = 0.00125.
    assert!(close(j1.damping, 4.025), "{}", j1.damping);
    assert!(close(j2.armature, 0.007), "{}", j2.armature);
    assert!(close(j2.damping, 0.4 + 0.00125), "{}", j2.damping);
    assert!(close(j1.own_armature(), 0.01) && close(j2.own_armature(), 0.0));
    // Box 0.2 m, 1 kg about a centroidal axis: (0.2² + 0.2²)/12; plus the effective armature.
    let link = (0.04 + 0.04) / 12.0;
    assert!((r.key.m_diag[j2.dofadr] - (link + 0.007)).abs() < 1e-9, "{}", r.key.m_diag[j2.dofadr]);
    // Three actuators, two controls (the passive dcmotor has none): per-actuator data stays aligned.
    assert_eq!(r.actuators.len(), 3);
    assert_eq!(r.actuators[0].ctrlrange, [-24.0, 24.0]);
    assert!(r.actuators[0].ctrllimited);
    assert!((r.actuators[1].gear - 2.0).abs() < 1e-12);
    assert!(matches!(r.actuators[2].kind, modellint::model::ActuatorKind::DcMotor { .. }));
}

/// The "skipped without a spec" notice lists exactly the rules that do not run without one: no
/// fixture linted without a spec has a finding of a listed rule, and every rule listed as
/// skipped or weakened exists.
#[test]
fn spec_notice_lists_exactly_the_rules_that_did_not_run() {
    let ids: Vec<&str> = all_meta().iter().map(|m| m.id).collect();
    for (id, _) in modellint::spec_use::SKIPPED.iter().chain(modellint::spec_use::WEAKENED) {
        assert!(ids.contains(id), "unknown rule in the spec notice: {id}");
    }
    let mut checked = 0;
    for m in all_meta() {
        for path in fixtures(m.id) {
            if path.with_extension("toml").exists() {
                continue;
            }
            let input = LintInput {
                model: path.clone(),
                spec: None,
                config: None,
                select: vec![],
                ignore: vec![],
            };
            let Ok(l) = load(&input) else { continue };
            if l.spec.is_some() {
                continue;
            }
            checked += 1;
            for f in run_rules(&l) {
                assert!(
                    !modellint::spec_use::SKIPPED.iter().any(|(id, _)| *id == f.rule),
                    "{}: `{}` is listed as skipped without a spec but reported: {}",
                    path.display(),
                    f.rule,
                    f.message
                );
            }
        }
    }
    assert!(checked > 20, "only {checked} spec-less fixtures");
}

/// The findings of rule `id` on one of its fixtures (only that rule run).
fn of(id: &str, fixture: &str) -> Vec<modellint::finding::Finding> {
    let path = Path::new("fixtures/rules").join(id).join(fixture);
    lint_one(&path, id).0.into_iter().filter(|f| f.rule == id).collect()
}

#[test]
fn servo_stall_band_is_frictionloss_over_kp_times_gear_squared() {
    // Knee kp 1 / frictionloss 1 → 1 rad; ankle kp 1 / 0.1 → 0.1 rad; the hip (kp 60 / 0.3 →
    // 5 mrad) is stiff enough.
    let f = of("servo-stall-band", "invalid.xml");
    let bands: Vec<f64> = f.iter().map(|f| f.measured.as_ref().unwrap().value).collect();
    assert_eq!(bands.len(), 2, "{f:?}");
    assert!((bands[0] - 1.0).abs() < 1e-9 && (bands[1] - 0.1).abs() < 1e-9, "{bands:?}");
    // 20 N of friction against 400 N/m on a slide: 5 cm.
    let f = of("servo-stall-band", "invalid_slide.xml");
    assert!((f[0].measured.as_ref().unwrap().value - 0.05).abs() < 1e-9);
    // A force limit below the friction: never moves.
    assert_eq!(of("servo-stall-band", "invalid_forcerange.xml").len(), 1);
    // kp 2 at gear 10 is 200 N·m/rad at the joint: 5 mrad, not 0.5 rad.
    assert!(of("servo-stall-band", "valid_geared.xml").is_empty());
    assert!(of("servo-stall-band", "valid.xml").is_empty());
    assert!(of("servo-stall-band", "valid_torque_motor.xml").is_empty());
}

#[test]
fn isotropic_base_inertia_needs_an_elongated_floating_base() {
    assert_eq!(of("isotropic-base-inertia", "invalid.xml").len(), 1);
    // The evidence can be the child bodies' attachment points alone.
    assert_eq!(of("isotropic-base-inertia", "invalid_mesh_trunk.xml").len(), 1);
    for v in ["valid.xml", "valid_round_body.xml", "valid_fixed_base.xml"] {
        assert!(of("isotropic-base-inertia", v).is_empty(), "{v}");
    }
}

#[test]
fn keyframe_motor_ctrl_only_when_torque_motors_get_the_pose() {
    let f = of("keyframe-motor-ctrl", "invalid.xml");
    assert_eq!(f.len(), 1);
    assert_eq!(f[0].data.get("motors"), Some(&2.0), "the two non-zero angles");
    for v in ["valid_position_servos.xml", "valid_feedforward.xml", "valid_no_ctrl.xml"] {
        assert!(of("keyframe-motor-ctrl", v).is_empty(), "{v}");
    }
}

#[test]
fn mirror_pairs_leg_side_prefixes_and_reports_an_inherited_ctrlrange_once() {
    let f = of("mirror-asymmetry", "invalid_leg_side_prefixes.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!(f[0].message.contains("`LR_KFE`") && f[0].message.contains("`LL_KFE`"));
    assert!(of("mirror-asymmetry", "valid_leg_side_prefixes.xml").is_empty());
    // The joints' range differs; the actuators inherit it: one finding, on the joint.
    let f = of("mirror-asymmetry", "invalid_inherited_ctrlrange.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!(f[0].message.starts_with("joint `right_knee` range"), "{}", f[0].message);
}

/// A pair differing in mass and in principal moments reports both: the moments in the mass
/// finding (before, the mass finding hid them until `tolerance` was raised past the mass).
#[test]
fn mirror_reports_moments_beside_a_mass_difference() {
    let f = of("mirror-asymmetry", "invalid_mass_and_inertia.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!(f[0].message.starts_with("body `right_hand` mass 0.83 kg"), "{}", f[0].message);
    let note = f[0].note.as_deref().unwrap_or("");
    assert!(note.contains("principal moments of inertia differ too"), "{note}");
    let ratio = f[0].data.get("inertia_ratio").copied().unwrap_or(0.0);
    assert!((ratio - 0.0050 / 0.0042).abs() < 1e-3, "{ratio}");
}

/// A URDF link's `<collision>` geoms are indexed under the link: a finding on one points at it.
/// A collision-only mesh is declared collision geometry, not a visual mesh left colliding.
#[test]
fn urdf_collision_geoms_are_located_and_not_visual() {
    let p = Path::new("fixtures/rules/visual-mesh-collision/valid_urdf_collision_mesh.urdf");
    let input = LintInput {
        model: p.to_path_buf(),
        spec: None,
        config: None,
        select: vec![],
        ignore: vec![],
    };
    let l = load(&input).expect("loads");
    let g = l.robot.geoms.iter().find(|g| g.body != 0).expect("the foot's geom").id;
    let e = l.robot.elem(modellint::model::mjcf::ElemKind::Geom, g, "").expect("indexed");
    assert_eq!(e.tag, "collision");
    assert!(run_rules(&l).iter().all(|f| f.rule != "visual-mesh-collision"));
}

/// A joint whose damping takes its whole force limit below the spec's `velocity_limit` is
/// reported (damping × velocity limit > force limit); the same arm with the motor's viscous
/// friction as joint damping and the servo's damping in `kv` is not. The valid model lives in
/// `pairs/` because every spec with a `velocity_limit` also gets the rule's per-family info.
#[test]
fn damping_that_caps_speed_below_the_velocity_limit() {
    let caps = |path: &str| {
        let (fs, _) = lint_one(Path::new(path), "effort-limit-mismatch");
        let n = fs.iter().filter(|f| f.message.contains("cannot reach")).count();
        let infos = fs.iter().filter(|f| f.message.contains("speed–torque limit")).count();
        (n, infos)
    };
    let (n, infos) = caps("fixtures/rules/effort-limit-mismatch/invalid_damping_caps_speed.xml");
    assert_eq!((n, infos), (2, 2));
    let (n, infos) =
        caps("fixtures/rules/effort-limit-mismatch/pairs/valid_damping_within_speed.xml");
    assert_eq!((n, infos), (0, 2), "the spec's velocity_limit was read, no damping finding");
}

/// The first finding of rule `id` on fixture `path` (rules run alone, no probe).
fn first(path: &str, id: &str) -> (modellint::finding::Finding, String) {
    let (f, text) = lint_one(Path::new(path), id);
    let f = f.into_iter().find(|f| f.rule == id).unwrap_or_else(|| panic!("{path}: no {id}"));
    (f, text)
}

/// A `<general biastype="affine">` servo with gain g ≠ −biasprm[1] is a PD servo of stiffness
/// −biasprm[1] and damping −biasprm[2] (hand-computed from the fixture: kp 10, kd 0.1 + joint
/// damping 0.02), pointed at the `<general>`'s biasprm, not at a `<position>` default's kv.
#[test]
fn a_scaled_general_servo_is_a_pd_servo_on_its_setpoint() {
    let dir = "fixtures/rules/underdamped-pd-gains";
    let (f, text) = first(&format!("{dir}/invalid_scaled_general.xml"), "underdamped-pd-gains");
    assert!((f.data["kp"] - 10.0).abs() < 1e-9, "{:?}", f.data);
    assert!((f.data["kd"] - 0.12).abs() < 1e-9, "{:?}", f.data);
    assert!(text.contains("invalid_scaled_general.xml:23:"), "{text}");
    assert!(!text.contains("inherits `kv`"), "{text}");
    // Its ctrlrange 0..255 counts commands setpoints 0..g·255/kp = 0.80001 rad, not 255 rad.
    let (f, _) = first("fixtures/rules/soft-limits/invalid_scaled_servo.xml", "soft-limits");
    assert!(f.data["ctrl_lo"].abs() < 1e-12, "{:?}", f.data);
    assert!((f.data["ctrl_hi"] - 0.031373 * 255.0 / 10.0).abs() < 1e-12, "{:?}", f.data);
}

/// Under MJCF's default degrees, hinge ranges all within ±π are named as radians read as
/// degrees; real degree ranges (soft-limits/invalid.xml: -90..45, 0..120) are not.
#[test]
fn radian_sized_ranges_under_default_degrees_are_named() {
    let (f, _) = first(
        "fixtures/rules/soft-limits/invalid_radian_ranges_read_as_degrees.xml",
        "soft-limits",
    );
    assert!(f.message.contains("read as degrees"), "{}", f.message);
    let (f, _) = first("fixtures/rules/soft-limits/invalid.xml", "soft-limits");
    assert!(!f.message.contains("read as degrees"), "{}", f.message);
}

/// A 500 × 360 × 120 mm box read as metres: bounding radius √(250² + 180² + 60²) = 313.8 m, on a
/// 12.5 kg body of largest moment 0.4 kg·m² (radius of gyration 0.179 m).
#[test]
fn a_millimetre_mesh_on_a_metre_body_is_named_with_its_file() {
    let (f, _) = first("fixtures/rules/mesh-scale/invalid.xml", "mesh-scale");
    let across = 2.0 * (250f64.powi(2) + 180f64.powi(2) + 60f64.powi(2)).sqrt();
    assert!((f.measured.as_ref().unwrap().value - across).abs() < 1e-6 * across, "{f:?}");
    assert!(f.message.contains("chassis_mm.stl"), "{}", f.message);
    assert!(f.note.as_deref().is_some_and(|n| n.contains("millimetres")), "{f:?}");
}

#[test]
fn servo_sag_is_static_load_over_stiffness() {
    // Shoulder: 2 kg at 0.15 m and 1 kg at 0.4 m against kp 4 → 9.81·0.7 / 4 rad.
    let f = of("servo-sag", "invalid.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    let sag = f[0].measured.as_ref().unwrap().value;
    assert!((sag - 9.81 * 0.7 / 4.0).abs() < 1e-6, "{sag}");
    // Spring 20 N·m/rad resting 0.5 rad off the pose, servo kp 50: 10 / 70 rad.
    // The second turret (spring at the pose) commanded to its ctrlrange end −1 rad reaches
    // −50 / 70 rad: 20 / 70 short (towards springref).
    let f = of("servo-sag", "invalid_spring.xml");
    assert_eq!(f.len(), 2, "{f:?}");
    assert!((f[0].measured.as_ref().unwrap().value - 10.0 / 70.0).abs() < 1e-9);
    assert!((f[1].measured.as_ref().unwrap().value - 20.0 / 70.0).abs() < 1e-9, "{f:?}");
    // Joint springs equal to the servos' kp halve every command: hip yaw 0.7 → 0.35 rad,
    // knee 1.2 → 0.6 rad.
    let f = of("servo-sag", "invalid_spring_copies_kp.xml");
    let got: Vec<f64> = f.iter().map(|f| f.measured.as_ref().unwrap().value).collect();
    assert_eq!(got.len(), 2, "{f:?}");
    assert!((got[0] - 0.35).abs() < 1e-9 && (got[1] + 0.6).abs() < 1e-9, "{got:?}");
    // 5 kg on a vertical slide against 1000 N/m, no keyframe: 5·9.81 / 1000 m down.
    let f = of("servo-sag", "invalid_slide_no_keyframe.xml");
    assert!((f[0].measured.as_ref().unwrap().value + 5.0 * 9.81 / 1000.0).abs() < 1e-9);
    for v in [
        "valid_stiff.xml",
        "valid_gravcomp.xml",
        "valid_actuatorgravcomp.xml",
        "valid_ctrl_compensates.xml",
        "valid_rests_on_limit.xml",
        "valid_torque_motors.xml",
        "valid_soft_return_spring.xml",
    ] {
        assert!(of("servo-sag", v).is_empty(), "{v}");
    }
}

/// inertiafromgeom="true": the thigh's stated 4 kg becomes its drawn 0.2 × 0.2 × 0.4 m box at
/// 1000 kg/m³ (16 kg), the pelvis's 3 kg its 0.2 × 0.2 × 0.1 m box (4 kg); the torso, with no
/// geom in groups 2–3, keeps its stated 7.5 kg. One finding, the bodies by discrepancy.
#[test]
fn inertiafromgeom_true_is_named_with_the_masses_it_discards() {
    let f = of("inertial-overridden", "invalid.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!(
        (f[0].measured.as_ref().unwrap().value - 20.0).abs() < 1e-9
            && (f[0].expected.as_ref().unwrap().value - 7.0).abs() < 1e-12,
        "{f:?}"
    );
    let m = &f[0].message;
    let (thigh, pelvis) = (m.find("`thigh`").unwrap(), m.find("`pelvis`").unwrap());
    assert!(thigh < pelvis && !m.contains("`torso`"), "{m}");
    assert!(m.contains("`thigh` states 4 kg and weighs 16 kg"), "{m}");
    for v in ["valid.xml", "valid_true_matches.xml"] {
        assert!(of("inertial-overridden", v).is_empty(), "{v}");
    }
}

/// `_p`/`_v`/`_f` suffixes read by the file's own majority: the knee's `_v` and `_f` slots are
/// `<actuatorpos>` among `<actuatorvel>`/`<actuatorfrc>` siblings; axis letters, a `_v` the
/// file uses for positions and a lone `_t` on a position are not judged.
#[test]
fn sensor_letter_suffixes_follow_the_files_majority() {
    let f = of("sensor-quantity", "invalid_letter_suffix.xml");
    let names: Vec<&str> = f.iter().map(|f| f.message.as_str()).collect();
    assert_eq!(f.len(), 2, "{names:?}");
    assert!(names[0].contains("`knee_joint_v`") && names[0].contains("name says velocity"));
    assert!(names[1].contains("`knee_joint_f`") && names[1].contains("name says force"));
    assert!(of("sensor-quantity", "valid_letter_suffix.xml").is_empty());
}

/// A keyframe with the base at the floor's height: both legs' thighs, shanks and soles lie
/// entirely under the floor plane, the deepest the soles' tops at 0.82 − √0.0117 m; the same
/// robot standing 1 mm into the floor, a post fixed to the world and a non-colliding marker
/// below it are not reported.
#[test]
fn a_keyframe_that_buries_the_robot_in_the_floor_is_named() {
    let f: Vec<_> = of("keyframe-state", "invalid_buried_in_floor.xml")
        .into_iter()
        .filter(|f| f.message.contains("under the floor plane"))
        .collect();
    assert_eq!(f.len(), 1, "{f:?}");
    let depth = f[0].measured.as_ref().unwrap().value;
    assert!((depth - (0.82 - 0.0117f64.sqrt())).abs() < 1e-9, "{depth}");
    assert!(f[0].message.contains("places 6 colliding geoms"), "{}", f[0].message);
    assert!(of("keyframe-state", "valid_standing_on_floor.xml").is_empty());
}

#[test]
fn repeated_class_mass_counts_the_class_mass_once_per_geom() {
    // The tip's 0.02 kg class mass on two geoms (0.04 kg), the proximal link's 0.05 kg on two
    // capsules (0.1 kg): each body weighs its mass twice, one finding per body.
    let f = of("repeated-class-mass", "invalid.xml");
    let got: Vec<(f64, f64)> = f
        .iter()
        .map(|f| (f.measured.as_ref().unwrap().value, f.expected.as_ref().unwrap().value))
        .collect();
    assert_eq!(got.len(), 2, "{f:?}");
    assert!((got[0].0 - 0.04).abs() < 1e-12 && (got[0].1 - 0.02).abs() < 1e-12, "{got:?}");
    assert!((got[1].0 - 0.1).abs() < 1e-12 && (got[1].1 - 0.05).abs() < 1e-12, "{got:?}");
    for v in ["valid.xml", "valid_inertial_states_mass.xml"] {
        assert!(of("repeated-class-mass", v).is_empty(), "{v}");
    }
}

/// A placeholder cylinder (radius 0.8 m, length 1.2 m) on an 8 kg URDF root link: 1.6 m across
/// against the joints' span √(0.2² + 0.8²) m (left hip to right ankle), and π·0.8²·1.2 m³ at
/// 10 kg/m³; a box written in millimetres (half-sizes 150 40 30) on a 1.2 kg forearm.
#[test]
fn oversized_collision_primitive_against_link_mass_and_joint_span() {
    let id = "oversized-collision-primitive";
    let f = of(id, "invalid.urdf");
    assert_eq!(f.len(), 1, "{f:?}");
    let volume = std::f64::consts::PI * 0.8 * 0.8 * 1.2;
    assert!((f[0].measured.as_ref().unwrap().value - 1.6).abs() < 1e-9, "{f:?}");
    assert!((f[0].data["span"] - 0.68f64.sqrt()).abs() < 1e-9, "{:?}", f[0].data);
    assert!((f[0].data["volume"] - volume).abs() < 1e-9, "{:?}", f[0].data);
    assert!((f[0].data["least_mass"] - 10.0 * volume).abs() < 1e-9, "{:?}", f[0].data);
    assert!((f[0].data["link_mass"] - 8.0).abs() < 1e-12, "{:?}", f[0].data);
    let f = of(id, "invalid_mm.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!((f[0].measured.as_ref().unwrap().value - 300.0).abs() < 1e-9, "{f:?}");
    assert!((f[0].data["volume"] - 8.0 * 150.0 * 40.0 * 30.0).abs() < 1e-6, "{:?}", f[0].data);
    assert!((f[0].data["span"] - 0.55).abs() < 1e-9, "{:?}", f[0].data);
    // A 0.9 m bumper of 0.5 kg inside a 1.07 m span; a 120 kg chassis of 0.384 m³.
    for v in ["valid_mobile_manipulator.xml", "valid_heavy_base.xml"] {
        assert!(of(id, v).is_empty(), "{v}");
    }
}

/// 1 mm boxes (half-size 0.5 mm) on hips (visual sphere of radius 40 mm: 80 mm, more than the
/// 60 mm to the hip pitch joint), thighs (capsule 350 mm + 2 × 40 mm) and shins (350 + 2 × 35).
#[test]
fn token_collision_geometry_is_judged_against_the_link_it_stands_for() {
    let id = "token-collision-geometry";
    let f = of(id, "invalid.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!((f[0].measured.as_ref().unwrap().value - 6.0).abs() < 1e-12, "{f:?}");
    assert!((f[0].data["first_across"] - 0.001).abs() < 1e-12, "{:?}", f[0].data);
    assert!((f[0].data["first_size"] - 0.08).abs() < 1e-12, "{:?}", f[0].data);
    assert!((f[0].data["smallest_ratio"] - 80.0).abs() < 1e-6, "{:?}", f[0].data);
    for l in ["l_hip` (1 mm on a 80 mm", "l_thigh` (1 mm on a 430 mm", "r_shin` (1 mm on a 420 mm"]
    {
        assert!(f[0].message.contains(l), "{}", f[0].message);
    }
    for v in ["valid_covered_legs.xml", "valid_point_feet.xml"] {
        assert!(of(id, v).is_empty(), "{v}");
    }
}

/// Two arms of 0.3 + 1.5 + 1 kg on free joints of their own beside a 15 + 2 × (4 + 3) kg robot.
#[test]
fn a_limb_on_its_own_free_joint_is_named_and_scenes_are_not() {
    let id = "detached-limb";
    let f = of(id, "invalid.xml");
    assert_eq!(f.len(), 2, "{f:?}");
    for x in &f {
        assert!((x.measured.as_ref().unwrap().value - 2.8).abs() < 1e-9, "{x:?}");
        assert!((x.expected.as_ref().unwrap().value - 29.0).abs() < 1e-9, "{x:?}");
        assert!((x.data["actuated"] - 2.0).abs() < 1e-12, "{:?}", x.data);
    }
    for v in ["valid_scene.xml", "valid_two_robots.xml", "valid_held_by_weld.xml"] {
        assert!(of(id, v).is_empty(), "{v}");
    }
}

/// Links whose mass MuJoCo computes from their geoms at 1000 kg/m³ (no `<inertial>`), judged by
/// the torque their weight needs: a forearm cylinder of radius 0.5 m and half-length 0.6 m
/// (π·0.5²·1.2·1000 kg) centred 0.6 m below the elbow's y axis, at the elbow's π/2 (range 0 to
/// 2.5 rad), against the elbow motor's 40 N·m; a pelvis cylinder of radius 1 m and half-length
/// 1 m (2π·1000 kg) tilted on the knees' y axis 0.5 m below its centre, against the four leg
/// pitch motors' 4 × 100 N·m.
#[test]
fn oversized_primitive_with_computed_mass_is_judged_by_the_torque_its_weight_needs() {
    use std::f64::consts::PI;
    let id = "oversized-collision-primitive";
    let g = 9.81;
    let near = |a: f64, b: f64| (a - b).abs() <= 1e-4 * b.abs();
    let f = of(id, "invalid_computed_limb.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    let m = PI * 0.25 * 1.2 * 1000.0;
    assert!(near(f[0].data["link_mass"], m), "{:?}", f[0].data);
    assert!(near(f[0].data["need_torque"], m * g * 0.6), "{:?}", f[0].data);
    assert!((f[0].data["effort_limit"] - 40.0).abs() < 1e-9, "{:?}", f[0].data);
    assert!((f[0].measured.as_ref().unwrap().value - 1.2).abs() < 1e-9, "{f:?}");
    assert!((f[0].data["span"] - 0.3).abs() < 1e-9, "{:?}", f[0].data);
    assert!(f[0].message.contains("joint `elbow`"), "{}", f[0].message);
    let f = of(id, "invalid_computed_trunk.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    let m = 2.0 * PI * 1000.0;
    assert!(near(f[0].data["link_mass"], m), "{:?}", f[0].data);
    assert!(near(f[0].data["need_torque"], m * g * 0.5), "{:?}", f[0].data);
    assert!((f[0].data["effort_limit"] - 400.0).abs() < 1e-9, "{:?}", f[0].data);
    assert!((f[0].data["span"] - 0.2f64.hypot(0.4)).abs() < 1e-9, "{:?}", f[0].data);
    // A heavy planar chassis no joint lifts, a light forearm a little longer than its span, a
    // rover's shell within its axles, wheels, terrain and a crate: none.
    assert!(of(id, "valid_computed_masses.xml").is_empty());
    // The rover beside two robots states its mass on its geom (the mass test's case).
    assert!(of(id, "../detached-limb/valid_two_robots.xml").is_empty());
}

/// Leaves whose only collision geom is a 1 mm box at their joint: the head beside a visual
/// sphere of radius 90 mm, both feet beside visual soles of 200 mm; corner spheres at the
/// soles' ends, fingertip pads and a camera frame with no visual shape are not reported.
#[test]
fn token_collision_geometry_on_leaves_is_judged_against_their_visual_shape() {
    let id = "token-collision-geometry";
    let f = of(id, "invalid_leaf.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!((f[0].measured.as_ref().unwrap().value - 3.0).abs() < 1e-12, "{f:?}");
    assert!((f[0].data["first_size"] - 0.18).abs() < 1e-12, "{:?}", f[0].data);
    assert!((f[0].data["smallest_ratio"] - 180.0).abs() < 1e-6, "{:?}", f[0].data);
    // Both sides of the mirror-symmetric legs get the same verdict.
    for l in ["`left_foot` (1 mm on a 200 mm visual", "`right_foot` (1 mm on a 200 mm visual"] {
        assert!(f[0].message.contains(l), "{}", f[0].message);
    }
    assert!(of(id, "valid_leaf_contacts.xml").is_empty());
}

/// A quadruped's front-left leg (0.35 + 0.05 + 0.6 + 0.2 kg) on a free joint of its own with
/// no motor, beside a 6 + 3 × 1.6 kg robot; a humanoid's right arm (0.4 + 1.4 + 0.9 kg) 0.7 m
/// beside the torso (0.22 m above it), past a tenth of the robot's size.
#[test]
fn a_passive_or_distant_limb_is_named_by_its_joints() {
    let id = "detached-limb";
    let f = of(id, "invalid_passive_leg.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!((f[0].measured.as_ref().unwrap().value - 1.2).abs() < 1e-9, "{f:?}");
    assert!((f[0].expected.as_ref().unwrap().value - 10.8).abs() < 1e-9, "{f:?}");
    assert_eq!(f[0].data["actuated"], 0.0, "{:?}", f[0].data);
    assert!(f[0].message.contains("3 joints named for the robot's left side"), "{}", f[0].message);
    let f = of(id, "invalid_far_arm.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!((f[0].measured.as_ref().unwrap().value - 2.7).abs() < 1e-9, "{f:?}");
    assert!((f[0].expected.as_ref().unwrap().value - 28.3).abs() < 1e-9, "{f:?}");
    assert!((f[0].data["distance"] - 0.7f64.hypot(0.22)).abs() < 1e-9, "{:?}", f[0].data);
    assert!((f[0].data["actuated"] - 3.0).abs() < 1e-12, "{:?}", f[0].data);
    // A strap on ball joints, a chair, a door and a jaw tool (no limb names or one joint), a
    // payload and a two-sided toy robot: none.
    assert!(of(id, "valid_scene_passive.xml").is_empty());
}

/// A floating base left without its `<inertial>` under the torso that states the part's: its
/// 0.2 × 0.14 × 0.42 m box and 1 cm sphere weigh 11.76 kg at 1000 kg/m³ (computed here from the
/// shapes, not read back); a shell welded to a stated forearm 1.78 kg. Bodies whose geoms' mass
/// the writer chose, and a hand on its own joint with no stated mass, are not reported.
#[test]
fn default_density_mass_names_the_body_and_the_water_it_weighs() {
    let pi = std::f64::consts::PI;
    let base = 1000.0 * (0.2 * 0.14 * 0.42 + 4.0 / 3.0 * pi * 0.01f64.powi(3));
    let f = of("default-density-mass", "invalid.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!((f[0].measured.as_ref().unwrap().value - base).abs() < 1e-6, "{f:?}");
    assert!(
        f[0].message.contains("body `floating_base_link` states no <inertial>"),
        "{}",
        f[0].message
    );
    // Its share of the moving bodies' mass: the base itself, the torso, two legs.
    let share = 100.0 * base / (base + 13.3 + 2.0 * (3.5 + 2.0));
    assert!((share - 32.62).abs() < 0.01, "{share}");
    assert!(f[0].message.contains("32.6 % of the robot's 36.06 kg"), "{}", f[0].message);
    let shell = 1000.0 * (pi * 0.045f64.powi(2) * 0.22 + 4.0 / 3.0 * pi * 0.045f64.powi(3));
    let f = of("default-density-mass", "invalid_welded_cover.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!((f[0].measured.as_ref().unwrap().value - shell).abs() < 1e-6, "{f:?}");
    assert!(f[0].message.contains("`forearm`, welded to it"), "{}", f[0].message);
    for v in ["valid.xml", "valid_all_from_geoms.xml", "valid_jointed_hand.xml"] {
        assert!(of("default-density-mass", v).is_empty(), "{v}");
    }
}

/// Bodies named by part number pair through the side-named joints that move them: the right
/// upper arm's 0.744 kg against the left's 0.579 kg, once; the forearms agree.
#[test]
fn mirror_pairs_part_numbered_bodies_through_their_joints() {
    let f = of("mirror-asymmetry", "invalid_part_numbered_bodies.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    let m = &f[0].message;
    assert!(m.contains("`KC_202R`") && m.contains("`KC_202L`") && m.contains("0.744"), "{m}");
    assert!(of("mirror-asymmetry", "valid_part_numbered_bodies.xml").is_empty());
}

/// A legged URDF's joints that nothing says how they are driven (no `<transmission>`, no spec
/// motor family) are named in one finding; joints a transmission names or the spec gives a
/// motor are left to `transmission-without-armature` and `zero-armature`.
#[test]
fn legged_urdf_joints_without_a_stated_drive_are_named_once() {
    let id = "legged-urdf-armature";
    let names = |f: &modellint::finding::Finding, js: &[&str], not: &[&str]| {
        for j in js {
            assert!(f.message.contains(&format!("`{j}`")), "{j}: {}", f.message);
        }
        for j in not {
            assert!(!f.message.contains(&format!("`{j}`")), "{j}: {}", f.message);
        }
    };
    let f = of(id, "invalid_biped.urdf");
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].data["joints"], 8.0);
    assert_eq!(f[0].data["legs"], 2.0);
    names(&f[0], &["l_hip_roll", "l_ankle", "r_hip_roll", "r_ankle"], &[]);
    // The hips have a 6:1 transmission; the knees and the wheels at the shanks' ends none.
    let f = of(id, "invalid_wheel_legs.urdf");
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].data["joints"], 4.0);
    names(&f[0], &["left_knee", "left_wheel", "right_knee", "right_wheel"], &["left_hip"]);
    // The spec gives the four hip abduction joints a motor family.
    let f = of(id, "invalid_quadruped_part_spec.urdf");
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].data["joints"], 8.0);
    assert_eq!(f[0].data["legs"], 4.0);
    names(&f[0], &["FL_HFE", "HR_KFE"], &["FL_HAA", "HR_HAA"]);
    for v in [
        "valid_transmissions.urdf",
        "valid_direct_drive.urdf",
        "valid_arm_gripper.urdf",
        "valid_rover.urdf",
        "valid_mjcf_biped.xml",
    ] {
        assert!(of(id, v).is_empty(), "{v}");
    }
}

/// A leaf whose only colliding geometry is a speck at its far end (where a leaf touches) is a
/// token when the speck covers under a twentieth of the visual's width there; corner spheres
/// spread over a sole, a point foot's sphere across a shin's end and fingertip pads are
/// contacts.
#[test]
fn token_collision_geometry_at_a_leafs_tip_is_judged_against_the_ends_width() {
    let id = "token-collision-geometry";
    let f = of(id, "invalid_leaf_tip.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].measured.as_ref().unwrap().value, 3.0, "{f:?}");
    // Both feet (mirror images) alike; the left hand's 0.8 mm sphere on a 60 mm wide paddle;
    // the right hand's 16 mm pad is a contact.
    for l in [
        "`left_foot` (1 mm on a 80 mm wide visual end",
        "`right_foot` (1 mm on a 80 mm wide visual end",
        "`left_hand` (0.8 mm on a 60 mm wide visual end",
    ] {
        assert!(f[0].message.contains(l), "{}", f[0].message);
    }
    assert!(!f[0].message.contains("right_hand"), "{}", f[0].message);
    assert!((f[0].data["smallest_ratio"] - 75.0).abs() < 1e-6, "{:?}", f[0].data);
    for v in ["valid_tip_contacts.xml", "valid_leaf_contacts.xml", "valid_point_feet.xml"] {
        assert!(of(id, v).is_empty(), "{v}");
    }
}

/// A strap of four equal segments on hinges numbered `left_hand_strap_1..4` is not a limb; an
/// arm whose joints are numbered `left_arm_1..3` the same way, but whose segments differ in
/// mass, is.
#[test]
fn a_strap_of_equal_segments_is_not_a_limb_but_a_numbered_arm_is() {
    let id = "detached-limb";
    assert!(of(id, "valid_hinge_strap.xml").is_empty());
    let f = of(id, "invalid_numbered_arm.xml");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!((f[0].measured.as_ref().unwrap().value - 2.9).abs() < 1e-9, "{f:?}");
    assert!(f[0].message.contains("3 joints named for the robot's left side"), "{}", f[0].message);
}
