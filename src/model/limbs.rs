//! Limbs: the parts of a robot that move independently of each other but for where they join.
//!
//! A joint's limb is the unbranched chain of jointed bodies it sits on: walking from its body
//! towards the world, the limb ends below the first body where the tree forks (two or more
//! child subtrees with joints), below a floating base's body (the free joint), or below the
//! static world. On a humanoid: the head, each arm, the waist, each leg. Two joints of
//! different limbs interact only through the bodies where the limbs join (not at all across
//! MuJoCo's separate kinematic trees): through the held base, or a servo-held waist.

use super::{GeomType, JointType, Robot};

impl Robot {
    /// The id of the body that starts `joint`'s limb (see the module doc); `None` for an unknown
    /// joint or a free joint.
    pub fn limb_of(&self, joint: &str) -> Option<usize> {
        let j = self.joint(joint)?;
        if j.jtype == JointType::Free {
            return None;
        }
        let n = self.bodies.len();
        let parent = |b: usize| self.bodies.get(b).map_or(0, |x| x.parent);
        let hinged =
            |b: usize| self.joints.iter().any(|x| x.body == b && x.jtype != JointType::Free);
        let floating =
            |b: usize| self.joints.iter().any(|x| x.body == b && x.jtype == JointType::Free);
        // Whether a body's subtree holds a joint other than a free joint.
        let mut jointed = vec![false; n];
        for x in &self.joints {
            if x.jtype == JointType::Free {
                continue;
            }
            let mut b = x.body;
            while b != 0 && b < n && !jointed[b] {
                jointed[b] = true;
                b = parent(b);
            }
        }
        let fork = |b: usize| (1..n).filter(|&c| parent(c) == b && jointed[c]).count() >= 2;
        // A body that no joint moves: the world and what is welded to it.
        let fixed = |mut b: usize| loop {
            if b == 0 {
                return true;
            }
            if hinged(b) || floating(b) {
                return false;
            }
            b = parent(b);
        };
        let mut b = j.body;
        loop {
            let p = parent(b);
            if b == 0 || p == b || fixed(p) || floating(p) || fork(p) {
                return Some(b);
            }
            b = p;
        }
    }
}

impl Robot {
    /// Whether `joint` turns a wheel: an unlimited hinge whose body carries a colliding round
    /// geom (sphere, or a cylinder, capsule or ellipsoid whose symmetry axis is the hinge axis,
    /// or a mesh whose bounding box is round about the hinge: [`round_mesh`]) centred on the
    /// axis at the keyframe, and that carries no jointed body further out (a
    /// wheel ends its chain: a round actuator housing on a thigh, concentric with the hip, is
    /// not a wheel). Wheels turn without end by design: they need no range and are not feet.
    pub fn is_wheel(&self, joint: usize) -> bool {
        self.joints.get(joint).is_some_and(|j| !j.limited) && self.turns_a_wheel(joint)
    }

    /// Whether hinge `joint` is shaped as a wheel's, limited or not: the geometry test of
    /// [`Robot::is_wheel`] (a round colliding geom centred on the axis, at the end of its chain).
    /// A wheel written with a range (a URDF's `revolute` wheel) turns about itself all the same.
    pub fn turns_a_wheel(&self, joint: usize) -> bool {
        let Some(j) = self.joints.get(joint) else { return false };
        if j.jtype != JointType::Hinge {
            return false;
        }
        let beyond = |mut b: usize| {
            for _ in 0..self.bodies.len() {
                let p = self.bodies.get(b).map_or(0, |x| x.parent);
                if p == j.body {
                    return true;
                }
                if p == b || p == 0 {
                    return false;
                }
                b = p;
            }
            false
        };
        if self.joints.iter().any(|o| o.body != j.body && beyond(o.body)) {
            return false;
        }
        let (Some(a), Some(u)) =
            (self.key.joint_xanchor.get(joint), self.key.joint_xaxis.get(joint))
        else {
            return false;
        };
        let nu = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt().max(1e-12);
        let u = [u[0] / nu, u[1] / nu, u[2] / nu];
        let aabb = self.mj.geom_aabb();
        self.geoms
            .iter()
            .filter(|g| g.body == j.body && crate::model::contact::takes_part(self, g.id))
            .any(|g| {
                let (Some(p), Some(m)) =
                    (self.key.geom_xpos.get(g.id), self.key.geom_xmat.get(g.id))
                else {
                    return false;
                };
                if g.gtype == GeomType::Mesh {
                    return aabb.get(g.id).is_some_and(|bb| round_mesh(bb, p, m, a, u));
                }
                let d = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
                let along = d[0] * u[0] + d[1] * u[1] + d[2] * u[2];
                let off = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - along * along).max(0.0).sqrt();
                let radius = g.size[0];
                if radius <= 0.0 || off > 0.1 * radius {
                    return false;
                }
                // The geom's own z axis (column 2 of the row-major frame).
                let z = [m[2], m[5], m[8]];
                let aligned = (z[0] * u[0] + z[1] * u[1] + z[2] * u[2]).abs() > 0.97;
                match g.gtype {
                    GeomType::Sphere => true,
                    GeomType::Cylinder | GeomType::Capsule => aligned,
                    GeomType::Ellipsoid => {
                        aligned && (g.size[0] - g.size[1]).abs() <= 0.05 * g.size[0]
                    }
                    _ => false,
                }
            })
    }
}

