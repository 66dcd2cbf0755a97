//! Rigid-body mass properties for the body effects (`link_mass`, `com_offset`,
//! `link_inertia`): a body's mass, centre of mass and inertia as MuJoCo stores them — principal
//! moments `body_inertia` in the frame `body_iquat` at `body_ipos`, all in the body's frame —
//! read as one full inertia tensor, changed, and stored back in principal form. Every change
//! here maps a valid rigid body to a valid one (a point mass ≥ 0 added, the mass distribution
//! translated, its extent along a principal axis scaled), so no fitted value can be a body that
//! does not exist.

use mujoco_rs::prelude::*;
use nalgebra::{Matrix3, Rotation3, SymmetricEigen, UnitQuaternion, Vector3};

use super::JointTarget;

/// The nominal (compiled, as given) mass properties of a joint's child body and the link's
/// directions, from which the body effects' parameters are measured. Read once from the model
/// as given, so that the parameters mean the same whatever else is applied to the copy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyAxes {
    /// MuJoCo body id of the joint's child body.
    pub body: usize,
    /// Its mass [kg] and the mass of its subtree [kg].
    pub mass: f64,
    pub subtree_mass: f64,
    /// Its centre of mass in the body frame [m].
    pub com: [f64; 3],
    /// Unit vector along the link: from the body's origin (the joint) to its centre of mass,
    /// else to its first child body, else perpendicular to the joint axis.
    pub along: [f64; 3],
    /// Unit vector across the link: joint axis × `along` (in the joint's plane of motion). When
    /// the link lies along its own joint's axis (a yaw joint whose link hangs along it), the
    /// axis of the nearest joint that turns the link otherwise (a carrying pitch or roll) ×
    /// `along`: the direction that joint swings the link's centre.
    pub across: [f64; 3],
    /// Unit vector `along` × `across`: the joint axis where the link is perpendicular to it,
    /// the second perpendicular to the link where the link lies along it.
    pub normal: [f64; 3],
    /// Whether a rotation moves the body's centre of mass along [`BodyAxes::normal`]: some
    /// hinge moving the body (its own or a carrying one) has an axis not parallel to `normal`,
    /// or a ball or free joint carries it. In a planar chain (every hinge parallel) a place
    /// along `normal` changes no torque and no motion, and it is not a parameter.
    pub normal_seen: bool,
    /// The joint's axis (unit; `along`'s perpendicular when the model gives none).
    pub axis: [f64; 3],
    /// The link's length scale [m]: the largest of twice the centre of mass's distance, the
    /// distance to a child body, and 5 cm.
    pub length: f64,
    /// Whether a joint other than its own moves the body (a joint of an ancestor body, or a
    /// second joint of its own). When none does, the body's inertia about the joint axis adds
    /// to the mass matrix exactly what the joint's armature adds (one diagonal entry).
    pub carried: bool,
}

fn v3(a: [f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}

/// A unit vector perpendicular to `a` (non-zero).
fn perpendicular(a: Vector3<f64>) -> Vector3<f64> {
    let trial = if a.x.abs() < 0.9 { Vector3::x() } else { Vector3::z() };
    a.cross(&trial).normalize()
}

/// Sine of the angle below which two axes are taken as parallel: the rounding of a model's
/// axes, not a physical scale.
const PARALLEL: f64 = 1e-6;

/// The rotation axes of every joint that moves body `b`, its own first, then each ancestor's,
/// in `b`'s frame at the model's reference pose (`Some(axis)` of a hinge, `None` of a ball or
/// free joint, which turns it about every axis; slides turn nothing).
fn turning_axes(m: &MjModel, b: usize) -> Vec<Option<Vector3<f64>>> {
    let (adr, num, quat, parent) =
        (m.body_jntadr(), m.body_jntnum(), m.body_quat(), m.body_parentid());
    let (types, axes) = (m.jnt_type(), m.jnt_axis());
    let mut out = Vec::new();
    // Maps a vector in body `c`'s frame into `b`'s.
    let mut r = Matrix3::identity();
    let mut c = b;
    for _ in 0..parent.len() {
        if c == 0 {
            break;
        }
        let first = adr.get(c).and_then(|&a| usize::try_from(a).ok()).unwrap_or(0);
        let n = num.get(c).and_then(|&n| usize::try_from(n).ok()).unwrap_or(0);
        for j in first..first + n {
            match types.get(j).map(|&t| t as i32) {
                Some(3) => {
                    if let Some(a) = axes.get(j).map(|&a| r * v3(a)).filter(|a| a.norm() > 1e-9) {
                        out.push(Some(a));
                    }
                }
                Some(0 | 1) => out.push(None),
                _ => {}
            }
        }
        let Some(q) = quat.get(c) else { break };
        let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]));
        r *= q.to_rotation_matrix().into_inner().transpose();
        match parent.get(c).and_then(|&p| usize::try_from(p).ok()) {
            Some(p) if p != c => c = p,
            _ => break,
        }
    }
    out
}

