use crate::declare_rule;
use crate::finding::{Finding, Severity};
use crate::model::contact::takes_part;
use crate::model::mjcf::ElemKind;
use crate::model::{GeomType, Robot};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds `<touch>` sensors whose site cannot hold the contacts of the end it was placed at
    /// while another touch sensor of the model holds its own. MuJoCo's touch sensor adds the
    /// normal forces of the contacts of the site's body whose contact point lies inside the
    /// site's volume (MuJoCo XML reference, `sensor/touch`); a contact point lies midway between
    /// the two surfaces, inside the colliding geom by half the penetration. For each touch
    /// sensor whose site sits on an end body (a body with no child body: a foot, a fingertip),
    /// the body's distal geom is its colliding geom that reaches farthest from the body's frame
    /// (the joint): its bounding sphere's far side. The site's volume (a sphere's radius; for
    /// other site types the bounding sphere of their size, which can only shrink a gap) is
    /// compared with that geom's surface (sphere, capsule, cylinder, box; a distal mesh or
    /// ellipsoid is not judged). When at least one touch site on an end body reaches its
    /// distal geom — the model's touch sensors are meant for those contacts — each other one
    /// that stays more than `gap` from its own distal geom is reported, with the distance.
    /// Not judged: a model whose touch sites all stay off their distal geoms (sensors placed
    /// for another contact: a shin, a bumper), sites on bodies with children.
    ///
    /// ## Why is this bad?
    /// A touch sensor whose site misses the foot reads 0 in every stance: the policy's contact
    /// observation for that leg is dead in simulation while the hardware's contact estimate is
    /// not, and gait rewards built on foot contact never see that foot land. A site copied from
    /// one leg and edited on another (Deep Robotics X30's `FL_touch` at the foot, z −0.31 m,
    /// the other three at −0.21 m, 0.1 m up the shank) gives no error in MuJoCo.
    ///
    /// ## How it is confirmed
    /// Static: the compiled site and geom frames and sizes in their body's frame, which MuJoCo
    /// uses as written; no pose changes them.
    ///
    /// ## How to fix
    /// Put the site where the contact happens: centred on the foot geom (a sphere site of the
    /// foot sphere's radius or a little more), as on the leg whose sensor works.
    pub TouchSensorSite {
        id: "touch-sensor-site",
        group: "mapping",
        level: Severity::Warning,
        probe: None,
        options: [opt("gap", 0.001, "m", Domain::NON_NEGATIVE, "largest distance between a touch site's volume and its body's distal geom still taken as reaching it (rounding of the written numbers)")],
    }
}

type V3 = [f64; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn norm(a: V3) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}
/// `p` in the frame of a body-local placement `pos`, `quat` (w, x, y, z): the conjugate
/// rotation of `p − pos`.
fn into_frame(pos: V3, q: [f64; 4], p: V3) -> V3 {
    let v = sub(p, pos);
    let (w, x, y, z) = (q[0], -q[1], -q[2], -q[3]);
    let n = (w * w + x * x + y * y + z * z).sqrt().max(1e-12);
    let (w, x, y, z) = (w / n, x / n, y / n, z / n);
    // v' = v + 2w (u × v) + 2 u × (u × v), u = (x, y, z)
    let c1 = [y * v[2] - z * v[1], z * v[0] - x * v[2], x * v[1] - y * v[0]];
    let c2 = [y * c1[2] - z * c1[1], z * c1[0] - x * c1[2], x * c1[1] - y * c1[0]];
    [
        v[0] + 2.0 * (w * c1[0] + c2[0]),
        v[1] + 2.0 * (w * c1[1] + c2[1]),
        v[2] + 2.0 * (w * c1[2] + c2[2]),
    ]
}

/// Distance from point `p` (in the geom's own frame) to the surface of a primitive, 0 inside
/// it; `None` for shapes not judged.
pub fn distance_to_primitive(gtype: GeomType, s: V3, p: V3) -> Option<f64> {
    let d = match gtype {
        GeomType::Sphere => norm(p) - s[0],
        GeomType::Capsule => norm([p[0], p[1], p[2] - p[2].clamp(-s[1], s[1])]) - s[0],
        GeomType::Cylinder => {
            let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
            let (dr, dz) = (r - s[0], p[2].abs() - s[1]);
            (dr.max(0.0).powi(2) + dz.max(0.0).powi(2)).sqrt() + dr.max(dz).min(0.0)
        }
        GeomType::Box => {
            let q = [p[0].abs() - s[0], p[1].abs() - s[1], p[2].abs() - s[2]];
            norm([q[0].max(0.0), q[1].max(0.0), q[2].max(0.0)]) + q[0].max(q[1]).max(q[2]).min(0.0)
        }
        _ => return None,
    };
    Some(d.max(0.0))
}

/// Radius of the ball a site's volume fits in (its own radius for a sphere).
fn site_radius(t: i32, s: V3) -> f64 {
    match t {
        2 => s[0],                               // sphere
        3 => s[0] + s[1],                        // capsule
        5 => (s[0] * s[0] + s[1] * s[1]).sqrt(), // cylinder
        _ => norm(s),                            // box, ellipsoid: the half-size diagonal bounds it
    }
}

/// The colliding geom of `body` that reaches farthest from the body's frame.
fn distal_geom(robot: &Robot, body: usize) -> Option<usize> {
    let (pos, rb) = (robot.mj.geom_pos(), robot.mj.geom_rbound());
    robot
        .geoms
        .iter()
        .filter(|g| g.body == body && takes_part(robot, g.id))
        .map(|g| (g.id, norm(pos[g.id]) + rb[g.id]))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(g, _)| g)
}

