//! Left/right names: which side a joint, body or actuator name is on and the name of its mirror
//! (`left_knee` ↔ `right_knee`, `Hip_Pitch_Right` ↔ `Hip_Pitch_Left`, `l_hip` ↔ `r_hip`,
//! `hip_L` ↔ `hip_R`, quadruped `FL_calf` ↔ `FR_calf`), with the spec's own markers first. One
//! implementation for the lint rules and the fit engine's joint pairing.

use crate::spec::Spec;

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Side {
    Left,
    Right,
}

impl Side {
    pub fn word(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }
}

/// Left/right marker pairs to try, the spec's first.
pub fn markers(spec: Option<&Spec>) -> Vec<(String, String)> {
    let mut v = Vec::new();
    if let Some(s) = spec
        && let (Some(l), Some(r)) = (&s.robot.left, &s.robot.right)
    {
        v.push((l.clone(), r.clone()));
    }
    for (l, r) in leg_prefixes() {
        v.push((l.to_string(), r.to_string()));
    }
    for (l, r) in [
        ("left_", "right_"),
        ("Left_", "Right_"),
        ("_left", "_right"),
        ("_Left", "_Right"),
        ("l_", "r_"),
        ("L_", "R_"),
        ("_l", "_r"),
        ("_L", "_R"),
        ("Left", "Right"),
        ("left", "right"),
        ("LEFT", "RIGHT"),
    ] {
        v.push((l.to_string(), r.to_string()));
    }
    v
}

/// Quadruped leg prefixes, by naming convention: front/rear (or fore/hind, front/back) left ↔
/// right. Only ever a name's prefix. Hind legs are `RL_`/`RR_`, `HL_`/`HR_` (Spot's `hl_`/`hr_`)
/// or `BL_`/`BR_` (back: Stoch 3's `bl_`/`br_`) beside `FL_`/`FR_`; `LH_`/`RH_` beside
/// `LF_`/`RF_` (ANYmal).
const LEG_CONVENTIONS: [&[(&str, &str)]; 4] = [
    &[("FL_", "FR_"), ("RL_", "RR_"), ("HL_", "HR_"), ("BL_", "BR_")],
    &[("fl_", "fr_"), ("rl_", "rr_"), ("hl_", "hr_"), ("bl_", "br_")],
    &[("LF_", "RF_"), ("LH_", "RH_")],
    &[("lf_", "rf_"), ("lh_", "rh_")],
];

/// Every quadruped leg prefix pair.
fn leg_prefixes() -> impl Iterator<Item = &'static (&'static str, &'static str)> {
    LEG_CONVENTIONS.iter().flat_map(|c| c.iter())
}

/// The joint a quadruped leg prefix is on, with the prefix's convention (`FL_` `FR_` `RL_`
/// `RR_` `HL_` `HR_`, or `LF_` `RF_` `LH_` `RH_`, each in one case): `FL_knee` → (0, `knee`),
/// `RH_KFE` → (2, `KFE`). The same joint on every leg has the same pair; a hexapod's `lf_` and
/// `rr_` are of two conventions. `None` without a leg prefix.
pub fn leg_joint(name: &str) -> Option<(usize, &str)> {
    LEG_CONVENTIONS
        .iter()
        .enumerate()
        .flat_map(|(c, pairs)| pairs.iter().flat_map(move |(l, r)| [(c, l), (c, r)]))
        .find(|(_, p)| name.starts_with(**p) && name.len() > p.len())
        .map(|(c, p)| (c, &name[p.len()..]))
}

/// Replace one marker occurrence: short markers (`l_`, `_l`) only as a prefix / suffix.
fn swap(name: &str, from: &str, to: &str) -> Option<String> {
    if leg_prefixes().any(|(l, r)| *l == from || *r == from) {
        return name.starts_with(from).then(|| format!("{to}{}", &name[from.len()..]));
    }
    let short = from.trim_matches('_').len() <= 1;
    if short {
        if from.ends_with('_') && name.starts_with(from) {
            return Some(format!("{to}{}", &name[from.len()..]));
        }
        if from.starts_with('_') && name.ends_with(from) {
            return Some(format!("{}{to}", &name[..name.len() - from.len()]));
        }
        return None;
    }
    name.contains(from).then(|| name.replacen(from, to, 1))
}