impl BodyAxes {
    /// The axes of joint `jnt`'s child body in `m` (`None` for the world body or out of range).
    pub fn of(m: &MjModel, jnt: usize) -> Option<BodyAxes> {
        let b = usize::try_from(*m.jnt_bodyid().get(jnt)?).ok().filter(|&b| b > 0)?;
        let com = *m.body_ipos().get(b)?;
        let axis = v3(*m.jnt_axis().get(jnt)?);
        let child = m
            .body_parentid()
            .iter()
            .enumerate()
            .filter(|&(c, &p)| c != b && usize::try_from(p).ok() == Some(b))
            .map(|(c, _)| v3(m.body_pos()[c]))
            .max_by(|x, y| x.norm().total_cmp(&y.norm()));
        let child_len = child.map_or(0.0, |c| c.norm());
        let along = if v3(com).norm() > 1e-4 {
            v3(com).normalize()
        } else if child_len > 1e-4 {
            child.unwrap_or_default().normalize()
        } else if axis.norm() > 1e-9 {
            perpendicular(axis)
        } else {
            Vector3::z()
        };
        let turning = turning_axes(m, b);
        // The nearest joint whose rotation swings `along` (the own joint first): its axis ×
        // `along`; a ball or free joint swings it every way.
        let across = std::iter::once(Some(axis))
            .chain(turning.iter().copied())
            .find_map(|a| match a {
                Some(a) => {
                    let c = a.cross(&along);
                    (c.norm() > PARALLEL * a.norm()).then(|| c.normalize())
                }
                None => Some(perpendicular(along)),
            })
            .unwrap_or_else(|| perpendicular(along));
        let normal = along.cross(&across).normalize();
        let normal_seen = turning.iter().any(|a| match a {
            Some(a) => a.cross(&normal).norm() > PARALLEL * a.norm(),
            None => true,
        });
        let length = (2.0 * v3(com).norm()).max(child_len).max(0.05);
        let axis = if axis.norm() > 1e-9 { axis.normalize() } else { perpendicular(along) };
        let finite = |x: f64| if x.is_finite() { x } else { 0.0 };
        let (jntnum, parent) = (m.body_jntnum(), m.body_parentid());
        let mut carried = jntnum.get(b).is_some_and(|&n| n > 1);
        let mut p = parent.get(b).and_then(|&p| usize::try_from(p).ok());
        for _ in 0..jntnum.len() {
            match p {
                Some(a) if a > 0 && !carried => {
                    carried = jntnum.get(a).is_some_and(|&n| n > 0);
                    p = parent.get(a).and_then(|&q| usize::try_from(q).ok());
                }
                _ => break,
            }
        }
        Some(BodyAxes {
            body: b,
            mass: finite(*m.body_mass().get(b)?),
            subtree_mass: finite(*m.body_subtreemass().get(b)?),
            com,
            along: along.into(),
            across: across.into(),
            normal: normal.into(),
            normal_seen,
            axis: axis.into(),
            length: finite(length),
            carried,
        })
    }

    /// Whether `self` and `other` are alike links (mirror links, the same link on every leg), so
    /// that one body-effect parameter vector means the same on both: mass, subtree mass, the
    /// centre of mass's distance from the joint and the link's length within 1 %.
    pub fn alike(&self, other: &BodyAxes) -> bool {
        let near = |a: f64, b: f64| (a - b).abs() <= 0.01 * a.abs().max(b.abs()).max(1e-9);
        near(self.mass, other.mass)
            && near(self.subtree_mass, other.subtree_mass)
            && near(v3(self.com).norm(), v3(other.com).norm())
            && near(self.length, other.length)
    }

