use super::*;
use crate::declare_effect;

declare_effect! {
    /// The ground contact under a foot softer, stiffer or more damped than modelled (a real floor and sole against MuJoCo's soft contact).
    ///
    /// MuJoCo-native: the contact between the joint's child body (a foot) and the ground it
    /// stands on (a plane, height field or box of the world body, `model::contact`) gets the
    /// solver reference `timeconst` (the contact's time constant [s]) and `dampratio` (its damping
    /// ratio) of MuJoCo's `solref`, and the impedance `dmin` at first touch and `width` (the
    /// penetration over which the impedance rises to the contact's `dmax` [m]) of its `solimp`.
    /// A wide impedance ramp makes the contact's force grow with each point's own penetration —
    /// a rocking sole then sinks at the toe and lifts at the heel as on a compliant floor — where
    /// a narrow one acts on the foot's whole motion through its effective mass (MuJoCo
    /// documentation, *Computation: soft constraints*). The foot's geoms take the ground's
    /// priority + 1, so that their own parameters are the contact's; the rest of their `solimp`,
    /// their friction and `condim` are set to the values the contact had. A candidate only on a
    /// joint whose child body touches the ground through its geoms (not through an explicit
    /// `<pair>`, nor where the ground's priority decides, nor with a direct, negative `solref`).
    /// Fitted as the foot's contact, not as a joint's physics: it acts on every joint through
    /// the ground. Tried only when named (`--effects`, `--told`).
    ///
    /// ## Simulation
    /// the foot's `geom_solref` and `geom_solimp` (dmin, width; and `geom_priority`, `geom_friction`, `geom_condim` to keep the rest of the contact)
    ///
    /// ## Signature
    /// servo torque `τ` (ranked by the simulated sensitivity)
    ///
    /// ## Write-back
    /// the foot's ground-touching `<geom>`s: `solref`, `priority`, `solimp`, `friction`, `condim`
    ///
    /// ## Isaac Lab / mjlab
    /// comment with the parameters (the contact's stiffness and damping are the simulator's own)
    pub GroundContact {
        id: "ground_contact",
        entry: Model,
        params: [
            ParamDef { name: "timeconst", unit: "s", lo: 0.002, hi: 0.1, default: 0.02 },
            ParamDef { name: "dampratio", unit: "", lo: 0.2, hi: 4.0, default: 1.0 },
            ParamDef { name: "dmin", unit: "", lo: 0.05, hi: 0.99, default: 0.9 },
            ParamDef { name: "width", unit: "m", lo: 0.0001, hi: 0.02, default: 0.001 },
        ],
    }
}

impl Effect for GroundContact {
    /// The contact's solref, solimp dmin and width as the model gives them (the first
    /// ground-touching geom's).
    fn initial(&self, _m: &MjModel, t: &JointTarget) -> Vec<f64> {
        match t.ground.first() {
            Some(g) => {
                let (r, i) = (g.contact.solref, g.contact.solimp);
                vec![r[0], r[1], i[0], i[2]]
            }
            None => self.params().iter().map(|p| p.default).collect(),
        }
    }
    /// Time constant from twice the timestep (MuJoCo's own floor for it) to 0.1 s, damping
    /// ratio 0.2–4, dmin 0.05–0.99, width 0.1 mm – 2 cm (each widened to hold the model's own
    /// value).
    fn bounds(&self, m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        let ps = self.params();
        let start = self.initial(m, t);
        let mut lo: Vec<f64> = ps.iter().map(|p| p.lo).collect();
        let mut hi: Vec<f64> = ps.iter().map(|p| p.hi).collect();
        lo[0] = (2.0 * m.opt().timestep).max(lo[0]);
        for k in 0..ps.len() {
            if let Some(&s) = start.get(k).filter(|s| s.is_finite()) {
                if k > 0 {
                    lo[k] = lo[k].min(s);
                }
                hi[k] = hi[k].max(s);
            }
        }
        hi[0] = hi[0].max(lo[0]);
        (lo, hi)
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        for g in &t.ground {
            let mut imp = g.contact.solimp;
            if let (Some(&dmin), Some(&width)) = (p.get(2), p.get(3)) {
                imp[0] = dmin;
                imp[2] = width;
            }
            set_contact(m, g, [p[0], p[1]], imp);
        }
    }
    /// Not smooth: the impedance ramp makes the error surface one of several basins (which
    /// penetration the feet settle at inside the ramp), where a least-squares step from the
    /// model's contact stops in the nearest; fitted by the derivative-free search.
    fn smooth(&self) -> bool {
        false
    }
    fn signature(&self, s: &Samples) -> Signature {
        Signature::centred(s.tau.clone())
    }
    fn screened(&self) -> usize {
        2
    }
    fn write_back(&self, _p: &[f64]) -> WriteBack {
        WriteBack::Geoms
    }
    fn by_default(&self) -> bool {
        false
    }
    fn acts_on(&self, t: &JointTarget) -> bool {
        !t.ground.is_empty()
    }
    /// The floor pushes on the whole standing chain, not on the foot's joint alone.
    fn joint_local(&self) -> bool {
        false
    }
    /// A group only of feet: a joint whose body touches no ground has no contact to share.
    fn alike(&self, a: &JointTarget, b: &JointTarget) -> bool {
        self.acts_on(a) && self.acts_on(b)
    }
}