/// Side of a name and its mirrored counterpart, by the first marker pair that applies.
pub fn mirror(name: &str, spec: Option<&Spec>) -> Option<(Side, String)> {
    for (l, r) in markers(spec) {
        if let Some(m) = swap(name, &l, &r) {
            return Some((Side::Left, m));
        }
        if let Some(m) = swap(name, &r, &l) {
            return Some((Side::Right, m));
        }
    }
    None
}

pub fn side_of(name: &str, spec: Option<&Spec>) -> Option<Side> {
    mirror(name, spec).map(|(s, _)| s)
}

/// Leg-side prefixes of two-legged robots: `LL_` (leg left) ↔ `LR_` (leg right), as on the
/// Berkeley Humanoid. The same letters name a quadruped's left-rear leg (`LF_` `LR_` `RF_`
/// `RR_`), so they are used only by [`mirror_in`], where the partner must exist.
const LEG_SIDE_PREFIXES: [(&str, &str); 2] = [("LL_", "LR_"), ("ll_", "lr_")];

/// [`mirror`] within a model whose names `exists` knows: the built-in and spec markers first,
/// then the leg-side prefixes `LL_`/`LR_` when the partner name exists (a quadruped's `LR_knee`
/// has no `LL_knee` and stays unpaired).
pub fn mirror_in(
    name: &str,
    spec: Option<&Spec>,
    exists: impl Fn(&str) -> bool,
) -> Option<(Side, String)> {
    if let Some(m) = mirror(name, spec) {
        // `RLEG_HIP_R`'s marker `_R` names the roll axis, not a side: its partner
        // `RLEG_HIP_L` does not exist, the side letter fused to the limb word does.
        if !exists(&m.1)
            && let Some(fused) = fused_side_letter(name, &exists)
        {
            return Some(fused);
        }
        return Some(m);
    }
    if let Some(fused) = fused_side_letter(name, &exists) {
        return Some(fused);
    }
    if let Some(infix) = infix_side_letter(name, &exists) {
        return Some(infix);
    }
    if let Some(numbered) = numbered_side_letter(name, &exists) {
        return Some(numbered);
    }
    for (l, r) in LEG_SIDE_PREFIXES {
        for (from, to, side) in [(l, r, Side::Left), (r, l, Side::Right)] {
            if let Some(rest) = name.strip_prefix(from)
                && !rest.is_empty()
            {
                let other = format!("{to}{rest}");
                if exists(&other) {
                    return Some((side, other));
                }
            }
        }
    }
    None
}

/// A side letter fused to the limb word of a name's first token, as in HRP-style names
/// (`LLEG_HIP_P` ↔ `RLEG_HIP_P`, `LARM_ELBOW` ↔ `RARM_ELBOW`, `lleg_knee` ↔ `rleg_knee`): the
/// token is `L`/`R` (or `l`/`r`) and a word of letters, and the name with the other letter must
/// exist (`LEG_x` would need a `REG_x`).
fn fused_side_letter(name: &str, exists: &impl Fn(&str) -> bool) -> Option<(Side, String)> {
    let token = name.split('_').next()?;
    let mut chars = token.chars();
    let first = chars.next()?;
    let word: String = chars.collect();
    if word.chars().count() < 2 || !word.chars().all(|c| c.is_ascii_alphabetic()) {
        return None;
    }
    let (side, other) = match first {
        'L' => (Side::Left, 'R'),
        'R' => (Side::Right, 'L'),
        'l' => (Side::Left, 'r'),
        'r' => (Side::Right, 'l'),
        _ => return None,
    };
    let partner = format!("{other}{}", &name[first.len_utf8()..]);
    exists(&partner).then_some((side, partner))
}