    /// A point in the body frame: the nominal centre of mass moved by `a` along the link, `c`
    /// across it and `n` along [`BodyAxes::normal`].
    pub fn point(&self, a: f64, c: f64, n: f64) -> Vector3<f64> {
        v3(self.com) + a * v3(self.along) + c * v3(self.across) + n * v3(self.normal)
    }

    /// The bound of a place along [`BodyAxes::normal`] whose half-width is `h`: `h` where a
    /// rotation moves the body along it, else 0 (the place is no parameter).
    pub fn normal_bound(&self, h: f64) -> f64 {
        if self.normal_seen { h } else { 0.0 }
    }

    /// A rotation whose last column is the joint axis and whose first two span the plane
    /// perpendicular to it (the plane a hinge turns the body in).
    pub fn joint_frame(&self) -> Matrix3<f64> {
        let a = v3(self.axis);
        let w = a.cross(&v3(self.along));
        let w = if w.norm() > 1e-6 { w.normalize() } else { perpendicular(a) };
        Matrix3::from_columns(&[w, a.cross(&w), a])
    }
}

/// [`crate::fit::effects::Effect::alike`] of the body effects: both joints have a child body,
/// and the two bodies are alike.
pub fn alike_targets(a: &JointTarget, b: &JointTarget) -> bool {
    matches!((&a.body, &b.body), (Some(x), Some(y)) if x.alike(y))
}

/// The [`crate::fit::effects::Effect`] methods every body effect shares, in its `impl`: smooth
/// in its parameters, diagnosed by the centred `$feature` of the samples (`tau`, `qdd`), written
/// back as the body's `<inertial>`, and grouped over alike links only ([`alike_targets`]).
macro_rules! body_effect_methods {
    ($feature:ident) => {
        fn smooth(&self) -> bool {
            true
        }
        fn signature(&self, s: &Samples) -> Signature {
            Signature::centred(s.$feature.clone())
        }
        fn write_back(&self, _p: &[f64]) -> WriteBack {
            WriteBack::Inertial
        }
        fn alike(&self, a: &JointTarget, b: &JointTarget) -> bool {
            inertial::alike_targets(a, b)
        }
        fn joint_local(&self) -> bool {
            false
        }
    };
}
pub(crate) use body_effect_methods;

/// Body `b`'s mass, centre of mass and full inertia tensor about it, in the body frame.
pub fn read(m: &MjModel, b: usize) -> Option<(f64, Vector3<f64>, Matrix3<f64>)> {
    let mass = *m.body_mass().get(b)?;
    let com = v3(*m.body_ipos().get(b)?);
    let d = *m.body_inertia().get(b)?;
    let q = *m.body_iquat().get(b)?;
    let r = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]));
    let r = r.to_rotation_matrix().into_inner();
    Some((mass, com, r * Matrix3::from_diagonal(&v3(d)) * r.transpose()))
}

/// Principal moments and MuJoCo's `iquat` (w, x, y, z) of a symmetric inertia tensor.
pub fn principal(i: &Matrix3<f64>) -> ([f64; 3], [f64; 4]) {
    let sym = (i + i.transpose()) * 0.5;
    let eig = SymmetricEigen::new(sym);
    let mut r = eig.eigenvectors;
    if r.determinant() < 0.0 {
        r.column_mut(2).neg_mut();
    }
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let d = eig.eigenvalues;
    ([d[0].max(0.0), d[1].max(0.0), d[2].max(0.0)], [q.w, q.i, q.j, q.k])
}

/// Stores body `b`'s mass properties (mass, centre of mass, inertia about it, body frame) in
/// the model copy; the subtree masses of the body and its ancestors follow the mass.
pub fn write(m: &mut MjModel, b: usize, mass: f64, com: Vector3<f64>, i: &Matrix3<f64>) {
    let Some(old) = m.body_mass().get(b).copied() else { return };
    let (d, q) = principal(i);
    m.body_mass_mut()[b] = mass;
    m.body_ipos_mut()[b] = com.into();
    m.body_inertia_mut()[b] = d;
    m.body_iquat_mut()[b] = q;
    // MuJoCo skips the inertial frame of a body whose inertia sat at its origin
    // (`body_sameframe`), and fills the mass matrix of "simple" DoFs from `dof_M0` compiled at
    // qpos0: neither holds once the body changed, so the general path is taken everywhere.
    m.body_sameframe_mut()[b] = mujoco_rs::wrappers::mj_model::MjtSameFrame::mjSAMEFRAME_NONE;
    m.dof_simplenum_mut().iter_mut().for_each(|n| *n = 0);
    let parents: Vec<i32> = m.body_parentid().to_vec();
    let mut at = b;
    loop {
        if let Some(s) = m.body_subtreemass_mut().get_mut(at) {
            *s += mass - old;
        }
        match parents.get(at).and_then(|&p| usize::try_from(p).ok()) {
            Some(p) if p != at => at = p,
            _ => break,
        }
    }
}