/// Gives geom `g.geom` the contact `g.contact` with `solref` and `solimp`, by priority over its
/// ground.
fn set_contact(m: &mut MjModel, g: &GroundGeom, solref: [f64; 2], solimp: [f64; 5]) {
    let i = g.geom;
    let c = &g.contact;
    if let Some(x) = m.geom_priority_mut().get_mut(i) {
        *x = (*x).max(g.ground_priority.saturating_add(1));
    }
    if let Some(x) = m.geom_solref_mut().get_mut(i) {
        *x = solref;
    }
    if let Some(x) = m.geom_solimp_mut().get_mut(i) {
        *x = solimp;
    }
    if let Some(x) = m.geom_friction_mut().get_mut(i) {
        *x = c.friction;
    }
    // SAFETY: condim is read by the collision code only, as any other geom parameter; no
    // derived array depends on it.
    if let Some(x) = unsafe { m.geom_condim_mut() }.get_mut(i) {
        *x = c.condim;
    }
}

/// A geom of a joint's child body that touches the ground, with the contact's parameters as the
/// model gives them.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundGeom {
    pub geom: usize,
    pub contact: crate::model::contact::Combined,
    /// The priority of the ground geom it touches.
    pub ground_priority: i32,
}

/// How close to a ground plane a geom's lowest point must be at the keyframe to stand on it [m].
const STANDING: f64 = 0.005;

/// The geoms of body `body` that stand on the world's ground at the keyframe (their lowest
/// point within [`STANDING`] of a ground plane) through their own parameters (none through an
/// explicit pair, where the ground wins on priority, or with a direct solref).
pub fn ground_geoms(robot: &Robot, body: usize) -> Vec<GroundGeom> {
    robot
        .geoms
        .iter()
        .filter(|g| g.body == body && body > 0)
        .filter_map(|g| {
            let (ground, contact) = crate::model::contact::ground_partners(robot, g.id)
                .into_iter()
                .find(|(p, _)| height_above(robot, g.id, *p).is_some_and(|h| h <= STANDING))?;
            let gp = robot.geoms.get(ground)?.priority;
            let own = contact.pair.is_none()
                && contact.by_priority.is_none_or(|w| w == g.id)
                && contact.solref[0] > 0.0;
            own.then_some(GroundGeom { geom: g.id, contact, ground_priority: gp })
        })
        .collect()
}

/// The height of geom `g`'s lowest point above the plane geom `plane` at the keyframe (negative:
/// below it); `None` when `plane` is not a plane. Exact for spheres, capsules, cylinders, boxes
/// and ellipsoids, the bounding sphere for the other shapes.
fn height_above(robot: &Robot, g: usize, plane: usize) -> Option<f64> {
    use crate::model::GeomType;
    let (p, x) = (robot.geoms.get(plane)?, robot.geoms.get(g)?);
    if p.gtype != GeomType::Plane {
        return None;
    }
    let k = &robot.key;
    let (pm, pp, xm, xp) =
        (k.geom_xmat.get(plane)?, k.geom_xpos.get(plane)?, k.geom_xmat.get(g)?, k.geom_xpos.get(g)?);
    let n = [pm[2], pm[5], pm[8]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    // The geom's local axes' components along the plane's normal.
    let a = [0, 1, 2].map(|i| dot([xm[i], xm[3 + i], xm[6 + i]], n).abs());
    let s = x.size;
    let reach = match x.gtype {
        GeomType::Sphere => s[0],
        GeomType::Capsule => s[0] + s[1] * a[2],
        GeomType::Cylinder => s[0] * (1.0 - a[2] * a[2]).max(0.0).sqrt() + s[1] * a[2],
        GeomType::Box => s[0] * a[0] + s[1] * a[1] + s[2] * a[2],
        GeomType::Ellipsoid => ((s[0] * a[0]).powi(2) + (s[1] * a[1]).powi(2) + (s[2] * a[2]).powi(2)).sqrt(),
        _ => x.rbound,
    };
    let centre = dot([xp[0] - pp[0], xp[1] - pp[1], xp[2] - pp[2]], n);
    Some(centre - reach)
}
