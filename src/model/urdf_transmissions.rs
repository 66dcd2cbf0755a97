//! A URDF's ROS `<transmission>`s: which joints a motor drives and through what reduction.
//! MuJoCo's importer ignores them (it makes no actuator and no armature); the rules read them
//! as the file's own statement that a joint is motor-driven.
//!
//! Three syntaxes are read: the old one (`<transmission type="…SimpleTransmission">` with
//! `<joint name>`, `<actuator name>` and `<mechanicalReduction>` as its children), ros_control's
//! (`<type>`, `<joint name>` with a `<hardwareInterface>`, and `<mechanicalReduction>` inside
//! `<actuator>`), and ros2_control's (`<transmission>` inside `<ros2_control>`, with
//! `<mechanical_reduction>` inside `<joint>` or `<actuator>`).

use crate::model::source::{Loc, SourceMap, XNode};

/// One `<transmission>`: the joints it names and its mechanical reduction, if it states one.
#[derive(Debug, Clone)]
pub struct Drive {
    /// The transmission's `name` ("" when it has none).
    pub name: String,
    /// Where the `<transmission>` element starts.
    pub loc: Loc,
    /// The joints it drives, with where each is named.
    pub joints: Vec<(String, Loc)>,
    /// The largest |reduction| it states (joint turns per motor turn inverted: the motor turns
    /// `reduction` times per joint turn), and where; `None` when no reduction is written (ROS
    /// then takes 1) or it is not a number (an unexpanded xacro expression).
    pub reduction: Option<(f64, Loc)>,
}

/// The text inside an element (between its start and end tags), trimmed.
fn inner_text<'a>(map: &'a SourceMap, n: &XNode) -> Option<&'a str> {
    let text = &map.files.get(n.full.file)?.text;
    let whole = text.get(n.full.start..n.full.end)?;
    let open = whole.find('>')?;
    let close = whole.rfind("</")?;
    whole.get(open + 1..close).map(str::trim)
}

/// Every `<transmission>` of a URDF tree (at any depth: ros2_control nests them).
pub fn transmissions(map: &SourceMap, root: &XNode) -> Vec<Drive> {
    let mut found: Vec<&XNode> = Vec::new();
    root.walk(&mut |n| {
        if n.tag == "transmission" {
            found.push(n);
        }
    });
    found
        .into_iter()
        .map(|t| {
            let joints = t
                .children_tagged("joint")
                .filter_map(|j| j.attr("name").map(|a| (a.value.clone(), a.loc)))
                .collect();
            let mut reduction: Option<(f64, Loc)> = None;
            t.walk(&mut |n| {
                if n.tag != "mechanicalReduction" && n.tag != "mechanical_reduction" {
                    return;
                }
                let Some(v) = inner_text(map, n).and_then(|s| s.parse::<f64>().ok()) else {
                    return;
                };
                if v.is_finite() && reduction.is_none_or(|(r, _)| v.abs() > r) {
                    reduction = Some((v.abs(), n.loc));
                }
            });
            Drive { name: t.get("name").unwrap_or("").to_string(), loc: t.loc, joints, reduction }
        })
        .collect()
}

/// Whether a transmission names joint `name` (the file says a motor drives it).
pub fn drives(drives: &[Drive], name: &str) -> bool {
    drives.iter().any(|d| d.joints.iter().any(|(j, _)| j == name))
}