/// The inertia a point mass `mass` at offset `d` from a centre contributes about it.
fn point_inertia(mass: f64, d: Vector3<f64>) -> Matrix3<f64> {
    (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * mass
}

/// Adds a point mass `dm` ≥ 0 at `p` (body frame) to body `b`: the combined centre of mass and
/// the inertia about it by the parallel-axis theorem.
pub fn add_point_mass(m: &mut MjModel, b: usize, dm: f64, p: Vector3<f64>) {
    let Some((mass, com, i)) = read(m, b) else { return };
    let dm = dm.max(0.0);
    if dm == 0.0 || mass + dm <= 0.0 {
        return;
    }
    let total = mass + dm;
    let c = (com * mass + p * dm) / total;
    let i2 = i + point_inertia(mass, com - c) + point_inertia(dm, p - c);
    write(m, b, total, c, &i2);
}

/// Moves body `b`'s mass distribution by `d` (body frame): the centre of mass moves, the
/// inertia about it stays.
pub fn shift(m: &mut MjModel, b: usize, d: Vector3<f64>) {
    let Some((mass, com, i)) = read(m, b) else { return };
    if d.norm() == 0.0 {
        return;
    }
    write(m, b, mass, com + d, &i);
}

/// Scales body `b`'s extent along the principal axes of its *nominal* inertia `axes` (a
/// rotation whose columns are the axes) by `e^{s_k}`: the second moments of the mass
/// distribution Σ = ½ tr(I) 1 − I (the pseudo-inertia's covariance, positive semi-definite for
/// every real body) become `S Σ S` with `S = R diag(e^s) Rᵀ`, and the inertia `tr(Σ') 1 − Σ'`.
/// Every `s` gives a valid rigid body (the triangle inequality holds by construction).
pub fn scale_extent(m: &mut MjModel, b: usize, axes: &Matrix3<f64>, s: [f64; 3]) {
    let Some((mass, com, i)) = read(m, b) else { return };
    if s.iter().all(|&x| x == 0.0) {
        return;
    }
    let sigma = Matrix3::identity() * (0.5 * i.trace()) - i;
    let k = axes * Matrix3::from_diagonal(&Vector3::new(s[0].exp(), s[1].exp(), s[2].exp()));
    let k = k * axes.transpose();
    let sigma2 = k * sigma * k;
    let i2 = Matrix3::identity() * sigma2.trace() - sigma2;
    write(m, b, mass, com, &i2);
}

/// `true` when (principal moments) describe a rigid body: all ≥ 0 and each at most the sum of
/// the other two (within a relative 1e-9).
pub fn valid(d: [f64; 3]) -> bool {
    let tol = 1e-9 * (d[0] + d[1] + d[2]).abs().max(1e-300);
    d.iter().all(|&x| x >= -tol && x.is_finite())
        && d[0] <= d[1] + d[2] + tol
        && d[1] <= d[0] + d[2] + tol
        && d[2] <= d[0] + d[1] + tol
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn principal_form_round_trips_a_rotated_tensor() {
        let r = Rotation3::from_euler_angles(0.3, -0.7, 1.1).into_inner();
        let i = r * Matrix3::from_diagonal(&Vector3::new(0.01, 0.02, 0.025)) * r.transpose();
        let (d, q) = principal(&i);
        let mut s = d;
        s.sort_by(f64::total_cmp);
        assert!((s[0] - 0.01).abs() < 1e-12 && (s[2] - 0.025).abs() < 1e-12, "{d:?}");
        let rq = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]))
            .to_rotation_matrix()
            .into_inner();
        let back = rq * Matrix3::from_diagonal(&v3(d)) * rq.transpose();
        assert!((back - i).norm() < 1e-12);
        assert!(valid(d));
        assert!(!valid([1.0, 0.1, 0.1]));
    }
}