/// Whether a mesh geom is round about a hinge (anchor `a`, unit axis `u`): one of the axes of
/// its bounding box (`bb`: centre and half-sizes in the geom's frame, at `p` with row-major frame
/// `m`) lies along the hinge, the two across it are equal within 5 % (the ellipsoid test's
/// tolerance), and the box's centre is on the hinge within 10 % of that radius. A wheel or caster
/// mesh passes; so does a box that is square about the axis, which the chain test (a wheel ends
/// its chain) and the unlimited hinge keep from being a limb.
fn round_mesh(bb: &[f64; 6], p: &[f64; 3], m: &[f64; 9], a: &[f64; 3], u: [f64; 3]) -> bool {
    // Column i of the row-major frame: the geom's axis i in the world.
    let col = |i: usize| [m[i], m[3 + i], m[6 + i]];
    let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let Some(k) = (0..3).find(|&i| dot(col(i), u).abs() > 0.97) else { return false };
    let across: Vec<f64> = (0..3).filter(|&i| i != k).map(|i| bb[3 + i]).collect();
    let radius = across[0].max(across[1]);
    if radius <= 0.0 || (across[0] - across[1]).abs() > 0.05 * radius {
        return false;
    }
    let c: [f64; 3] = std::array::from_fn(|r| {
        p[r] + m[3 * r] * bb[0] + m[3 * r + 1] * bb[1] + m[3 * r + 2] * bb[2]
    });
    let d = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let along = dot(d, u);
    let off = (dot(d, d) - along * along).max(0.0).sqrt();
    off <= 0.1 * radius
}

impl Robot {
    /// The bodies that float over the world: a body with a free joint, and a floating base
    /// written as slides and a ball in place of one (humanoid-gym's files: a ball and a slide on
    /// the body, and every hinge or slide of it a base coordinate, [`Robot::is_base_coordinate`]).
    /// A planar base (slides and a hinge about the vertical, no ball) does not float.
    pub fn floating_bodies(&self) -> Vec<usize> {
        let on = |b: usize| self.joints.iter().filter(move |j| j.body == b);
        self.bodies
            .iter()
            .filter(|b| b.id != 0)
            .filter(|b| {
                let free = on(b.id).any(|j| j.jtype == JointType::Free);
                let slide_ball = on(b.id).any(|j| j.jtype == JointType::Ball)
                    && on(b.id).any(|j| j.jtype == JointType::Slide)
                    && on(b.id).filter(|j| j.is_scalar()).all(|j| self.is_base_coordinate(j.id));
                free || slide_ball
            })
            .map(|b| b.id)
            .collect()
    }

    /// Whether `joint` is a coordinate of a mobile base over the world, written in place of a
    /// free joint (a planar base: slides along x and y and a hinge about the vertical): it sits
    /// on a body whose parent is fixed to the world, and that body has two or more joints, all
    /// slides, hinges or a ball, at least one a slide (a floating base written as three slides
    /// and a ball, as humanoid-gym's files do, is one too). Such joints are where the base is on
    /// the floor, not motor joints: nothing stops them and they have no rotor of their own. A base whose
    /// coordinates are split over nested bodies (one joint each) is recognised by
    /// [`Robot::in_nested_planar_base`].
    pub fn is_base_coordinate(&self, joint: usize) -> bool {
        let Some(j) = self.joints.get(joint) else { return false };
        let scalar = |t: JointType| matches!(t, JointType::Hinge | JointType::Slide);
        if !scalar(j.jtype) || j.body == 0 {
            return false;
        }
        let Some(body) = self.bodies.get(j.body) else { return false };
        if self.bodies.get(body.parent).is_none_or(|p| p.weld != 0) {
            return self.in_nested_planar_base(joint);
        }
        let on_body: Vec<JointType> =
            self.joints.iter().filter(|x| x.body == j.body).map(|x| x.jtype).collect();
        (on_body.len() >= 2
            && on_body.iter().all(|t| scalar(*t) || *t == JointType::Ball)
            && on_body.iter().filter(|t| **t == JointType::Ball).count() <= 1
            && on_body.contains(&JointType::Slide))
            || self.in_nested_planar_base(joint)
    }

