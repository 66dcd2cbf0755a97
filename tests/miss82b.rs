//! The classes the nineteenth and twentieth rounds left, fixed from the class (docs/audit.md,
//! "Classes missed by the rounds, fixed from the class (20b)"), run from the CLI. What each test
//! expects is worked out from the fixtures' written text (masses, moments, box sizes, effort and
//! velocity limits) and the rules' documented defaults, not from the code under test.

mod common;

use common::lint::{measured, message, of_message, option, real_robot_files};
use common::xml_text::{attr, tags};

const PJ: &str = "fixtures/rules/placeholder-joint-limits/";
const CI: &str = "fixtures/rules/copied-inertial/";

fn num(tag: &str, name: &str) -> f64 {
    attr(tag, name).unwrap_or_else(|| panic!("{tag}: no {name}")).parse().unwrap()
}

/// A URDF's written mass (the sum of its `<mass value>`s) and the peak power its limits claim,
/// Σ effort × velocity / 4 (W).
fn mass_and_power(text: &str) -> (f64, f64) {
    let mass = tags(text, "mass").iter().map(|t| num(t, "value")).sum();
    let power =
        tags(text, "limit").iter().map(|t| num(t, "effort") * num(t, "velocity") / 4.0).sum();
    (mass, power)
}

/// Limits claiming more peak power than `max_specific_power` per kg of the robot (the Ghost
/// Vision 60's 100 N·m at 100 rad/s on every joint) are named, at the power per kg the text
/// gives; a Mini Cheetah actuator's values and the MIT humanoid's stronger ones are not. The
/// invalid file with a body heavy enough to bring it under the bound is not named either.
#[test]
fn joint_limits_claiming_more_power_than_the_robot_holds() {
    let bound = option("placeholder-joint-limits", "max_specific_power");
    let case = "of peak motor power";
    for (file, named) in [
        ("invalid_urdf_power_over_mass.urdf", true),
        ("valid_urdf_power_datasheet.urdf", false),
        ("valid_urdf_power_strong_motors.urdf", false),
    ] {
        let path = format!("{PJ}{file}");
        let text = std::fs::read_to_string(&path).unwrap();
        let (mass, power) = mass_and_power(&text);
        assert_eq!(power / mass > bound, named, "{file}: {} W/kg", power / mass);
        let hits = of_message(&path, "placeholder-joint-limits", case);
        assert_eq!(hits.len(), usize::from(named), "{file}: {hits:#?}");
        if named {
            let got = measured(&hits[0]);
            assert!((got / (power / mass) - 1.0).abs() < 1e-6, "{file}: {got}");
        }
    }
    // The same limits on a body heavy enough that they claim 5 % under the bound per kg.
    let path = format!("{PJ}invalid_urdf_power_over_mass.urdf");
    let text = std::fs::read_to_string(&path).unwrap();
    let (mass, power) = mass_and_power(&text);
    let body = tags(&text, "mass")[0];
    let heavy = num(body, "value") + power / (0.95 * bound) - mass;
    let edited = text.replacen(body, &format!("<mass value=\"{heavy}\"/"), 1);
    let (m2, p2) = mass_and_power(&edited);
    assert!(p2 / m2 < bound && p2 / m2 > 0.9 * bound, "{}", p2 / m2);
    let dir = std::env::temp_dir().join(format!("modellint_miss82b_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let copy = dir.join("heavy_body.urdf");
    std::fs::write(&copy, edited).unwrap();
    let hits = of_message(copy.to_str().unwrap(), "placeholder-joint-limits", case);
    assert!(hits.is_empty(), "{hits:#?}");
}

/// A URDF link as written: name, mass, largest written moment and box size.
struct Link {
    name: String,
    mass: f64,
    imax: f64,
    volume: f64,
}

fn links(text: &str) -> Vec<Link> {
    let mut v = Vec::new();
    for (i, _) in text.match_indices("<link name=\"") {
        let end = i + text[i..].find("</link>").unwrap();
        let link = &text[i..end];
        let inertia = tags(link, "inertia")[0];
        let imax = ["ixx", "iyy", "izz"].iter().map(|k| num(inertia, k)).fold(0.0, f64::max);
        let size: Vec<f64> = attr(tags(link, "box")[0], "size")
            .unwrap()
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        v.push(Link {
            name: attr(link, "name").unwrap().to_string(),
            mass: num(tags(link, "mass")[0], "value"),
            imax,
            volume: size.iter().product(),
        });
    }
    v
}

/// One mass written on links of different sizes (the KUKA LWR's 2 kg on every link) is named
/// once, measured at the largest ratio of the links' radii of gyration √(I_max / m) or of their
/// boxes' cube-root volumes, worked out from the text; a modular arm of identical segments
/// (one mass, one size) is not. The base, welded to the world, is no body of the compiled
/// model and is left out.
#[test]
fn one_mass_over_links_of_different_sizes() {
    let factor = option("copied-inertial", "size_factor");
    let min_bodies = option("copied-inertial", "copied_mass_min_bodies");
    let share = option("copied-inertial", "copied_mass_share");
    for (file, named) in [
        ("invalid_urdf_one_mass_over_links.urdf", true),
        ("valid_urdf_modular_identical_segments.urdf", false),
    ] {
        let path = format!("{CI}{file}");
        let text = std::fs::read_to_string(&path).unwrap();
        let moving: Vec<Link> = links(&text).into_iter().filter(|l| l.name != "base").collect();
        let total: f64 = moving.iter().map(|l| l.mass).sum();
        let same: Vec<&Link> = moving.iter().filter(|l| l.mass == moving[0].mass).collect();
        let n = same.len() as f64;
        let spread = |size: &dyn Fn(&Link) -> f64| {
            let hi = same.iter().map(|l| size(l)).fold(0.0, f64::max);
            let lo = same.iter().map(|l| size(l)).fold(f64::INFINITY, f64::min);
            hi / lo
        };
        let ratio = spread(&|l| (l.imax / l.mass).sqrt()).max(spread(&|l| l.volume.cbrt()));
        let expected = n >= min_bodies && n * moving[0].mass / total >= share && ratio >= factor;
        assert_eq!(expected, named, "{file}: {n} links, ratio {ratio}");
        let hits = of_message(&path, "copied-inertial", "bodies state one mass");
        assert_eq!(hits.len(), usize::from(named), "{file}: {hits:#?}");
        if named {
            assert!((measured(&hits[0]) / ratio - 1.0).abs() < 1e-3, "{}", measured(&hits[0]));
            assert!(message(&hits[0]).starts_with(&format!("{} bodies", same.len())), "{hits:#?}");
        }
    }
}

/// The Mini Pupper's class in MJCF: one `mass` written on every leg link's geom (a hip box and
/// two capsules of different lengths) is named with the count of geoms that write it; a
/// hexapod's six identical legs (one mass per part, mirrored) and three 1 g sensor frames of
/// different shapes (under the share of the robot's mass) are not.
#[test]
fn one_mass_written_on_leg_links_of_different_shapes() {
    let share = option("copied-inertial", "copied_mass_share");
    for (file, value, named) in [
        ("invalid_one_mass_leg_links.xml", "0.025", true),
        ("valid_hexapod_identical_legs.xml", "0.05", false),
        ("valid_sensor_frames_one_gram.xml", "0.001", false),
    ] {
        let path = format!("{CI}{file}");
        let text = std::fs::read_to_string(&path).unwrap();
        let written: Vec<&str> = tags(&text, "geom")
            .into_iter()
            .chain(tags(&text, "inertial"))
            .filter(|t| attr(t, "mass") == Some(value))
            .collect();
        let total: f64 = tags(&text, "geom")
            .into_iter()
            .chain(tags(&text, "inertial"))
            .filter_map(|t| attr(t, "mass").map(|m| m.parse::<f64>().unwrap()))
            .sum();
        let n = written.len();
        assert!(n >= 3, "{file}: {n}");
        let carried = n as f64 * value.parse::<f64>().unwrap() / total;
        let hits = of_message(&path, "copied-inertial", "bodies state one mass");
        assert_eq!(hits.len(), usize::from(named), "{file}: {hits:#?}");
        if named {
            assert!(carried >= share, "{file}: {carried}");
            assert!(message(&hits[0]).starts_with(&format!("{n} bodies")), "{hits:#?}");
        }
    }
}

/// One mass on bodies of different robots or props of one scene (an arm's 0.5 kg forearm and
/// three 0.5 kg objects of different sizes, each its own kinematic tree) is no copy: not named,
/// while the same bodies hung from one tree are.
#[test]
fn one_mass_across_kinematic_trees_is_not_a_copy() {
    let path = format!("{CI}valid_scene_objects_one_mass.xml");
    let text = std::fs::read_to_string(&path).unwrap();
    let n = tags(&text, "geom").iter().filter(|t| attr(t, "mass") == Some("0.5")).count();
    assert_eq!(n, 4);
    assert!(of_message(&path, "copied-inertial", "bodies state one mass").is_empty());
    // The three objects welded under the forearm: one tree, one mass on four parts.
    let joined = text.replace("<freejoint/>", "").replace(
        "      </body>\n    </body>\n    <body name=\"cube\"",
        "      <body name=\"cube\"",
    );
    let joined = joined.replacen(
        "    </body>\n  </worldbody>",
        "    </body>\n      </body>\n    </body>\n  </worldbody>",
        1,
    );
    assert_ne!(joined, text);
    let dir = std::env::temp_dir().join(format!("modellint_miss82b_tree_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let copy = dir.join("one_tree.xml");
    std::fs::write(&copy, &joined).unwrap();
    let hits = of_message(copy.to_str().unwrap(), "copied-inertial", "bodies state one mass");
    assert_eq!(hits.len(), 1, "{joined}\n{hits:#?}");
    assert!(message(&hits[0]).starts_with("4 bodies"), "{hits:#?}");
}

/// The shared real robots and Asimov: no copied mass named.
#[test]
fn real_robots_state_no_copied_mass() {
    for file in real_robot_files() {
        let hits = of_message(&file, "copied-inertial", "bodies state one mass");
        assert!(hits.is_empty(), "{file}: {hits:#?}");
    }
}
