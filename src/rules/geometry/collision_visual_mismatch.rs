use parry3d::math::{Pose, Vector};
use parry3d::query::PointQuery;
use parry3d::shape::ConvexPolyhedron;

use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::source::XNode;
use crate::model::{Geom, GeomType, Robot};
use crate::rules::contact::feet::{FootKind, feet};
use crate::rules::geometry::shapes::{Placed, V3, add, hull_area, norm, scale, sub, to_local_dir};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// For every body that has a visual mesh (a mesh geom with `contype = conaffinity = 0`),
    /// compares its collision geoms with the visual mesh at the keyframe: a collision geom whose
    /// surface sticks out of the visual mesh's bounding box (in the mesh's own principal frame)
    /// by more than `tolerance` is reported; when its centre also lies outside the mesh's convex
    /// hull (parry3d) by more than `tolerance`, it is reported as misplaced rather than oversized.
    /// Only geoms that stick out by `misplaced` (50 mm) or more are warnings: a primitive a
    /// centimetre or two outside a curved link (a hip cylinder 12–16 mm out) is a deliberate
    /// coarse approximation and is reported as info, while misplaced collision geometry on real
    /// models sticks out by 50 mm or more.
    /// For flat feet (not wheels, not point feet: a wheel rolls on a line and a foot sphere
    /// touches at a point by design) it also compares the support polygon of
    /// the collision geoms (the xy hull of their ground points) with the xy hull of the visual
    /// sole (visual vertices within 5 mm of its bottom); coverage below `min_sole_coverage` is
    /// reported. Bodies without a visual mesh are skipped, and a collision mesh that is the
    /// visual mesh itself, placed where the visual draws it, always matches; the same mesh file
    /// placed elsewhere (a URDF `<collision>` whose `<origin>` differs from its `<visual>`'s,
    /// such as a visual's `rpy` typed into the collision's `xyz`) is measured like any geom.
    /// MuJoCo's importer drops a URDF's `<visual>`s by default, so in a URDF the same test
    /// reads the file: a link's `<collision>` mesh that is the very file (and scale) its
    /// `<visual>` draws, with an `<origin>` `xyz` more than `tolerance` from the visual's, is
    /// that mesh moved by that distance (a warning from `misplaced`).
    ///
    /// ## Why is this bad?
    /// Collision geometry is what the simulator feels. A collision primitive that is larger than
    /// the part, or left at the wrong place after an edit, makes the simulated robot hit itself
    /// and the ground where the real one does not (and the other way round); a foot whose contact
    /// points cover a small part of the real sole has a smaller support polygon than the
    /// hardware, so balance learned in simulation does not transfer.
    ///
    /// ## How it is confirmed
    /// Static geometry at the keyframe.
    ///
    /// ## How to fix
    /// Resize or move the collision geom to fit inside the visual mesh (use the mesh in the
    /// viewer with collision geoms shown, group 3), and spread foot contact geoms over the whole
    /// sole: heel, midfoot and toe, inner and outer edge.
    pub CollisionVisualMismatch {
        id: "collision-visual-mismatch",
        group: "geometry",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("tolerance", 0.01, "m", Domain::NON_NEGATIVE, "how far a collision geom may extend outside the visual mesh's hull before it is reported (as info)"),
            opt("misplaced", 0.05, "m", Domain::POSITIVE, "from this far outside the visual mesh a collision geom is a warning (misplaced or grossly oversized)"),
            opt("min_sole_coverage", 0.6, "ratio", Domain::FRACTION, "smallest fraction of the visual sole's area the foot's support polygon must cover"),
        ],
    }
}

fn is_visual_mesh(g: &Geom) -> bool {
    g.gtype == GeomType::Mesh && g.mesh >= 0 && !g.collides()
}

/// 26 unit directions: cube faces, edges and corners.
fn directions() -> Vec<V3> {
    let mut v = Vec::new();
    for x in [-1.0, 0.0, 1.0] {
        for y in [-1.0, 0.0, 1.0] {
            for z in [-1.0, 0.0, 1.0] {
                let d: V3 = [x, y, z];
                let n = norm(d);
                if n > 0.0 {
                    v.push(scale(d, 1.0 / n));
                }
            }
        }
    }
    v
}

