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
