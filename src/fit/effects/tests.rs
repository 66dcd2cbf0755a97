/// Bounds on a servo of the strength the fixed bounds were set on (kp 50, 30 N·m) are the
/// fixed ones; a knee-sized servo (kp 400 with a gear of 2 → 1600 N·m/rad at the joint)
/// widens damping, friction and stiffness 16-fold and the effort limit to half a radian of
/// its error. The numbers are the ParamDef bounds times kp·gear²/100, worked by hand.
#[test]
fn a_strong_drive_widens_the_absolute_bounds() {
    use super::{JointTarget, by_id, hinge_robot, model_with};
    let dir = std::env::temp_dir().join(format!("modellint-strength-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let hi = |r: &crate::model::Robot, e: &str| {
        let t = JointTarget::of(r, "j").unwrap();
        by_id(e).unwrap().bounds(&model_with(r, &[]), &t).1
    };
    let small = hinge_robot(&dir, "small.xml", "", "", r#"kp="50" kv="2" forcerange="-30 30""#);
    assert_eq!(JointTarget::of(&small, "j").unwrap().strength(), 1.0);
    assert_eq!(hi(&small, "viscous_damping"), [5.0]);
    assert_eq!(hi(&small, "coulomb_friction"), [5.0]);
    assert_eq!(hi(&small, "joint_stiffness"), [20.0]);
    assert_eq!(hi(&small, "stribeck_friction"), [5.0, 5.0, 2.0]);
    assert_eq!(hi(&small, "load_dependent_friction"), [2.0, 0.5]);
    assert_eq!(hi(&small, "torque_limit")[0], 50.0);
    let big = hinge_robot(&dir, "big.xml", "", "", r#"kp="400" kv="10" gear="2""#);
    let t = JointTarget::of(&big, "j").unwrap();
    assert_eq!((t.servo_kp, t.max_torque, t.strength()), (1600.0, 0.0, 16.0));
    assert_eq!(hi(&big, "viscous_damping"), [80.0]);
    assert_eq!(hi(&big, "coulomb_friction"), [80.0]);
    assert_eq!(hi(&big, "joint_stiffness"), [320.0]);
    assert_eq!(hi(&big, "stribeck_friction"), [80.0, 80.0, 2.0]);
    assert_eq!(hi(&big, "load_dependent_friction"), [32.0, 0.5]);
    assert_eq!(hi(&big, "torque_limit")[0], 800.0);
    // The torque limit's start is no limit: the top of its box, not the 50 N·m default.
    let tl = by_id("torque_limit").unwrap();
    assert_eq!(tl.initial(&model_with(&big, &[]), &t)[0], 800.0);
    // A force-limited drive counts its declared torque (250 N·m × gear 2).
    let limited = hinge_robot(
        &dir,
        "limited.xml",
        "",
        "",
        r#"kp="20" kv="1" gear="2" forcelimited="true" forcerange="-250 250""#,
    );
    let t = JointTarget::of(&limited, "j").unwrap();
    assert_eq!((t.servo_kp, t.max_torque, t.strength()), (80.0, 500.0, 5.0));
    assert_eq!(hi(&limited, "torque_limit")[0], 500.0);
    // So does the joint's own actuator force range.
    let joint = hinge_robot(
        &dir,
        "joint.xml",
        "",
        r#"actuatorfrclimited="true" actuatorfrcrange="-60 60""#,
        r#"kp="20" kv="1""#,
    );
    assert_eq!(hi(&joint, "torque_limit")[0], 60.0);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn short_parameter_vectors_are_padded_with_defaults() {
    let multi: Vec<_> = super::all().into_iter().filter(|e| e.params().len() >= 2).collect();
    assert!(!multi.is_empty());
    for e in multi {
        let a = super::Applied { effect: e, joints: vec!["j".into()], params: vec![1.0] };
        let p = a.full_params();
        assert_eq!(p.len(), e.params().len());
        assert_eq!(p[0], 1.0);
        assert_eq!(p[1], e.params()[1].default);
        let full = super::Applied { params: p.to_vec(), ..a.clone() };
        assert!(matches!(full.full_params(), std::borrow::Cow::Borrowed(_)));
    }
}

#[test]
fn friction_absorbs_only_coulomb_friction() {
    use crate::fit::effects::{all, by_id};
    let (st, ldf, c, d) = (
        by_id("stribeck_friction").unwrap(),
        by_id("load_dependent_friction").unwrap(),
        by_id("coulomb_friction").unwrap(),
        by_id("viscous_damping").unwrap(),
    );
    assert_eq!(st.absorb(c, &[1.0, 0.1, 0.2], &[0.9]), Some(vec![1.9, 1.0, 0.2]));
    assert_eq!(ldf.absorb(c, &[0.1, 0.05], &[0.4]), Some(vec![0.5, 0.05]));
    assert_eq!(st.absorb(d, &[1.0, 0.1, 0.2], &[0.9]), None);
    assert_eq!(c.absorb(st, &[0.9], &[1.0, 0.1, 0.2]), None);
    assert_eq!(st.absorb(st, &[1.0, 0.1, 0.2], &[1.0, 0.1, 0.2]), None);
    for e in all() {
        if !["stribeck_friction", "load_dependent_friction"].contains(&e.id()) {
            assert_eq!(e.absorb(c, &[0.0; 4], &[0.1]), None, "{}", e.id());
        }
    }
}

#[test]
fn ids_are_unique_and_found() {
    let all = super::all();
    for (i, e) in all.iter().enumerate() {
        assert!(all[..i].iter().all(|x| x.id() != e.id()), "{} twice", e.id());
        assert_eq!(super::by_id(e.id()).map(|x| x.id()), Some(e.id()));
        assert!(e.fitted() >= 1 && e.fitted() <= e.params().len(), "{}", e.id());
    }
    assert!(super::by_id("no_such_effect").is_none());
}

/// The diagnosis's probe without evidence: the default 5 % step (down from the upper
/// bound), or no probe for an effect that needs its evidence (torque_limit) — never a value
/// outside the bounds.
#[test]
fn probe_steps_stay_within_bounds() {
    let none = std::collections::BTreeMap::new();
    let mut stepped = 0;
    for e in super::all() {
        let d = e.params()[0];
        let step = 0.05 * (d.hi - d.lo);
        for (start, want) in [(d.lo, d.lo + step), (d.hi, d.hi - step)] {
            for v in e.probes(start, d.lo, d.hi, &none) {
                assert_eq!(v, want, "{}: from {start}", e.id());
                stepped += 1;
            }
        }
    }
    assert_eq!(stepped, 2 * (super::all().len() - 1));
}

#[test]
fn num_trims_zeros_and_negative_zero() {
    assert_eq!(super::num(0.1), "0.1");
    assert_eq!(super::num(50.0), "50");
    assert_eq!(super::num(-1e-9), "0");
    assert_eq!(super::num(1.23456789), "1.234568");
}

/// A two-link arm under gravity (shoulder and elbow position servos), written to `dir/name` with
/// `extra` inside the forearm body and `forearm` as the forearm's geom attributes, and loaded.
#[cfg(test)]
fn arm_with(dir: &std::path::Path, name: &str, extra: &str, forearm: &str) -> crate::model::Robot {
    let xml = format!(
        r#"<mujoco><option gravity="0 0 -9.81" timestep="0.002"/>
  <worldbody><body name="upper"><joint name="shoulder" type="hinge" axis="0 1 0"/>
    <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.03" mass="1.2"/>
    <body name="fore" pos="0 0 -0.3"><joint name="elbow" type="hinge" axis="0 1 0" stiffness="0.8" springref="0.3"/>
      <geom type="capsule" {forearm} size="0.025" mass="0.8"/>{extra}
    </body></body></worldbody>
  <actuator><position joint="shoulder" kp="60" kv="2"/><position joint="elbow" kp="30" kv="1"/></actuator>
</mujoco>"#
    );
    let path = dir.join(name);
    std::fs::write(&path, xml).expect("write the test model");
    let mut map = crate::model::source::SourceMap::default();
    crate::model::load(&mut map, &path, None).expect("load the test model")
}

/// Both joints commanded through steps and a sine for 1.5 s at 100 Hz.
#[cfg(test)]
fn arm_recording() -> crate::sim2real::recording::Recording {
    use crate::sim2real::recording::{JointTrace, Recording};
    let t: Vec<f64> = (0..150).map(|i| i as f64 * 0.01).collect();
    let mk = |name: &str, f: &dyn Fn(f64) -> f64| {
        let mut j = JointTrace::new(name, vec![0.0; t.len()]);
        j.q_cmd = Some(t.iter().map(|&x| f(x)).collect());
        j.qd = Some(vec![0.0; t.len()]);
        j
    };
    let sh = mk("shoulder", &|x| if x < 0.5 { 0.0 } else { 0.6 * (3.0 * x).sin() });
    let el = mk("elbow", &|x| {
        if x < 0.3 {
            0.0
        } else if x < 0.9 {
            0.8
        } else {
            -0.4
        }
    });
    Recording::at_100hz(t, vec![sh, el])
}

/// Largest difference between the replays of `a` (with effects `ea`) and `b` (with none).
#[cfg(test)]
fn replay_gap(a: &crate::model::Robot, ea: &[super::Applied], b: &crate::model::Robot) -> f64 {
    use crate::sim2real::replay::ReplayOptions;
    let rec = arm_recording();
    let opts = ReplayOptions::default();
    let x = super::simulate(a, std::slice::from_ref(&rec), ea, &opts).remove(0).unwrap();
    let y = super::simulate(b, std::slice::from_ref(&rec), &[], &opts).remove(0).unwrap();
    let moved = x.q_sim.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(moved > 0.3, "the arm moves ({moved})");
    x.q_sim
        .iter()
        .flatten()
        .zip(y.q_sim.iter().flatten())
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f64::max)
}

/// `link_mass` on the elbow moves the arm as MuJoCo's own compiler composes a forearm carrying
/// a 0.3 kg sphere (0.5 mm: a point) as a child body 0.07 m beyond its centre of mass (along the link),
/// and 0.03 m across the link beside that — the
/// parallel-axis algebra of `inertial.rs` against MuJoCo's; `com_offset` (along 0.02, across
/// −0.015) as the forearm's capsule moved by (0.015, 0, −0.02) (across = joint axis y × link
/// axis −z = −x). Without the effects the replays differ by centimetres.
#[test]
fn body_effects_move_the_arm_as_mujoco_composes_the_body() {
    use super::{Applied, by_id};
    let dir = std::env::temp_dir().join(format!("modellint-body-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let nominal = arm_with(&dir, "nominal.xml", "", r#"fromto="0 0 0 0 0 -0.25""#);
    let payload = arm_with(
        &dir,
        "payload.xml",
        r#"<body pos="0 0 -0.195"><geom type="sphere" size="0.0005" mass="0.3"/></body>"#,
        r#"fromto="0 0 0 0 0 -0.25""#,
    );
    let link_mass = Applied {
        effect: by_id("link_mass").unwrap(),
        joints: vec!["elbow".into()],
        params: vec![0.3, 0.07],
    };
    assert!(replay_gap(&nominal, &[], &payload) > 5e-3);
    let d = replay_gap(&nominal, std::slice::from_ref(&link_mass), &payload);
    assert!(d < 1e-6, "link_mass vs the composed payload: {d}");
    // Off the link's axis: 0.03 m across it (joint axis y × link axis −z = −x).
    let aside = arm_with(
        &dir,
        "aside.xml",
        r#"<body pos="-0.03 0 -0.195"><geom type="sphere" size="0.0005" mass="0.3"/></body>"#,
        r#"fromto="0 0 0 0 0 -0.25""#,
    );
    let on_axis = replay_gap(&nominal, std::slice::from_ref(&link_mass), &aside);
    assert!(on_axis > 1e-3, "the place across the link moves the arm ({on_axis})");
    let across = Applied { params: vec![0.3, 0.07, 0.03], ..link_mass.clone() };
    let d = replay_gap(&nominal, &[across], &aside);
    assert!(d < 1e-6, "link_mass across the link vs the composed payload: {d}");
    let shifted = arm_with(&dir, "shifted.xml", "", r#"fromto="0.015 0 -0.02 0.015 0 -0.27""#);
    let com = Applied {
        effect: by_id("com_offset").unwrap(),
        joints: vec!["elbow".into()],
        params: vec![0.02, -0.015],
    };
    assert!(replay_gap(&nominal, &[], &shifted) > 2e-3);
    let d = replay_gap(&nominal, &[com], &shifted);
    assert!(d < 1e-6, "com_offset vs the moved capsule: {d}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A body effect with one component held (`EFFECT~PARAMETER`, what the floor's rival fits) is
/// the full effect with that parameter at its nominal value: the same replay, one parameter
/// fewer in its list, its bounds and its start; a parameter that is no declared component names
/// nothing.
#[test]
fn a_held_component_is_the_effect_with_it_at_its_nominal_value() {
    use super::{Applied, JointTarget, by_id};
    let dir = std::env::temp_dir().join(format!("modellint-held-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let arm = arm_with(&dir, "nominal.xml", "", r#"fromto="0 0 0 0 0 -0.25""#);
    let t = JointTarget::of(&arm, "elbow").unwrap();
    let on = |id: &str, params: Vec<f64>| Applied {
        effect: by_id(id).unwrap(),
        joints: vec!["elbow".into()],
        params,
    };
    let replay = |a: &Applied| {
        let rec = arm_recording();
        let o = crate::sim2real::replay::ReplayOptions::default();
        super::simulate(&arm, std::slice::from_ref(&rec), std::slice::from_ref(a), &o)
            .remove(0)
            .unwrap()
            .q_sim
    };
    let cases = [
        ("com_offset~along", vec![-0.015, 0.0], vec![0.0, -0.015, 0.0]),
        ("com_offset~across", vec![0.02, 0.0], vec![0.02, 0.0, 0.0]),
        ("link_mass~offset", vec![0.3, 0.03, 0.0], vec![0.3, 0.0, 0.03, 0.0]),
        ("link_mass~across", vec![0.3, 0.07, 0.0], vec![0.3, 0.07, 0.0, 0.0]),
    ];
    for (id, held, full) in cases {
        let h = by_id(id).unwrap_or_else(|| panic!("{id}"));
        let (base, name) = id.split_once('~').unwrap();
        let e = by_id(base).unwrap();
        assert_eq!(h.id(), id);
        assert_eq!(h.params().len() + 1, e.params().len(), "{id}");
        assert!(h.params().iter().all(|p| p.name != name), "{id}");
        assert_eq!(h.fitted(), e.fitted() - 1, "{id}");
        let (lo, hi) = h.bounds(&arm.mj, &t);
        assert_eq!(
            (lo.len(), hi.len(), h.initial(&arm.mj, &t).len()),
            (held.len(), held.len(), held.len())
        );
        assert!(!h.by_default(), "{id} is no candidate of the search");
        let k = e.held_components().iter().find(|(_, v)| v.id() == id).map(|(k, _)| *k).unwrap();
        assert_eq!(e.params()[k].name, name);
        let (x, y) = (replay(&on(id, held.clone())), replay(&on(base, full.clone())));
        assert_eq!(x, y, "{id}: {held:?} replays as {base} {full:?}");
        // And not as the effect with that component moved.
        let mut other = full.clone();
        other[k] += 0.05;
        assert_ne!(x, replay(&on(base, other)), "{id}");
    }
    assert!(by_id("link_mass~added_mass").is_none());
    assert!(by_id("com_offset~nothing").is_none());
    assert!(by_id("armature~armature").is_none());
    std::fs::remove_dir_all(&dir).ok();
}

/// `link_inertia` scales the forearm's inertia about the elbow axis through its centre of mass
/// by `inertia_scale` and leaves its mass and centre of mass; every scale in the bounds is a
/// valid body (principal moments obey the triangle inequality) — a capsule squashed to a
/// quarter and stretched to four times.
#[test]
fn link_inertia_scales_the_moment_about_the_joint_axis_and_stays_a_body() {
    use super::{Applied, by_id, inertial, model_with};
    let dir = std::env::temp_dir().join(format!("modellint-inertia-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let robot = arm_with(&dir, "arm.xml", "", r#"fromto="0 0 0 0 0 -0.25""#);
    let b = robot.mj.jnt_bodyid()[robot.joint("elbow").unwrap().id] as usize;
    let (m0, c0, i0) = inertial::read(&robot.mj, b).unwrap();
    let y: nalgebra::Vector3<f64> = nalgebra::Vector3::y();
    for k in [0.25, 0.7, 1.0, 2.5, 4.0] {
        let a = Applied {
            effect: by_id("link_inertia").unwrap(),
            joints: vec!["elbow".into()],
            params: vec![k],
        };
        let m = model_with(&robot, &[a]);
        let (m1, c1, i1) = inertial::read(&m, b).unwrap();
        assert_eq!(m1, m0);
        assert!((c1 - c0).norm() < 1e-12);
        let (about0, about1) = (y.dot(&(i0 * y)), y.dot(&(i1 * y)));
        assert!((about1 - k * about0).abs() < 1e-12, "{k}: {about1} vs {}", k * about0);
        assert!(inertial::valid(m.body_inertia()[b]), "{k}: {:?}", m.body_inertia()[b]);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A thin rod (a forearm whose inertia is a rod's along the link: `m L²/12` about the two axes
/// across it, 1e-7 kg·m² about its own) scaled by `link_inertia` in the elbow's plane stays a
/// rigid body at every scale of the bounds, and its moment about the elbow axis is scaled
/// exactly. Scaling the moment about the axis alone, or the moments about the plane's two axes
/// (the rod's own and the one across it), would not be a body at 4× — one moment would exceed
/// the sum of the other two — and the validity check here fails on either.
#[test]
fn link_inertia_keeps_a_thin_rod_a_rigid_body() {
    use super::{Applied, by_id, inertial, model_with};
    let dir = std::env::temp_dir().join(format!("modellint-rod-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rod = r#"<inertial pos="0 0 -0.125" mass="0.8" diaginertia="0.0041667 0.0041667 1e-7"/>"#;
    let robot =
        arm_with(&dir, "rod.xml", rod, r#"fromto="0 0 0 0 0 -0.25" contype="0" conaffinity="0""#);
    let b = robot.mj.jnt_bodyid()[robot.joint("elbow").unwrap().id] as usize;
    let d0 = robot.mj.body_inertia()[b];
    assert!(d0.iter().any(|&x| x < 1e-6), "a thin rod: {d0:?}");
    let (_, _, i0) = inertial::read(&robot.mj, b).unwrap();
    let y: nalgebra::Vector3<f64> = nalgebra::Vector3::y();
    for k in [0.25, 0.5, 2.0, 4.0] {
        let a = Applied {
            effect: by_id("link_inertia").unwrap(),
            joints: vec!["elbow".into()],
            params: vec![k],
        };
        let m = model_with(&robot, &[a]);
        let (_, _, i1) = inertial::read(&m, b).unwrap();
        assert!(inertial::valid(m.body_inertia()[b]), "{k}: {:?}", m.body_inertia()[b]);
        let (about0, about1) = (y.dot(&(i0 * y)), y.dot(&(i1 * y)));
        assert!(
            (about1 - k * about0).abs() < 1e-12 * about0.max(1.0),
            "{k}: {about1} vs {}",
            k * about0
        );
    }
    // The naive alternatives at 4×: the moment about the elbow axis alone, or the moments
    // about the two axes of the elbow's plane (x and z) — neither is a body.
    let (x, z) = (nalgebra::Vector3::x(), nalgebra::Vector3::z());
    let (ix, iy, iz) = (x.dot(&(i0 * x)), y.dot(&(i0 * y)), z.dot(&(i0 * z)));
    assert!(!inertial::valid([ix, 4.0 * iy, iz]), "the moment about y alone");
    assert!(!inertial::valid([4.0 * ix, iy, 4.0 * iz]), "the moments about x and z");
    std::fs::remove_dir_all(&dir).ok();
}

/// A body effect groups only alike links: the quadruped's four shanks (0.5 kg capsule and a
/// 0.1 kg foot each) are alike, a shank and a thigh are not; a joint effect groups any joints.
#[test]
fn body_effects_group_alike_links_only() {
    use super::{JointTarget, by_id};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("bench/independent_py/models/quad12.xml");
    let mut map = crate::model::source::SourceMap::default();
    let robot = crate::model::load(&mut map, &path, None).expect("load quad12");
    let t = |j: &str| JointTarget::of(&robot, j).unwrap();
    let (fl, rr, thigh) = (t("FL_knee"), t("RR_knee"), t("FL_hip_pitch"));
    for id in ["link_mass", "com_offset", "link_inertia"] {
        let e = by_id(id).unwrap();
        assert!(e.alike(&fl, &rr), "{id}: two shanks");
        assert!(!e.alike(&fl, &thigh), "{id}: a shank and a thigh");
    }
    assert!(by_id("armature").unwrap().alike(&fl, &thigh));
}

/// The directions of a body's place span what the joints moving it can see: on the
/// `arm4y.xml` arm (pitch y → roll x → yaw z, the upper arm hanging along the yaw's axis) the
/// yaw's link gets the two perpendiculars to its axis besides the link's own direction, and the
/// third one is a parameter; on the planar arm of [`arm_with`] (two parallel hinges) the third
/// direction is the joints' axis, which no rotation moves the body along: bounds of zero width.
#[test]
fn a_body_place_has_every_direction_its_carrying_joints_see() {
    use super::{JointTarget, by_id};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("bench/independent_py/models/arm4y.xml");
    let mut map = crate::model::source::SourceMap::default();
    let arm = crate::model::load(&mut map, &path, None).expect("load arm4y");
    let b = JointTarget::of(&arm, "shoulder_yaw").unwrap().body.unwrap();
    let dot = |x: [f64; 3], y: [f64; 3]| (0..3).map(|k| x[k] * y[k]).sum::<f64>();
    assert!((dot(b.along, [0.0, 0.0, -1.0]) - 1.0).abs() < 1e-9, "{:?}", b.along);
    for d in [b.across, b.normal] {
        assert!(dot(d, b.axis).abs() < 1e-9 && (dot(d, d) - 1.0).abs() < 1e-9, "{d:?}");
    }
    assert!(dot(b.across, b.normal).abs() < 1e-9 && b.normal_seen);
    let t = JointTarget::of(&arm, "shoulder_yaw").unwrap();
    for id in ["com_offset", "link_mass"] {
        let (lo, hi) = by_id(id).unwrap().bounds(&arm.mj, &t);
        assert!(lo.iter().zip(&hi).skip(1).all(|(l, h)| h > l), "{id}: {lo:?} {hi:?}");
    }
    let dir = std::env::temp_dir().join(format!("modellint-planar-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let planar = arm_with(&dir, "planar.xml", "", r#"fromto="0 0 0 0 0 -0.25""#);
    let t = JointTarget::of(&planar, "elbow").unwrap();
    let b = t.body.unwrap();
    assert!((dot(b.normal, b.axis).abs() - 1.0).abs() < 1e-9 && !b.normal_seen);
    let (lo, hi) = by_id("com_offset").unwrap().bounds(&planar.mj, &t);
    assert!(lo[2] == 0.0 && hi[2] == 0.0 && hi[0] > lo[0] && hi[1] > lo[1], "{lo:?} {hi:?}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A mirror pair shares one body effect only over alike links: the quadruped's front shanks
/// (`FL_knee` ↔ `FR_knee`, as `mirror_name` pairs them) are alike; with a 0.3 kg box bolted to
/// the right shank alone they are not, and neither is any group holding both (every leg), while
/// a joint effect still groups them.
#[test]
fn mirror_pairs_share_a_body_effect_only_over_alike_links() {
    use super::{alike_over, by_id};
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("bench/independent_py/models/quad12.xml");
    let xml = std::fs::read_to_string(&src).unwrap();
    let load = |xml: &str, name: &str| {
        let dir = std::env::temp_dir().join(format!("modellint-mirror-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, xml).unwrap();
        let mut map = crate::model::source::SourceMap::default();
        crate::model::load(&mut map, &path, None).expect("load quad12")
    };
    let mark = r#"<geom name="FR_foot""#;
    assert!(xml.contains(mark));
    let battery = r#"<geom name="FR_battery" type="box" pos="0.03 0 -0.08" size="0.02 0.02 0.03" mass="0.3"/>"#;
    let uneven = xml.replacen(mark, &format!("{battery}\n{mark}"), 1);
    let (even, uneven) = (load(&xml, "even.xml"), load(&uneven, "uneven.xml"));
    let pair = ["FL_knee".to_string(), "FR_knee".to_string()];
    assert_eq!(crate::model::mirror::mirror_name(&pair[0]).as_deref(), Some("FR_knee"));
    let legs: Vec<String> =
        ["FL_knee", "FR_knee", "RL_knee", "RR_knee"].iter().map(|s| s.to_string()).collect();
    for id in ["link_mass", "com_offset", "link_inertia"] {
        let e = by_id(id).unwrap();
        assert!(alike_over(&even, e, &pair), "{id}: the even front shanks");
        assert!(alike_over(&even, e, &legs), "{id}: the even four shanks");
        assert!(!alike_over(&uneven, e, &pair), "{id}: a battery on the right shank alone");
        assert!(!alike_over(&uneven, e, &legs), "{id}: every leg, one with a battery");
        assert!(alike_over(&uneven, e, &pair[..1]), "{id}: one joint");
    }
    assert!(alike_over(&uneven, by_id("armature").unwrap(), &pair));
    assert!(!alike_over(&even, by_id("armature").unwrap(), &["no_such_joint".to_string()]));
}

/// Inside the play the servo applies no force at all (neither its `kp` nor its `kd` term), with
/// or without a rotor inertia; on a flank it acts on the link with its set-point moved by half
/// the play. Torques from [`super::servo_torque`], the actuator law `kp (ctrl − q) − kd q̇`.
#[test]
fn backlash_applies_no_servo_force_inside_the_play() {
    use super::{Backlash, Effect, EffectState, HookCtx, servo_torque};
    use crate::sim2real::replay::StepIo;
    for armature in [0.0, 0.01] {
        let io0 = StepIo {
            kp: 50.0,
            kd: 2.0,
            enabled: true,
            armature,
            inertia: 0.02,
            ..Default::default()
        };
        let run = |u: f64, q: f64, qd: f64| {
            let (mut st, mut io) = (EffectState::default(), StepIo { ctrl: u, ..io0 });
            let p = [0.1];
            Backlash.torque(HookCtx {
                st: &mut st,
                q,
                qd,
                q_target: u,
                io: &mut io,
                dt: 0.001,
                p: &p,
            });
            (servo_torque(q, qd, &io), io.tau)
        };
        // 0.03 rad of error, within the ±0.05 play, the link moving at 0.8 rad/s.
        let (tau, extra) = run(0.33, 0.3, 0.8);
        assert!(tau.abs() < 1e-9 && extra == 0.0, "armature {armature}: {tau} + {extra}");
        // 0.2 rad of error: 0.15 beyond the flank, kp·0.15 − kd·0.8 = 5.9.
        let (tau, extra) = run(0.5, 0.3, 0.8);
        assert!((tau - 5.9).abs() < 1e-9 && extra == 0.0, "armature {armature}: {tau} + {extra}");
    }
}

/// A link set moving at 0.5 rad/s with its command at its start, no gravity and no damping:
/// inside the play (±0.05 rad) nothing brakes it, so it coasts at 0.5 rad/s until it meets the
/// rotor (held near the command by its servo) about 0.05 rad on, and is then pulled back. With
/// the servo's damping left on inside the play (kv 2 on ≈ 0.017 kg·m²: a 9 ms time constant)
/// it would stop within ≈ 5 mrad.
#[test]
fn backlash_lets_the_link_coast_through_the_play() {
    use super::{Applied, Backlash, hinge_recording, hinge_robot, simulate};
    use crate::sim2real::replay::ReplayOptions;
    let dir = std::env::temp_dir().join(format!("modellint-play-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let robot = hinge_robot(&dir, "play.xml", "", r#"armature="0.01""#, r#"kp="50" kv="2""#);
    let t: Vec<f64> = (0..40).map(|i| i as f64 * 0.005).collect();
    let mut rec = hinge_recording(t.clone(), vec![0.0; t.len()]);
    rec.joints[0].qd.as_mut().unwrap()[0] = 0.5;
    let applied = [Applied { effect: &Backlash, joints: vec!["j".into()], params: vec![0.1] }];
    let ep = simulate(&robot, &[rec], &applied, &ReplayOptions::default()).remove(0).unwrap();
    let q = &ep.q_sim[0];
    // At 60 ms: 0.5 × 0.06 = 0.030 rad coasted.
    let i = t.iter().position(|&x| x >= 0.06 - 1e-9).unwrap();
    assert!((q[i] - 0.030).abs() < 0.003, "q(60 ms) = {}", q[i]);
    let peak = q.iter().cloned().fold(f64::MIN, f64::max);
    assert!(peak > 0.045 && peak < 0.07, "the link is caught near the flank: peak {peak}");
    std::fs::remove_dir_all(&dir).ok();
}

/// On a link that only its own joint moves (the leg's thigh under a welded stand) a change of
/// its moment about the joint axis changes the mass matrix exactly as the joint's armature
/// does (one diagonal entry): link_inertia is no candidate there. On the shank (carried by the
/// hip) it also changes the hip's row, which armature never does: a candidate. The mass
/// matrices are MuJoCo's (`mj_fullM`) at the keyframe.
#[test]
fn link_inertia_is_a_candidate_only_where_armature_cannot_stand_in_for_it() {
    use super::{Applied, JointTarget, by_id, model_with};
    use mujoco_rs::prelude::MjData;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("bench/independent_py/models/leg3.xml");
    let mut map = crate::model::source::SourceMap::default();
    let robot = crate::model::load(&mut map, &path, None).expect("load leg3");
    let e = by_id("link_inertia").unwrap();
    let t = |j: &str| JointTarget::of(&robot, j).unwrap();
    assert!(!e.acts_on(&t("hip_pitch")), "the thigh: only the hip moves it");
    assert!(e.acts_on(&t("knee")) && e.acts_on(&t("ankle")), "shank and foot are carried");
    let mass = |applied: &[Applied]| {
        let m = model_with(&robot, applied);
        let mut d = MjData::new(&m);
        let _ = d.reset_keyframe(0);
        d.forward();
        crate::model::mj::full_mass_matrix(&d)
    };
    let m0 = mass(&[]);
    let on = |j: &str, id: &str, p: f64| Applied {
        effect: by_id(id).unwrap(),
        joints: vec![j.into()],
        params: vec![p],
    };
    for (joint, dof) in [("hip_pitch", 0), ("knee", 1)] {
        let m1 = mass(&[on(joint, "link_inertia", 2.0)]);
        let changed: Vec<usize> = (0..9).filter(|&k| (m1[k] - m0[k]).abs() > 1e-12).collect();
        if joint == "hip_pitch" {
            assert_eq!(changed, [0], "{m0:?} → {m1:?}");
            // the same as armature raised by the change
            let base = robot.mj.dof_armature()[dof];
            let m2 = mass(&[on(joint, "armature", base + m1[0] - m0[0])]);
            assert!(m2.iter().zip(&m1).all(|(a, b)| (a - b).abs() < 1e-12), "{m2:?} vs {m1:?}");
        } else {
            assert_eq!(changed, [0, 1, 3, 4], "the hip's row too: {m0:?} → {m1:?}");
        }
    }
}

/// An effect that declares its start neutral ([`super::Effect::neutral_start`]) replays, at its
/// start on either joint, bit for bit as the model without it — on an arm whose joints carry
/// armature, damping and friction of their own, so that a native parameter is written back at
/// the model's value. Stribeck friction's start (a guess of 0.1 / 0.05 N·m) is no such start:
/// it moves the arm, and the comparison tells. A joint stiffness is neutral only where the
/// model's own is zero ([`super::Effect::neutral_at`]): on the elbow's own spring (0.8 N·m/rad
/// towards 0.3 rad) its start moves the spring's reference to the keyframe, and the arm.
#[test]
fn a_neutral_start_replays_exactly_as_the_model_without_the_effect() {
    use super::{Applied, Effect, JointTarget, all, by_id, model_with, simulate};
    use crate::sim2real::replay::ReplayOptions;
    let dir = std::env::temp_dir().join(format!("modellint-neutral-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let xml = r#"<mujoco><option gravity="0 0 -9.81" timestep="0.002"/>
  <default><joint armature="0.013" damping="0.31" frictionloss="0.07"/></default>
  <worldbody><body name="upper"><joint name="shoulder" type="hinge" axis="0 1 0"/>
    <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.03" mass="1.2"/>
    <body name="fore" pos="0 0 -0.3"><joint name="elbow" type="hinge" axis="0 1 0" stiffness="0.8" springref="0.3"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.25" size="0.025" mass="0.8"/>
    </body></body></worldbody>
  <actuator><position joint="shoulder" kp="60" kv="2"/><position joint="elbow" kp="30" kv="1"/></actuator>
</mujoco>"#;
    let path = dir.join("arm.xml");
    std::fs::write(&path, xml).unwrap();
    let mut map = crate::model::source::SourceMap::default();
    let robot = crate::model::load(&mut map, &path, None).expect("load the test model");
    let rec = arm_recording();
    let opts = ReplayOptions::default();
    let run = |a: &[Applied]| {
        simulate(&robot, std::slice::from_ref(&rec), a, &opts).remove(0).expect("replays").q_sim
    };
    let bits =
        |q: Vec<Vec<f64>>| -> Vec<u64> { q.into_iter().flatten().map(f64::to_bits).collect() };
    let base = bits(run(&[]));
    let m0 = model_with(&robot, &[]);
    let at_start = |e: &'static dyn Effect, j: &str| {
        let t = JointTarget::of(&robot, j).expect("a joint");
        Applied { effect: e, joints: vec![j.into()], params: e.initial(&m0, &t) }
    };
    let target = |j: &str| JointTarget::of(&robot, j).expect("a joint");
    let mut neutral = 0;
    for e in all() {
        for j in ["shoulder", "elbow"] {
            if e.neutral_at(&m0, &target(j)) {
                assert!(bits(run(&[at_start(e, j)])) == base, "{} at its start on {j}", e.id());
                neutral += 1;
            }
        }
    }
    assert!(neutral >= 11, "{neutral} (effect, joint) starts declared neutral");
    let stiffness = by_id("joint_stiffness").expect("known");
    assert!(stiffness.neutral_at(&m0, &target("shoulder")));
    assert!(!stiffness.neutral_at(&m0, &target("elbow")));
    assert!(bits(run(&[at_start(stiffness, "elbow")])) != base, "the elbow's spring moves");
    let stribeck = by_id("stribeck_friction").expect("known");
    assert!(!stribeck.neutral_start());
    assert!(bits(run(&[at_start(stribeck, "elbow")])) != base, "Stribeck's start acts");
    std::fs::remove_dir_all(&dir).ok();
}

/// A gripper's fingers: one position servo on `driver`, `follower` coupled to it by an
/// equality, `spread` driven by a motor through a tendon, `idle` free. An effect of the actuator
/// (its gains, its delay, its torque limit, its play) is a candidate only on the joints an
/// actuator reaches; a passive joint keeps the joint effects (friction, damping, armature).
#[test]
fn actuator_effects_act_only_on_driven_joints() {
    use super::{JointTarget, all, by_id};
    let dir = std::env::temp_dir().join(format!("modellint-driven-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("grip.xml");
    std::fs::write(
        &path,
        r#"<mujoco><worldbody><body name="a"><joint name="driver" axis="0 1 0"/>
<geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01"/>
<body name="b" pos="0.1 0 0"><joint name="follower" axis="0 1 0"/>
<geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01"/></body>
<body name="c" pos="0 0.05 0"><joint name="spread" axis="0 0 1"/>
<geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01"/></body>
<body name="d" pos="0 -0.05 0"><joint name="idle" axis="0 0 1"/>
<geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01"/></body></body></worldbody>
<tendon><fixed name="t"><joint joint="spread" coef="1"/></fixed></tendon>
<equality><joint joint1="driver" joint2="follower"/></equality>
<actuator><position joint="driver" kp="5" kv="0.1"/><motor tendon="t"/></actuator></mujoco>"#,
    )
    .unwrap();
    let mut map = crate::model::source::SourceMap::default();
    let robot = crate::model::load(&mut map, &path, None).expect("load the gripper");
    let t = |j: &str| JointTarget::of(&robot, j).unwrap();
    let servo = ["gain_error", "motor_constants", "torque_off_braking", "backlash"];
    let actuator = ["action_delay", "torque_limit"];
    for id in servo.iter().chain(&actuator) {
        let e = by_id(id).unwrap();
        assert!(e.acts_on(&t("driver")), "{id} on the servo's joint");
        assert!(!e.acts_on(&t("follower")), "{id} on a joint only an equality moves");
        assert!(!e.acts_on(&t("idle")), "{id} on a joint nothing drives");
        let on_motor = actuator.contains(id);
        assert_eq!(e.acts_on(&t("spread")), on_motor, "{id} on a motor's tendon joint");
        // Nor is a group that holds the passive joint shared (a mirror pair, a merge).
        assert!(!super::alike_over(&robot, e, &["driver".into(), "follower".into()]), "{id}");
    }
    for e in all().into_iter().filter(|e| !servo.contains(&e.id()) && !actuator.contains(&e.id())) {
        if ["viscous_damping", "coulomb_friction", "armature", "joint_stiffness"].contains(&e.id())
        {
            assert!(e.acts_on(&t("follower")), "{} is the joint's own", e.id());
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