/// A side letter standing alone between two underscores inside a name (`J_hip_l_roll` ↔
/// `J_hip_r_roll`, `Link_arm_L_03` ↔ `Link_arm_R_03`, OpenLoong's convention): the first
/// middle token that is `l`/`r` (or `L`/`R`), swapped, when the name with the other letter
/// exists. A letter at either end is the `l_`/`_l` markers' case; requiring the partner keeps a
/// lone `r` that means something else (a roll axis) unpaired.
fn infix_side_letter(name: &str, exists: &impl Fn(&str) -> bool) -> Option<(Side, String)> {
    let tokens: Vec<&str> = name.split('_').collect();
    if tokens.len() < 3 {
        return None;
    }
    let k = (1..tokens.len() - 1).find(|&k| matches!(tokens[k], "l" | "r" | "L" | "R"))?;
    let (side, other) = match tokens[k] {
        "l" => (Side::Left, "r"),
        "r" => (Side::Right, "l"),
        "L" => (Side::Left, "R"),
        _ => (Side::Right, "L"),
    };
    let mut t = tokens.clone();
    t[k] = other;
    let partner = t.join("_");
    exists(&partner).then_some((side, partner))
}

/// A side letter standing alone beside a part number (`5R_Link` ↔ `5L_Link`, `leg_2l` ↔
/// `leg_2r`, `hip-R3` ↔ `hip-L3`, Kayra's convention): an `L`/`R` (or `l`/`r`) with a digit on
/// one side and a digit, a separator (`_`, `-`, `.`, space) or the name's end on the other,
/// swapped, when the name with the other letter exists. A letter inside a word (`3BRU_Link`'s
/// `R`, between `B` and `U`) is no side, and neither is one between two separators or at an end
/// beside a separator, the markers' and [`infix_side_letter`]'s cases.
fn numbered_side_letter(name: &str, exists: &impl Fn(&str) -> bool) -> Option<(Side, String)> {
    let b = name.as_bytes();
    let sep = |c: u8| matches!(c, b'_' | b'-' | b'.' | b' ');
    for (i, &c) in b.iter().enumerate() {
        let (side, other) = match c {
            b'L' => (Side::Left, "R"),
            b'R' => (Side::Right, "L"),
            b'l' => (Side::Left, "r"),
            b'r' => (Side::Right, "l"),
            _ => continue,
        };
        let before = i.checked_sub(1).map(|k| b[k]);
        let after = b.get(i + 1).copied();
        let digit = |x: Option<u8>| x.is_some_and(|x| x.is_ascii_digit());
        let bound = |x: Option<u8>| x.is_none_or(|x| x.is_ascii_digit() || sep(x));
        if !(digit(before) && bound(after) || digit(after) && bound(before)) {
            continue;
        }
        let partner = format!("{}{other}{}", &name[..i], &name[i + 1..]);
        if exists(&partner) {
            return Some((side, partner));
        }
    }
    None
}

