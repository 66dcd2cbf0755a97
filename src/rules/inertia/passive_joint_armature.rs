use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::source::Loc;
use crate::model::{Joint, PartSource, Robot};
use crate::rules::{Context, Domain, Rule, RuleMeta, in_subtree, opt};
use crate::util::fmt_num;

/// The class attributes the actuated joints inherit a quantity from: the locations `source`
/// gives (where a joint's attribute is written, and the class it inherits from) of the scalar,
/// actuated joints for which `set` holds, when the value comes from a class.
pub(crate) fn class_sources(
    robot: &Robot,
    set: impl Fn(&Joint) -> bool,
    source: impl Fn(usize) -> (Loc, Option<String>),
) -> Vec<Loc> {
    robot
        .joints
        .iter()
        .filter(|j| j.is_scalar() && set(j))
        .filter(|j| !robot.actuators_on_joint(j.id).is_empty())
        .filter_map(|j| {
            let (loc, class) = source(j.id);
            class.map(|_| loc)
        })
        .collect()
}

declare_rule! {
    /// ## What it does
    /// Finds a motor's armature inherited by joints no motor drives: a hinge or slide with no
    /// actuator (on the joint, or on a tendon or joint equality that couples it to one) that
    /// takes its `armature` from the same `<default class>` attribute as actuated joints do
    /// (a joint an actuated spatial tendon crosses — a cable-driven finger — counts as driven),
    /// where that armature is at least `min_inertia_share` of the joint's inertia (the
    /// diagonal of MuJoCo's joint-space inertia at the keyframe, armature included). Passive
    /// wheels and casters, a rocker suspension, a free finger under a class that sets the arm
    /// motors' value.
    ///
    /// Not reported: a passive joint whose armature is written on the joint itself or comes
    /// from a class no actuated joint uses (a deliberate value: a bearing, a stabiliser for a
    /// light part); an armature below `min_inertia_share` of the joint's inertia (it changes
    /// little); joints that a spec marks passive with a motor family (the spec's rules judge
    /// those).
    ///
    /// ## Why is this bad?
    /// `armature` is the motor rotor's inertia seen through the gearbox (rotor inertia ×
    /// gear²). A joint with no motor has no rotor: a caster that should swivel at a touch turns
    /// as if it dragged a geared motor, a passive wheel resists spinning up, a rocker
    /// suspension answers bumps many times slower. The base then turns, rolls and settles
    /// differently in simulation than on the floor, and a policy that steers or balances the
    /// base learns the wrong response. MuJoCo XML reference, `joint/armature`.
    ///
    /// ## How it is confirmed
    /// Static: where each joint's compiled armature is written (the attribute and the class it
    /// inherits from), the actuators' transmissions and the equalities, and the keyframe's
    /// joint-space inertia.
    ///
    /// ## How to fix
    /// Set `armature="0"` on the passive joints (or give them a class of their own without the
    /// motors' armature); keep a small value only where a measured bearing or a light part's
    /// numerical stability needs one, written on the joint.
    pub PassiveJointArmature {
        id: "passive-joint-armature",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [opt(
            "min_inertia_share",
            0.5,
            "",
            Domain::POSITIVE_FRACTION,
            "smallest share of the joint's inertia (joint-space inertia diagonal at the keyframe, armature included) the inherited armature must make up to be reported"
        )],
    }
}
/// Whether joint `j` is driven: an actuator moves it directly or through a fixed tendon
/// ([`Robot::actuators_on_joint`]), an actuated spatial tendon has a site or wrapping geom
/// beyond it, an actuator or tendon adds armature to it, or a joint equality couples it to an
/// actuated joint.
pub(crate) fn driven(robot: &Robot, j: usize) -> bool {
    let joint = &robot.joints[j];
    if !robot.actuators_on_joint(j).is_empty()
        || joint.armature_parts.iter().any(|p| p.source != PartSource::Joint)
    {
        return true;
    }
    // A spatial tendon that an actuator pulls moves every joint between its sites (or the
    // geoms it wraps): a cable-driven finger.
    let m = &robot.mj;
    let (adr, num, wt, wo) = (m.tendon_adr(), m.tendon_num(), m.wrap_type(), m.wrap_objid());
    let (site_body, geom_body) = (m.site_bodyid(), m.geom_bodyid());
    let beyond = |b: Option<&i32>| {
        b.and_then(|&b| usize::try_from(b).ok()).is_some_and(|b| in_subtree(robot, joint.body, b))
    };
    for a in robot.actuators.iter().filter(|a| a.trn == crate::model::Transmission::Tendon) {
        let Ok(t) = usize::try_from(a.target) else { continue };
        let (Some(&ad), Some(&n)) = (adr.get(t), num.get(t)) else { continue };
        let (ad, n) = (ad.max(0) as usize, n.max(0) as usize);
        let pulls = (ad..ad + n).any(|w| {
            let o = wo.get(w).and_then(|&o| usize::try_from(o).ok());
            match (wt.get(w).map(|&x| x as i32), o) {
                (Some(3), Some(o)) => beyond(site_body.get(o)),
                (Some(4 | 5), Some(o)) => beyond(geom_body.get(o)),
                _ => false,
            }
        });
        if pulls {
            return true;
        }
    }
    robot.equalities.iter().any(|e| {
        e.etype == 2
            && (e.obj1 == j as i32 || e.obj2 == j as i32)
            && [e.obj1, e.obj2].iter().any(|&o| {
                usize::try_from(o).is_ok_and(|o| o != j && !robot.actuators_on_joint(o).is_empty())
            })
    })
}

