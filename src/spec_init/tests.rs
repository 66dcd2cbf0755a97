//! Unit tests of the template's pieces (names, globs, TOML values).
use super::*;

#[test]
fn common_ends_stop_at_word_boundaries() {
    assert_eq!(common_ends("left_knee", "right_knee"), (0, 5));
    assert_eq!(common_ends("Hip_Pitch_Right", "Hip_Pitch_Left"), (10, 0));
    assert_eq!(common_ends("FL_calf", "FR_calf"), (0, 5));
    assert_eq!(common_ends("l_hip_r", "r_hip_r"), (0, 6));
}

#[test]
fn pair_globs_match_exactly_their_pair() {
    let all: Vec<String> =
        ["left_knee", "right_knee", "left_knee2", "waist"].iter().map(|s| s.to_string()).collect();
    assert_eq!(globs(&["left_knee", "right_knee"], &all), vec!["{left,right}_knee"]);
    assert_eq!(globs(&["waist"], &all), vec!["waist"]);
    let odd: Vec<String> = ["a[1]".to_string()].to_vec();
    let g = globs(&["a[1]"], &odd);
    let m = Glob::new(&g[0]).unwrap().compile_matcher();
    assert!(m.is_match("a[1]"));
}

#[test]
fn toml_values_parse() {
    assert_eq!(num(65.0), "65.0");
    assert_eq!(num(39.4), "39.4");
    let v: toml::Value = toml::from_str(&format!("x = {}", quote("a\"b\\c"))).unwrap();
    assert_eq!(v["x"].as_str(), Some("a\"b\\c"));
}