/// The visual mesh's bounding box in the frame of its (first) visual geom — MuJoCo aligns a
/// compiled mesh frame with the mesh's principal axes, so the box is tight — plus its convex hull
/// (parry3d) for misplacement checks.
struct Bounds {
    pos: V3,
    mat: [f64; 9],
    lo: V3,
    hi: V3,
    centre: V3,
    /// Points relative to `centre`; the hull is built only when a geom sticks out (it is the
    /// costly part on mesh-heavy models).
    pts: Vec<Vector>,
    poly: std::cell::OnceCell<Option<ConvexPolyhedron>>,
}

impl Bounds {
    fn new(pos: V3, mat: [f64; 9], verts: &[V3]) -> Option<Bounds> {
        if verts.len() < 4 {
            return None;
        }
        let local: Vec<V3> = verts.iter().map(|v| to_local_dir(&mat, sub(*v, pos))).collect();
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for v in &local {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        let centre =
            scale(verts.iter().fold([0.0; 3], |a, v| add(a, *v)), 1.0 / verts.len() as f64);
        let pts: Vec<Vector> = verts
            .iter()
            .map(|v| {
                Vector::new(
                    (v[0] - centre[0]) as f32,
                    (v[1] - centre[1]) as f32,
                    (v[2] - centre[2]) as f32,
                )
            })
            .collect();
        Some(Bounds { pos, mat, lo, hi, centre, pts, poly: std::cell::OnceCell::new() })
    }
    /// Distance of a world point outside the bounding box (0 inside).
    fn outside_box(&self, p: V3) -> f64 {
        let l = to_local_dir(&self.mat, sub(p, self.pos));
        let d: V3 = std::array::from_fn(|k| (self.lo[k] - l[k]).max(l[k] - self.hi[k]).max(0.0));
        norm(d)
    }
    /// Distance of a world point outside the convex hull (0 inside; box distance without a hull).
    fn outside_hull(&self, p: V3) -> f64 {
        match self.poly.get_or_init(|| ConvexPolyhedron::from_convex_hull(&self.pts)) {
            Some(poly) => {
                let q = sub(p, self.centre);
                poly.distance_to_point(
                    &Pose::IDENTITY,
                    Vector::new(q[0] as f32, q[1] as f32, q[2] as f32),
                    true,
                ) as f64
            }
            None => self.outside_box(p),
        }
    }
}

fn gname(robot: &Robot, g: usize) -> String {
    let n = &robot.geoms[g].name;
    // Unnamed: its number in its body (the message names the body), not the scene-dependent id.
    if n.is_empty() { format!("no. {}", robot.geom_no(g)) } else { format!("`{n}`") }
}

/// The `xyz` of an element's `<origin>` (zero when absent or unreadable).
fn origin_xyz(x: &XNode) -> V3 {
    let v: Vec<f64> = x
        .children_tagged("origin")
        .next()
        .and_then(|o| o.get("xyz"))
        .map(|t| t.split_whitespace().filter_map(|w| w.parse().ok()).collect())
        .unwrap_or_default();
    if v.len() == 3 { [v[0], v[1], v[2]] } else { [0.0; 3] }
}

/// The mesh file and scale of a `<visual>` or `<collision>`, as written.
fn urdf_mesh(x: &XNode) -> Option<(&str, &str)> {
    let m = x.children_tagged("geometry").flat_map(|g| g.children_tagged("mesh")).next()?;
    Some((m.get("filename")?, m.get("scale").unwrap_or("1 1 1")))
}

/// URDF `<collision>` meshes that are their link's `<visual>` mesh (same file and scale) with an
/// `<origin>` `xyz` more than `tol` from the visual's: the visual mesh moved.
fn urdf_same_mesh_moved(cx: &Context, tol: f64, misplaced: f64) -> Vec<Finding> {
    let mut out = Vec::new();
    for l in cx.robot.tree.children_tagged("link") {
        let drawn: Vec<(&XNode, (&str, &str))> =
            l.children_tagged("visual").filter_map(|v| Some((v, urdf_mesh(v)?))).collect();
        for c in l.children_tagged("collision") {
            let Some(mesh) = urdf_mesh(c) else { continue };
            let twins: Vec<&XNode> =
                drawn.iter().filter(|(_, m)| *m == mesh).map(|(v, _)| *v).collect();
            let at = origin_xyz(c);
            let Some(d) = twins.iter().map(|v| norm(sub(at, origin_xyz(v)))).reduce(f64::min)
            else {
                continue;
            };
            if d <= tol {
                continue;
            }
            let name = l.get("name").unwrap_or("");
            let mut f = cx
                .finding(
                    format!(
                        "link `{name}` collides through its visual mesh `{}` moved {} mm from where its <visual> draws it (<origin> xyz {} against the visual's)",
                        mesh.0,
                        fmt_num(d * 1000.0, 3),
                        c.children_tagged("origin").next().and_then(|o| o.get("xyz")).unwrap_or("0 0 0")
                    ),
                    c.loc,
                )
                .element(format!("link `{name}`"), c.loc)
                .label(format!("the visual mesh, {} mm away", fmt_num(d * 1000.0, 3)))
                .note("the same mesh file as the link's <visual> at another <origin>: the simulated link collides where no part of it is (an edit that typed the visual's rpy into the collision's xyz, a copied origin)")
                .help("give the <collision> the <origin> of its <visual> (or geometry fitted to the link)")
                .subject(Subject::Model)
                .measured(d, "m")
                .expected(tol, "m");
            if d < misplaced {
                f.severity = Severity::Info;
            }
            out.push(f);
        }
    }
    out
}

/// Whether two geoms sit at the same place and orientation at the keyframe, to the rounding of
/// compiled positions (a mesh drawn once and collided once at one spot).
fn same_place(robot: &Robot, a: usize, b: usize) -> bool {
    const ROUNDING: f64 = 1e-9;
    let (k, l) = (&robot.key, (a, b));
    (0..3).all(|i| (k.geom_xpos[l.0][i] - k.geom_xpos[l.1][i]).abs() <= ROUNDING)
        && (0..9).all(|i| (k.geom_xmat[l.0][i] - k.geom_xmat[l.1][i]).abs() <= ROUNDING)
}

impl Rule for CollisionVisualMismatch {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let tol = cx.opt("tolerance");
        let misplaced = cx.opt("misplaced");
        if robot.format == crate::model::Format::Urdf {
            out.extend(urdf_same_mesh_moved(cx, tol, misplaced));
        }
        let min_cov = cx.opt("min_sole_coverage");
        let dirs = directions();
        let foot_bodies: Vec<usize> = feet(robot, cx.spec)
            .iter()
            .filter(|f| f.kind == FootKind::Flat)
            .map(|f| f.root)
            .collect();
        for body in 1..robot.bodies.len() {
            let visuals: Vec<&Geom> =
                robot.geoms.iter().filter(|g| g.body == body && is_visual_mesh(g)).collect();
            if visuals.is_empty() {
                continue;
            }
            let verts: Vec<V3> =
                visuals.iter().flat_map(|g| Placed::of(robot, g.id).verts).collect();
            let v0 = visuals[0].id;
            let Some(hull) = Bounds::new(robot.key.geom_xpos[v0], robot.key.geom_xmat[v0], &verts)
            else {
                continue;
            };
            let bname = robot.body_name(body);
            let colliders: Vec<&Geom> = robot
                .geoms
                .iter()
                .filter(|g| {
                    g.body == body
                        && g.collides()
                        && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield)
                })
                .collect();
            for g in &colliders {
                if g.gtype == GeomType::Mesh
                    && visuals.iter().any(|v| v.mesh == g.mesh && same_place(robot, v.id, g.id))
                {
                    continue;
                }
                let p = Placed::of(robot, g.id);
                let (worst, wdir) = dirs
                    .iter()
                    .map(|d| (hull.outside_box(p.support(*d)), *d))
                    .fold((0.0, [0.0; 3]), |a, b| if b.0 > a.0 { b } else { a });
                if worst <= tol {
                    continue;
                }
                let centre_out = hull.outside_hull(p.pos);
                let dir_word = {
                    let axis = ["x", "y", "z"];
                    let mut parts = Vec::new();
                    for k in 0..3 {
                        if wdir[k].abs() > 0.1 {
                            parts.push(format!(
                                "{}{}",
                                if wdir[k] > 0.0 { "+" } else { "−" },
                                axis[k]
                            ));
                        }
                    }
                    parts.join("")
                };
                let (msg, label, note) = if centre_out > tol {
                    (
                        format!(
                            "collision geom {} of body `{bname}` is centred {} mm outside the body's visual mesh",
                            gname(robot, g.id),
                            fmt_num(centre_out * 1000.0, 3)
                        ),
                        format!(
                            "centre {} mm outside the visual mesh",
                            fmt_num(centre_out * 1000.0, 3)
                        ),
                        "a collision geom whose centre lies outside the part it stands for is misplaced (a wrong `pos`, or a geom left on the wrong body): the simulated robot collides where the real one has no material",
                    )
                } else {
                    (
                        format!(
                            "collision geom {} of body `{bname}` sticks out of the body's visual mesh by {} mm (towards world {dir_word})",
                            gname(robot, g.id),
                            fmt_num(worst * 1000.0, 3)
                        ),
                        format!("{} mm outside the visual mesh", fmt_num(worst * 1000.0, 3)),
                        "a collision geom larger than the part makes the simulated robot touch itself and the ground where the real one does not",
                    )
                };
                let mut f = cx.at_attr(ElemKind::Geom, g.id, &g.name, "size", msg);
                let coarse = worst.max(centre_out) < misplaced;
                if coarse && cx.level == cx.meta.default_level {
                    f.severity = Severity::Info;
                }
                let note = if coarse {
                    format!(
                        "{note}; within {} mm of the part this is often a deliberate coarse approximation — check that it is intended (misplaced geometry on real models sticks out by {} mm or more)",
                        fmt_num(misplaced * 1000.0, 3),
                        fmt_num(misplaced * 1000.0, 3)
                    )
                } else {
                    note.to_string()
                };
                out.push(
                    f
                        .label(label)
                        .note(note)
                        .help(format!("resize or move the geom to fit inside the visual mesh (tolerance {} mm)", fmt_num(tol * 1000.0, 3)))
                        .subject(Subject::Geom(g.id))
                        .measured(worst, "m")
                        .expected(tol, "m")
                        .with("outside_m", worst)
                        .with("centre_outside_m", centre_out),
                );
            }
            // Sole coverage of feet.
            if foot_bodies.contains(&body) && !colliders.is_empty() {
                let zmin = verts.iter().map(|v| v[2]).fold(f64::INFINITY, f64::min);
                let sole: Vec<[f64; 2]> =
                    verts.iter().filter(|v| v[2] <= zmin + 0.005).map(|v| [v[0], v[1]]).collect();
                let sole_area = hull_area(&sole);
                let placed: Vec<Placed> =
                    colliders.iter().map(|g| Placed::of(robot, g.id)).collect();
                let cmin = placed.iter().map(|p| p.lowest()[2]).fold(f64::INFINITY, f64::min);
                let pts: Vec<[f64; 2]> = placed
                    .iter()
                    .filter(|p| p.lowest()[2] <= cmin + 0.005)
                    .flat_map(|p| {
                        let mut v = p.ground_points(cmin + 0.005 - p.lowest()[2]);
                        v.push(p.lowest());
                        v
                    })
                    .map(|v| [v[0], v[1]])
                    .collect();
                let area = hull_area(&pts);
                if sole_area > 1e-5 {
                    let cov = area / sole_area;
                    if cov < min_cov {
                        let g0 = colliders[0];
                        out.push(
                            cx.at_elem(ElemKind::Geom, g0.id, &g0.name, format!(
                                "foot `{bname}` support polygon covers {}% of the visual sole ({} of {} cm²)",
                                fmt_num(cov * 100.0, 3), fmt_num(area * 1e4, 3), fmt_num(sole_area * 1e4, 3)))
                                .label("foot collision geoms")
                                .note("the simulated foot balances on a smaller support polygon than the real sole, so the centre-of-pressure limits and tipping behaviour learned in simulation do not match the hardware")
                                .help("spread the foot's contact geoms over the sole: heel, midfoot and toe, at the inner and outer edges")
                                .subject(Subject::Foot(body))
                                .measured(cov, "ratio")
                                .expected(min_cov, "ratio")
                                .with("sole_coverage", cov),
                        );
                    }
                }
            }
        }
    }
}