/// The mirror of a name by the built-in markers alone (no spec): `None` when the name carries no
/// side marker.
pub fn mirror_name(name: &str) -> Option<String> {
    mirror(name, None).map(|(_, m)| m)
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn mirror_names() {
        assert_eq!(mirror("left_knee", None), Some((Side::Left, "right_knee".into())));
        assert_eq!(mirror("Hip_Pitch_Right", None), Some((Side::Right, "Hip_Pitch_Left".into())));
        assert_eq!(mirror("l_ankle", None), Some((Side::Left, "r_ankle".into())));
        assert_eq!(mirror("ankle_r", None), Some((Side::Right, "ankle_l".into())));
        assert_eq!(mirror("torso", None), None);
        assert_eq!(mirror("wheel_rl", None), None);
        assert_eq!(mirror("FL_calf", None), Some((Side::Left, "FR_calf".into())));
        assert_eq!(mirror("RR_hip", None), Some((Side::Right, "RL_hip".into())));
        assert_eq!(mirror("LH_KFE", None), Some((Side::Left, "RH_KFE".into())));
        assert_eq!(mirror("HALF_link", None), None);
        // Spot's hind legs.
        assert_eq!(mirror("hl_kn", None), Some((Side::Left, "hr_kn".into())));
        assert_eq!(mirror("hr_uleg", None), Some((Side::Right, "hl_uleg".into())));
        assert_eq!(mirror("HL_hip", None), Some((Side::Left, "HR_hip".into())));
        // Back legs (Stoch 3's `bl_`/`br_`): a prefix only.
        assert_eq!(mirror("bl_thigh_link", None), Some((Side::Left, "br_thigh_link".into())));
        assert_eq!(mirror("BR_KNEE", None), Some((Side::Right, "BL_KNEE".into())));
        assert_eq!(mirror("cable_br_clip", None), None);
        assert_eq!(mirror("LL_HR", None), None);
    }

    #[test]
    fn leg_side_prefixes_pair_only_with_their_partner() {
        let humanoid = |n: &str| ["LL_HFE", "LR_HFE", "ll_kfe", "lr_kfe"].contains(&n);
        assert_eq!(mirror_in("LL_HFE", None, humanoid), Some((Side::Left, "LR_HFE".into())));
        assert_eq!(mirror_in("LR_HFE", None, humanoid), Some((Side::Right, "LL_HFE".into())));
        assert_eq!(mirror_in("lr_kfe", None, humanoid), Some((Side::Right, "ll_kfe".into())));
        // A quadruped's left-rear leg: no `LL_` partner, no pairing.
        let quadruped = |n: &str| ["LF_KFE", "LR_KFE", "RF_KFE", "RR_KFE"].contains(&n);
        assert_eq!(mirror_in("LR_KFE", None, quadruped), None);
        // Built-in markers still come first.
        assert_eq!(
            mirror_in("left_knee", None, |_| false),
            Some((Side::Left, "right_knee".into()))
        );
    }

    #[test]
    fn side_letters_fused_to_the_limb_word_pair_with_their_partner() {
        let hrp = |n: &str| {
            ["LLEG_HIP_R", "RLEG_HIP_R", "LARM_ELBOW", "RARM_ELBOW", "lleg_knee", "rleg_knee"]
                .contains(&n)
        };
        // `_R` is the roll axis here: the partner is the other leg, not `RLEG_HIP_L`.
        assert_eq!(mirror_in("RLEG_HIP_R", None, hrp), Some((Side::Right, "LLEG_HIP_R".into())));
        assert_eq!(mirror_in("LLEG_HIP_R", None, hrp), Some((Side::Left, "RLEG_HIP_R".into())));
        assert_eq!(mirror_in("LARM_ELBOW", None, hrp), Some((Side::Left, "RARM_ELBOW".into())));
        assert_eq!(mirror_in("rleg_knee", None, hrp), Some((Side::Right, "lleg_knee".into())));
        // No partner, no pairing: a `LEG_` name is not a left `EG`.
        assert_eq!(mirror_in("LEG_KNEE", None, |n| n == "LEG_KNEE"), None);
        assert_eq!(mirror_in("LINK_2", None, |_| false), None);
        // A built-in marker whose partner exists still wins.
        let both = |n: &str| ["LLEG_hip_l", "LLEG_hip_r"].contains(&n);
        assert_eq!(mirror_in("LLEG_hip_l", None, both), Some((Side::Left, "LLEG_hip_r".into())));
    }

    #[test]
    fn side_letters_between_underscores_pair_with_their_partner() {
        let names = ["J_hip_l_roll", "J_hip_r_roll", "Link_arm_L_03", "Link_arm_R_03", "J_x_r_y"];
        let has = |n: &str| names.contains(&n);
        assert_eq!(mirror_in("J_hip_l_roll", None, has), Some((Side::Left, "J_hip_r_roll".into())));
        assert_eq!(
            mirror_in("J_hip_r_roll", None, has),
            Some((Side::Right, "J_hip_l_roll".into()))
        );
        assert_eq!(
            mirror_in("Link_arm_R_03", None, has),
            Some((Side::Right, "Link_arm_L_03".into()))
        );
        // No partner (`J_x_l_y` does not exist): the letter is no side.
        assert_eq!(mirror_in("J_x_r_y", None, has), None);
        // Without the model's names, no guess.
        assert_eq!(mirror("J_hip_l_roll", None), None);
    }

    #[test]
    fn side_letters_beside_part_numbers_pair_with_their_partner() {
        let names = [
            "5R_Link",
            "5L_Link",
            "3BRU_Link",
            "3BLU_Link",
            "leg_2l",
            "leg_2r",
            "hip-R3",
            "hip-L3",
            "Rod1",
            "Lod1",
            "x_R_y",
            "x_L_y",
            "FL_calf",
            "FR_calf",
            "RL_calf",
            "RR_calf",
        ];
        let has = |n: &str| names.contains(&n);
        assert_eq!(mirror_in("5R_Link", None, has), Some((Side::Right, "5L_Link".into())));
        assert_eq!(mirror_in("5L_Link", None, has), Some((Side::Left, "5R_Link".into())));
        assert_eq!(mirror_in("leg_2l", None, has), Some((Side::Left, "leg_2r".into())));
        assert_eq!(mirror_in("hip-R3", None, has), Some((Side::Right, "hip-L3".into())));
        // A letter inside a word is no side, even when the swapped name exists.
        assert_eq!(mirror_in("3BRU_Link", None, has), None);
        assert_eq!(mirror_in("Rod1", None, has), None);
        // Quadruped legs still pair by side, front with front and rear with rear.
        assert_eq!(mirror_in("RL_calf", None, has), Some((Side::Left, "RR_calf".into())));
        assert_eq!(mirror_in("FR_calf", None, has), Some((Side::Right, "FL_calf".into())));
        // No partner, no pairing.
        assert_eq!(mirror_in("7R_Link", None, has), None);
        assert_eq!(mirror("5R_Link", None), None);
    }

    #[test]
    fn the_same_joint_on_every_leg() {
        assert_eq!(leg_joint("FL_calf_joint"), Some((0, "calf_joint")));
        assert_eq!(leg_joint("RR_calf_joint"), Some((0, "calf_joint")));
        assert_eq!(leg_joint("LH_KFE"), Some((2, "KFE")));
        assert_eq!(leg_joint("RF_KFE"), Some((2, "KFE")));
        assert_eq!(leg_joint("rf_hip"), Some((3, "hip")));
        assert_eq!(leg_joint("hl_kn"), leg_joint("fr_kn"));
        // A hexapod's legs (lf lm lr rf rm rr) are not one quadruped convention.
        assert_ne!(leg_joint("lf_coxa"), leg_joint("rr_coxa"));
        assert_eq!(leg_joint("lm_coxa"), None);
        for n in ["left_knee", "l_ankle", "FLOOR_hinge", "FL_", "knee", "hip_FL_"] {
            assert_eq!(leg_joint(n), None, "{n}");
        }
    }

    #[test]
    fn mirror_name_pairs_both_ways() {
        assert_eq!(mirror_name("left_knee").as_deref(), Some("right_knee"));
        assert_eq!(mirror_name("r_hip_pitch").as_deref(), Some("l_hip_pitch"));
        assert_eq!(mirror_name("hip_L").as_deref(), Some("hip_R"));
        assert_eq!(mirror_name("LEFT_ANKLE").as_deref(), Some("RIGHT_ANKLE"));
        assert_eq!(mirror_name("elbow_pitch"), None);
        for n in ["left_knee", "Hip_Pitch_Right", "l_ankle", "ankle_r", "FL_calf", "LEFT_ANKLE"] {
            assert_eq!(mirror_name(&mirror_name(n).unwrap()).as_deref(), Some(n));
        }
    }
}
