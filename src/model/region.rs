//! The body region a joint's name suggests — one classifier for `gap`'s per-region tables (when
//! the spec gives no `region`) and `modellint init-spec`'s `region =` guesses.

/// Name parts by region, checked in this order (the first region with a part in the name wins).
const REGIONS: [(&str, &[&str]); 4] = [
    ("head", &["head", "neck"]),
    ("arms", &["shoulder", "elbow", "wrist", "arm", "hand", "finger", "gripper"]),
    ("legs", &["hip", "knee", "ankle", "toe", "leg", "thigh", "calf", "foot", "haa", "hfe", "kfe"]),
    ("torso", &["waist", "torso", "spine", "trunk", "pelvis", "chest"]),
];

/// The region (`head`, `arms`, `legs`, `torso`) whose name part `name` contains (any case);
/// `None` when it has none.
pub fn from_name(name: &str) -> Option<&'static str> {
    let l = name.to_ascii_lowercase();
    REGIONS.iter().find(|(_, parts)| parts.iter().any(|p| l.contains(p))).map(|(r, _)| *r)
}

#[cfg(test)]
mod tests {
    use super::from_name;

    #[test]
    fn a_quadrupeds_hip_thigh_and_calf_are_all_legs() {
        // Go2 / ANYmal names: gap put thigh and calf in "other", init-spec in "legs".
        for n in ["FL_hip_joint", "FL_thigh_joint", "FL_calf_joint", "LF_HAA", "RH_KFE"] {
            assert_eq!(from_name(n), Some("legs"), "{n}");
        }
        assert_eq!(from_name("left_shoulder_pitch"), Some("arms"));
        assert_eq!(from_name("AAHead_yaw"), Some("head"));
        assert_eq!(from_name("Waist"), Some("torso"));
        assert_eq!(from_name("servo"), None);
    }
}