    /// Whether `joint` is one of the first joints below the world of a planar base written over
    /// nested bodies: walking down from the first moving body under a world-fixed parent, the
    /// leading joints are slides along the floor (world axis with no vertical part) and at
    /// most one hinge about the vertical, at most two slides, down to the first body with a
    /// geom (the chassis); the base is planar when two of those slides have different axes (x
    /// and y). `joint` counts when it is in that leading run. An arm on one linear rail (one
    /// slide) is not a planar base.
    fn in_nested_planar_base(&self, joint: usize) -> bool {
        let Some(j) = self.joints.get(joint) else { return false };
        // Bodies from the top moving body down to the joint's body.
        let mut path = vec![j.body];
        for _ in 0..self.bodies.len() {
            let b = *path.last().unwrap_or(&0);
            let Some(p) = self.bodies.get(b).map(|x| x.parent) else { return false };
            if p == b || self.bodies.get(p).is_none_or(|x| x.weld == 0) {
                break;
            }
            path.push(p);
        }
        path.reverse();
        // Below the joint's body the run may go on (the joint may be the base's first
        // coordinate): follow the only child body while there is exactly one.
        for _ in 0..self.bodies.len() {
            let b = *path.last().unwrap_or(&0);
            let mut kids = self.bodies.iter().filter(|x| x.parent == b && x.id != b);
            match (kids.next(), kids.next()) {
                (Some(k), None) => path.push(k.id),
                _ => break,
            }
        }
        let (mut slides, mut hinge, mut run) = (Vec::<[f64; 3]>::new(), false, Vec::new());
        'walk: for b in path {
            for x in self.joints.iter().filter(|x| x.body == b) {
                let Some(a) = self.key.joint_xaxis.get(x.id) else { break 'walk };
                let along_floor = a[2] == 0.0 && (a[0] != 0.0 || a[1] != 0.0);
                let vertical = a[0] == 0.0 && a[1] == 0.0 && a[2] != 0.0;
                match x.jtype {
                    JointType::Slide if along_floor && slides.len() < 2 => slides.push(*a),
                    JointType::Hinge if vertical && !hinge => hinge = true,
                    _ => break 'walk,
                }
                run.push(x.id);
            }
            // The base's coordinates end with the first body that has a shape (the chassis):
            // a vertical hinge further down is the arm's, not the base's yaw.
            if self.geoms.iter().any(|g| g.body == b) {
                break;
            }
        }
        let distinct = slides.len() == 2
            && (slides[0][0] * slides[1][1] - slides[0][1] * slides[1][0]).abs() > 0.0;
        distinct && run.contains(&joint)
    }
}

#[cfg(test)]
mod tests {
    use crate::model::load;
    use crate::model::source::SourceMap;

    fn model(xml: &str) -> crate::model::Robot {
        let dir = std::env::temp_dir().join(format!("modellint_limbs_{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let p = dir.join(format!("m{}.xml", xml.len()));
        std::fs::write(&p, xml).expect("write");
        load(&mut SourceMap::default(), &p, None).expect("loads")
    }

    #[test]
    fn legs_of_a_floating_trunk_are_separate_limbs_and_a_leg_is_one() {
        let r = model(
            r#"<mujoco><worldbody><body name="trunk"><freejoint/><geom size=".1"/>
            <body name="pelvis"><joint name="waist" axis="0 0 1"/><geom size=".1"/>
            <body name="lthigh"><joint name="lhip" axis="0 1 0"/><geom size=".05"/>
              <body name="lshank"><joint name="lknee" axis="0 1 0"/><geom size=".05"/></body></body>
            <body name="rthigh"><joint name="rhip" axis="0 1 0"/><geom size=".05"/>
              <body name="rshank"><joint name="rknee" axis="0 1 0"/><geom size=".05"/></body></body>
            </body></body></worldbody></mujoco>"#,
        );
        let l = r.limb_of("lknee").expect("limb");
        // The waist is a limb of its own; each leg below it another.
        assert_ne!(r.limb_of("waist"), Some(l));
        assert_ne!(r.limb_of("waist"), r.limb_of("rknee"));
        assert_eq!(r.limb_of("lhip"), Some(l));
        assert_ne!(r.limb_of("rknee"), Some(l));
        assert_eq!(r.limb_of("rhip"), r.limb_of("rknee"));
    }

    #[test]
    fn a_serial_arm_on_a_static_base_is_one_limb() {
        let r = model(
            r#"<mujoco><worldbody><body name="base"><geom size=".1"/>
            <body name="a"><joint name="j1"/><geom size=".05"/>
              <body name="b"><joint name="j2"/><geom size=".05"/>
                <body name="c"><joint name="j3"/><geom size=".05"/></body></body></body>
            </body></worldbody></mujoco>"#,
        );
        let l = r.limb_of("j3");
        assert!(l.is_some());
        assert_eq!(r.limb_of("j1"), l);
        assert_eq!(r.limb_of("j2"), l);
        assert_eq!(r.limb_of("nope"), None);
    }
}
