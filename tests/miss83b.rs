//! The classes the twentieth and twenty-first rounds left or disputed, fixed from the class
//! (docs/audit.md, "Classes missed by the rounds, fixed from the class (21b)"), run from the CLI.
//! What each test expects is worked out from the fixtures' written text (sphere sizes, joint
//! positions, densities and geom sizes) and the rules' documented defaults, not from the code
//! under test.

mod common;

use common::lint::{findings, message, of, option};
use common::xml_text::{attr, tags};

const FC: &str = "fixtures/rules/foot-collision-geometry/";
const RS: &str = "fixtures/rules/robot-scale/";

fn nums(tag: &str, name: &str) -> Vec<f64> {
    attr(tag, name)
        .unwrap_or_else(|| panic!("{tag}: no {name}"))
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect()
}

/// The point-foot quadruped fixtures: every leg hangs from its thigh body's origin (the hip
/// hinge) through a knee `pos` to a foot sphere at `pos` in the calf; the leg's length is the
/// distance from the hip anchor to the sphere's centre, summed from the written offsets (the
/// legs are straight down at qpos0). Returns (sphere radius, leg length).
fn radius_and_leg(text: &str) -> (f64, f64) {
    let foot = tags(text, "geom")
        .into_iter()
        .find(|t| attr(t, "name") == Some("FL_foot"))
        .expect("FL_foot");
    let calf = tags(text, "body")
        .into_iter()
        .find(|t| attr(t, "name") == Some("FL_calf"))
        .expect("FL_calf");
    let (r, fp, cp) = (nums(foot, "size")[0], nums(foot, "pos"), nums(calf, "pos"));
    let drop = (0..3).map(|i| fp[i] + cp[i]).map(|x| x * x).sum::<f64>().sqrt();
    (r, drop)
}

/// A contact sphere out of proportion with its leg (0.22 m on a 0.4 m leg: its diameter above
/// the leg's length) is worded as a unit or scale error; the same robot with 80 mm spheres
/// (dm_control's quadruped's toes, 20 % of the leg) is told the size is the feet's design, with
/// the contact point's travel per 10° of tilt (r × π/18).
#[test]
fn contact_radius_unit_wording_follows_the_leg() {
    let hi = option("foot-collision-geometry", "unit_max_leg_fraction");
    let rmax = option("foot-collision-geometry", "max_radius");
    for (file, unit) in
        [("invalid_point_foot_radius.xml", true), ("invalid_large_toe_spheres_design.xml", false)]
    {
        let path = format!("{FC}{file}");
        let text = std::fs::read_to_string(&path).unwrap();
        let (r, leg) = radius_and_leg(&text);
        assert!(r > rmax, "{file}: {r} m is within the band");
        assert_eq!(r > hi * leg, unit, "{file}: {r} m on a {leg} m leg");
        let all = findings(&path);
        let hits: Vec<_> = of(&all, "foot-collision-geometry")
            .into_iter()
            .filter(|f| message(f).contains("contact radius"))
            .collect();
        assert_eq!(hits.len(), 4, "{file}: one per foot: {hits:#?}");
        for f in hits {
            let whole = f.to_string();
            assert_eq!(whole.contains("unit or scale error"), unit, "{file}: {whole}");
            assert_eq!(whole.contains("the foot's design"), !unit, "{file}: {whole}");
            let pct = format!("is {} % of the", (100.0 * r / leg).round());
            assert!(whole.contains(&pct), "{file}: {pct} in {whole}");
            if !unit {
                let travel = (r * std::f64::consts::PI / 18.0 * 1000.0).round();
                assert!(whole.contains(&format!("travels {travel} mm")), "{file}: {whole}");
            }
        }
    }
}

/// The geoms' written density and the robot's mass MuJoCo derives from it: Σ density × volume
/// of the capsules (`fromto` length, `size` radius) and spheres.
fn density_mass(text: &str) -> (f64, f64) {
    use std::f64::consts::PI;
    let default = tags(text, "geom").into_iter().find(|t| attr(t, "density").is_some()).unwrap();
    let rho: f64 = attr(default, "density").unwrap().parse().unwrap();
    let mut volume = 0.0;
    for g in tags(text, "geom") {
        let r = match attr(g, "size") {
            Some(_) => nums(g, "size")[0],
            None => continue,
        };
        match attr(g, "type") {
            Some("sphere") => volume += 4.0 / 3.0 * PI * r.powi(3),
            Some("capsule") => {
                let f = nums(g, "fromto");
                let len = (0..3).map(|i| (f[i + 3] - f[i]).powi(2)).sum::<f64>().sqrt();
                volume += PI * r * r * len + 4.0 / 3.0 * PI * r.powi(3);
            }
            _ => {}
        }
    }
    (rho, rho * volume)
}

/// A robot weighed from `density="5"` (gym's Ant) is told the density is the evidence, with the
/// density written and the mass it makes; the same robot at 300 kg/m³ is not reported, and the
/// decimetre biped, whose masses the file states, keeps the lengths' wording.
#[test]
fn robot_scale_names_a_density_below_any_solid() {
    let material = option("robot-scale", "min_material_density");
    let text = std::fs::read_to_string(format!("{RS}invalid_density_five.xml")).unwrap();
    let (rho, mass) = density_mass(&text);
    assert!(rho < material);
    let all = findings(&format!("{RS}invalid_density_five.xml"));
    let hits = of(&all, "robot-scale");
    assert_eq!(hits.len(), 1, "{hits:#?}");
    let m = message(hits[0]);
    assert!(m.contains(&format!("at density {rho} kg/m³")), "{m}");
    assert!(m.contains("the density is the evidence, not the lengths"), "{m}");
    assert!(m.contains(&format!("weighs {:.3} kg", mass)), "{mass}: {m}");
    assert!(!m.contains("unit too small"), "{m}");

    let valid = findings(&format!("{RS}valid_density_printed.xml"));
    assert!(of(&valid, "robot-scale").is_empty(), "{valid:#?}");

    let biped = findings(&format!("{RS}invalid_decimetre_biped.xml"));
    let hits = of(&biped, "robot-scale");
    assert_eq!(hits.len(), 1);
    assert!(message(hits[0]).contains("its lengths are likely written in a unit too small"));
}