/// Passive joints that inherit one class attribute: (its location, the class, [(joint, share of
/// the joint's inertia)]).
type Group = (crate::model::source::Loc, String, Vec<(usize, f64)>);

impl Rule for PassiveJointArmature {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let share = cx.opt("min_inertia_share");
        // Where each joint's own armature is written: (location, class it inherits from).
        let source = |j: usize| {
            let jt = &robot.joints[j];
            robot.attr_loc(ElemKind::Joint, j, &jt.name, "armature")
        };
        let motor_sources = class_sources(robot, |j| j.own_armature() > 0.0, source);
        if motor_sources.is_empty() {
            return;
        }
        // Group the passive joints by the class attribute they inherit.
        let mut groups: Vec<Group> = Vec::new();
        for j in robot.joints.iter().filter(|j| j.is_scalar() && j.own_armature() > 0.0) {
            if driven(robot, j.id) || cx.facts(&j.name).is_some_and(|f| f.motor.is_some()) {
                continue;
            }
            let (loc, class) = source(j.id);
            let Some(class) = class else { continue };
            if !motor_sources.contains(&loc) {
                continue;
            }
            let inertia = robot.key.m_diag.get(j.dofadr).copied().unwrap_or(0.0);
            let s = if inertia > 0.0 { j.own_armature() / inertia } else { 1.0 };
            if s < share {
                continue;
            }
            match groups.iter_mut().find(|g| g.0 == loc) {
                Some(g) => g.2.push((j.id, s)),
                None => groups.push((loc, class, vec![(j.id, s)])),
            }
        }
        for (_, class, joints) in groups {
            out.push(report(cx, &class, &joints));
        }
    }
}

fn report(cx: &Context, class: &str, joints: &[(usize, f64)]) -> Finding {
    let robot = cx.robot;
    let (j0, _) = joints[0];
    let first = &robot.joints[j0];
    let value = first.own_armature();
    let n = joints.len();
    let names: Vec<String> = joints
        .iter()
        .map(|&(j, s)| format!("{} ({} %)", robot.joints[j].name, fmt_num(100.0 * s, 3)))
        .collect();
    let shown = if names.len() > 8 {
        format!("{}, … ({n} joints)", names[..8].join(", "))
    } else {
        names.join(", ")
    };
    let msg = format!(
        "armature {} from <default class=\"{class}\">, the actuated joints' motor value, reaches {n} joint{} no actuator drives: {shown} of the joint's inertia",
        fmt_num(value, 4),
        if n == 1 { "" } else { "s" }
    );
    let mut f = cx
        .at_attr(ElemKind::Joint, j0, &first.name, "armature", msg)
        .label("no motor drives this joint");
    for &(j, _) in joints.iter().skip(1).take(3) {
        let jt = &robot.joints[j];
        f = f.secondary(robot.elem_loc(ElemKind::Joint, j, &jt.name), "no motor either");
    }
    f.note("armature is a motor rotor's inertia through its gearbox (rotor inertia × gear²); a joint with no motor has no rotor, so casters, passive wheels and suspensions answer forces many times slower in simulation than on the floor")
        .help("set armature=\"0\" on the passive joints (or give them a class of their own); keep a small value only where a measured bearing or a light part's stability needs one, written on the joint")
        .subject(Subject::Joint(j0))
        .measured(value, "kg·m²")
        .expected(0.0, "kg·m²")
        .with("joints", n as f64)
}
