//! The class the twenty-second audit round (issue 45) found missed, end to end from the CLI on
//! fixtures written from the class: a locomotor that moves in a vertical plane (Brax's and
//! Gym's half-cheetah and hopper: a horizontal slide, a vertical slide and a pitch hinge in
//! place of a free joint) whose feet alone collide. Which links a finding must name is worked
//! out here from the fixtures' written text (which geoms carry contact bits), not read from
//! the tool.

mod common;

use common::lint::{findings, measured, message, of};
use common::xml_text::{attr, bodies_with_geoms};

const LW: &str = "fixtures/rules/links-without-collision/";
const RULE: &str = "links-without-collision";

/// The bodies of a fixture none of whose geoms the text gives contact bits (an explicit
/// `contype="1"` or the colliding class `col`; the fixtures' defaults switch contacts off).
fn bare_bodies(file: &str) -> Vec<String> {
    let text = std::fs::read_to_string(file).unwrap();
    bodies_with_geoms(&text)
        .into_iter()
        .filter(|(_, g)| {
            !g.iter().any(|g| attr(g, "contype") == Some("1") || attr(g, "class") == Some("col"))
        })
        .map(|(n, _)| n)
        .collect()
}

/// One finding naming exactly the bare links of the text, the count as its measured value.
fn names_exactly_the_bare_links(file: &str, feet_words: &str) {
    let all = findings(file);
    let found = of(&all, RULE);
    assert_eq!(found.len(), 1, "{file}: {all:#?}");
    let msg = message(found[0]);
    let bare = bare_bodies(file);
    assert!(!bare.is_empty(), "{file}: the fixture has no bare link");
    for b in &bare {
        assert!(msg.contains(&format!("{b} (")), "{file}: `{b}` not named: {msg}");
    }
    let text = std::fs::read_to_string(file).unwrap();
    for (name, _) in bodies_with_geoms(&text) {
        if !bare.contains(&name) {
            assert!(!msg.contains(&format!("{name} (")), "{file}: colliding `{name}` named: {msg}");
        }
    }
    assert_eq!(measured(found[0]), bare.len() as f64, "{file}");
    assert!(msg.contains(feet_words), "{file}: {msg}");
}

/// A one-legged hopper in a vertical plane whose foot alone collides: torso, thigh and shank
/// are named, and its one foot is enough to make it legged.
#[test]
fn planar_hopper_with_only_its_foot_colliding() {
    names_exactly_the_bare_links(&format!("{LW}invalid_planar_hopper.xml"), "its foot collides");
}

/// A planar walker (its vertical slide written first) whose thighs and shanks are drawn only.
#[test]
fn planar_walker_with_drawn_legs() {
    names_exactly_the_bare_links(&format!("{LW}invalid_planar_walker.xml"), "its 2 feet collide");
}

/// Must not fire: the hopper with every link colliding; the hopper's leg under a base that
/// moves over the floor (x and y slides, a yaw hinge: it cannot fall onto its links). (The
/// shared real robots float on free joints: the planar class does not reach them.)
#[test]
fn colliding_links_and_floor_bases_are_not_reported() {
    let files = [
        format!("{LW}valid_planar_hopper_colliding.xml"),
        format!("{LW}valid_planar_floor_base.xml"),
    ];
    for f in files {
        let all = findings(&f);
        assert!(of(&all, RULE).is_empty(), "{f}: {all:#?}");
    }
}

/// The floor-base fixture is the invalid hopper but for its base's joints: the same bodies are
/// bare, so only the base's freedom keeps it from being reported.
#[test]
fn the_floor_base_differs_from_the_hopper_only_in_its_base() {
    let hop = bare_bodies(&format!("{LW}invalid_planar_hopper.xml"));
    let floor = bare_bodies(&format!("{LW}valid_planar_floor_base.xml"));
    let rename = |v: Vec<String>| -> Vec<String> {
        v.into_iter().map(|n| if n == "cart" { "torso".into() } else { n }).collect()
    };
    assert_eq!(hop, rename(floor));
}