/// One touch sensor on an end body: (sensor index, site, distal geom, gap to it in m).
struct Touch {
    sensor: usize,
    site: usize,
    geom: usize,
    gap: f64,
}

fn touches(robot: &Robot) -> Vec<Touch> {
    let m = &robot.mj;
    let (st, so, sid) = (m.sensor_type(), m.sensor_objtype(), m.sensor_objid());
    let (site_body, spos, ssize, stype) =
        (m.site_bodyid(), m.site_pos(), m.site_size(), m.site_type());
    let (gpos, gquat) = (m.geom_pos(), m.geom_quat());
    let has_child = |b: usize| robot.bodies.iter().any(|x| x.id != 0 && x.parent == b);
    let mut out = Vec::new();
    for (i, ((&t, &o), &id)) in st.iter().zip(so.iter()).zip(sid.iter()).enumerate() {
        // mjSENS_TOUCH = 0; its object is a site (mjOBJ_SITE = 6).
        if t as i32 != 0 || o as i32 != 6 {
            continue;
        }
        let Ok(site) = usize::try_from(id) else { continue };
        let body = site_body[site].max(0) as usize;
        if body == 0 || has_child(body) {
            continue;
        }
        let Some(g) = distal_geom(robot, body) else { continue };
        let geom = &robot.geoms[g];
        let local = into_frame(gpos[g], gquat[g], spos[site]);
        let Some(d) = distance_to_primitive(geom.gtype, geom.size, local) else { continue };
        let gap = (d - site_radius(stype[site] as i32, ssize[site])).max(0.0);
        out.push(Touch { sensor: i, site, geom: g, gap });
    }
    out
}

impl Rule for TouchSensorSite {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let tol = cx.opt("gap");
        let all = touches(robot);
        let Some(good) = all.iter().find(|t| t.gap <= tol) else { return };
        // Names from the source: sites map to their elements; a touch sensor is the <touch>
        // that names the site.
        let name_of = |kind: ElemKind, i: usize| {
            robot.elem(kind, i, "").and_then(|e| e.name.clone()).unwrap_or_else(|| format!("#{i}"))
        };
        let good_site = name_of(ElemKind::Site, good.site);
        for t in all.iter().filter(|t| t.gap > tol) {
            let site = name_of(ElemKind::Site, t.site);
            let elem =
                robot.src.list(ElemKind::Sensor).iter().find(|e| {
                    e.tag == "touch" && e.attrs.get("site").is_some_and(|o| o.value == site)
                });
            let sensor =
                elem.and_then(|e| e.name.clone()).unwrap_or_else(|| format!("#{}", t.sensor));
            let g = &robot.geoms[t.geom];
            let body = robot.body_name(g.body);
            let geom = if g.name.is_empty() {
                format!("geom {}, the far end of its body", robot.geom_ref(t.geom))
            } else {
                format!("geom `{}` at the far end of body `{body}`", g.name)
            };
            let msg = format!(
                "touch sensor `{sensor}`: its site `{site}` stays {} m from {geom}, so no contact of that geom falls inside it (site `{good_site}` of another touch sensor reaches its own)",
                fmt_num(t.gap, 3),
            );
            let sloc = robot.elem_loc(ElemKind::Site, t.site, &site);
            let gloc = robot.elem_loc(ElemKind::Geom, t.geom, &g.name);
            let start = match elem {
                Some(e) => cx.finding(msg, e.loc).element(format!("sensor {sensor}"), e.loc),
                None => cx.at_elem(ElemKind::Sensor, t.sensor, &sensor, msg),
            };
            out.push(
                start
                    .secondary(sloc, format!("site `{site}`: {} m short of the geom", fmt_num(t.gap, 3)))
                    .secondary(gloc, "the body's distal colliding geom".to_string())
                    .note("MuJoCo's touch sensor adds only the contacts whose point lies inside the site's volume: this sensor reads 0 whenever that geom alone is in contact")
                    .help("centre the site on the geom that touches (as the working sensor's site is), with a radius at least the geom's")
                    .measured(t.gap, "m")
                    .expected(0.0, "m")
                    .with("gap", t.gap),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_to_primitives() {
        let s = [0.1, 0.2, 0.3];
        assert_eq!(distance_to_primitive(GeomType::Sphere, s, [0.0, 0.0, 0.05]), Some(0.0));
        let d = distance_to_primitive(GeomType::Sphere, s, [0.0, 0.3, 0.0]).unwrap();
        assert!((d - 0.2).abs() < 1e-12);
        // capsule radius 0.1, half-length 0.2 along z: a point 0.5 above the centre is 0.2 off
        let d = distance_to_primitive(GeomType::Capsule, s, [0.0, 0.0, 0.5]).unwrap();
        assert!((d - 0.2).abs() < 1e-12);
        // cylinder radius 0.1, half-height 0.2: beside the rim corner
        let d = distance_to_primitive(GeomType::Cylinder, s, [0.4, 0.0, 0.6]).unwrap();
        assert!((d - 0.5).abs() < 1e-12);
        let d = distance_to_primitive(GeomType::Box, s, [0.0, 0.5, 0.0]).unwrap();
        assert!((d - 0.3).abs() < 1e-12);
        assert_eq!(distance_to_primitive(GeomType::Mesh, s, [0.0; 3]), None);
    }

    #[test]
    fn frames_turn_the_point_back() {
        // a quarter turn about z maps the local x axis to world y: world y is local x
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let p = into_frame([1.0, 0.0, 0.0], [h, 0.0, 0.0, h], [1.0, 2.0, 0.0]);
        assert!((p[0] - 2.0).abs() < 1e-12 && p[1].abs() < 1e-12 && p[2].abs() < 1e-12, "{p:?}");
    }
}
