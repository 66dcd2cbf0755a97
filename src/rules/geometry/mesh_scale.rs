use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::GeomType;
use crate::model::mjcf::ElemKind;
use crate::model::source::{Loc, XNode};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

/// Metres per millimetre: the scale a mesh exported from CAD in millimetres needs.
const MM: f64 = 1e-3;

declare_rule! {
    /// ## What it does
    /// Finds a mesh geom far larger than the body that carries it: its bounding radius
    /// (`geom_rbound`, the mesh's farthest vertex from its centre after the mesh's `scale`) is
    /// more than `max_extent_ratio` times the body's largest radius of gyration √(I_max/m),
    /// with m and I the body's compiled mass and principal moments. A solid part's bounding
    /// radius is a few radii of gyration (a uniform rod of length L: L/2 against L/√12, 1.7×;
    /// a sphere 1.6×); a mesh exported in millimetres and read as metres is 1000× its part.
    /// When the mesh at scale 0.001 would fit the body (within the same ratio), the finding
    /// names millimetres as the likely cause. A URDF's fixed root link, which MuJoCo's
    /// importer fuses into the world body (dropping its `<inertial>`), is judged by the mass
    /// and inertia written in the `<link>` that uses the mesh file (largest moment bounded
    /// above by Gershgorin's row sums).
    /// Bodies without mass or inertia, and an MJCF's world-body meshes (scenery), are not
    /// judged.
    ///
    /// ## Why is this bad?
    /// MuJoCo reads mesh vertices in metres (STL has no unit; CAD exporters often write
    /// millimetres). A collision mesh 1000× too large puts a hull hundreds of metres across on
    /// the robot: it meets the floor and every other body at once, and the contact solver
    /// pushes the robot away or the model cannot stand at all; a drawn mesh hides the robot.
    /// The mass and inertia written in the file stay plausible, so nothing else flags it.
    /// MuJoCo XML reference, `asset/mesh` (`scale`) and URDF `<mesh scale>`.
    ///
    /// ## How it is confirmed
    /// Static: compiled `geom_rbound`, `body_mass` and `body_inertia` (a fused URDF root
    /// link's `<inertial>` as written). The comparison is of
    /// the file's own numbers, not a prediction a simulation could refute.
    ///
    /// ## How to fix
    /// Convert the mesh to metres, or scale it where it is used: `<mesh file=... scale="0.001
    /// 0.001 0.001"/>` in MJCF, `<mesh filename=... scale="0.001 0.001 0.001"/>` in URDF.
    pub MeshScale {
        id: "mesh-scale",
        group: "geometry",
        level: Severity::Error,
        probe: None,
        options: [opt("max_extent_ratio", 100.0, "ratio", Domain::POSITIVE, "largest accepted mesh bounding radius over the body's largest radius of gyration (a solid part: 1.5-3; a millimetre mesh read as metres: about 1000)")],
    }
}

/// The file name (no directory) MuJoCo resolved for mesh `id`, if it kept one.
fn mesh_file(m: &mujoco_rs::prelude::MjModel, id: usize) -> Option<String> {
    let paths = m.paths();
    let start = usize::try_from(*m.mesh_pathadr().get(id)?).ok()?;
    let rest = paths.get(start..)?;
    let end = rest.iter().position(|&b| b == 0).unwrap_or(rest.len());
    let bytes: Vec<u8> = rest[..end].iter().map(|&b| b as u8).collect();
    let s = String::from_utf8_lossy(&bytes).into_owned();
    let name = s.rsplit(['/', '\\']).next().unwrap_or(&s).to_string();
    (!name.is_empty()).then_some(name)
}

/// The URDF `<link>` whose `<collision>` (else `<visual>`) uses mesh file `file`: its name,
/// mass (kg), an upper bound on its largest principal moment (kg·m²) and the mesh's `filename`
/// attribute. MuJoCo's URDF importer fuses a fixed root link into the world body and drops its
/// `<inertial>`, so the file's own numbers are the only ones left. The bound is Gershgorin's
/// (a diagonal term plus its row's off-diagonal magnitudes), never below the true moment, so
/// the radius of gyration from it errs on the large side.
fn urdf_link_of_mesh(cx: &Context, file: &str) -> Option<(String, f64, f64, Loc)> {
    let uses = |l: &XNode, tag: &str| {
        l.children_tagged(tag)
            .flat_map(|c| c.children_tagged("geometry"))
            .flat_map(|g| g.children_tagged("mesh"))
            .filter_map(|m| m.attr("filename"))
            .find(|a| a.value.rsplit(['/', '\\']).next() == Some(file))
            .map(|a| a.loc)
    };
    let links = || cx.robot.tree.children_tagged("link");
    let (link, loc) = links()
        .find_map(|l| uses(l, "collision").map(|x| (l, x)))
        .or_else(|| links().find_map(|l| uses(l, "visual").map(|x| (l, x))))?;
    let inertial = link.children_tagged("inertial").next()?;
    let num = |n: &XNode, k: &str| -> f64 {
        n.get(k).and_then(|v| v.trim().parse::<f64>().ok()).unwrap_or(0.0)
    };
    let mass = num(inertial.children_tagged("mass").next()?, "value");
    let i = inertial.children_tagged("inertia").next()?;
    let (xx, yy, zz) = (num(i, "ixx"), num(i, "iyy"), num(i, "izz"));
    let (xy, xz, yz) = (num(i, "ixy").abs(), num(i, "ixz").abs(), num(i, "iyz").abs());
    let top = (xx + xy + xz).max(yy + xy + yz).max(zz + xz + yz);
    Some((link.get("name").unwrap_or("").to_string(), mass, top, loc))
}

impl Rule for MeshScale {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let ratio = cx.opt("max_extent_ratio");
        let inertia = robot.mj.body_inertia();
        let urdf = robot.format == crate::model::Format::Urdf;
        for g in robot.geoms.iter().filter(|g| g.gtype == GeomType::Mesh) {
            // (body name, mass, largest moment): compiled, or for a URDF's fixed root link
            // fused into the world, as its <link> writes them.
            let file = usize::try_from(g.mesh).ok().and_then(|m| mesh_file(&robot.mj, m));
            let (bname, mass, top, at) = if g.body != 0 {
                let Some(b) = robot.bodies.get(g.body) else { continue };
                let Some(i) = inertia.get(b.id) else { continue };
                (robot.body_name(b.id).to_string(), b.mass, i[0].max(i[1]).max(i[2]), None)
            } else if urdf {
                let Some(x) = file.as_deref().and_then(|f| urdf_link_of_mesh(cx, f)) else {
                    continue;
                };
                (x.0, x.1, x.2, Some(x.3))
            } else {
                continue;
            };
            if !(mass > 0.0 && top > 0.0) {
                continue;
            }
            let gyr = (top / mass).sqrt();
            let r = g.rbound;
            if !(r > ratio * gyr) || !r.is_finite() {
                continue;
            }
            let mesh = usize::try_from(g.mesh)
                .ok()
                .and_then(|m| robot.meshes.get(m))
                .filter(|n| !n.is_empty());
            let what = match (mesh, &file) {
                (Some(n), Some(f)) => format!("mesh `{n}` ({f})"),
                (Some(n), None) => format!("mesh `{n}`"),
                (None, Some(f)) => format!("mesh {f}"),
                (None, None) => "its mesh".into(),
            };
            let msg = format!(
                "{what} on body `{bname}` is {} m across, {}× the body's radius of gyration {} m (mass {} kg, largest moment {} kg·m²), above {}×",
                fmt_num(2.0 * r, 4),
                fmt_num(r / gyr, 4),
                fmt_num(gyr, 3),
                fmt_num(mass, 4),
                fmt_num(top, 4),
                fmt_num(ratio, 3)
            );
            let mm = r * MM <= ratio * gyr;
            let cause = if mm {
                format!(
                    "likely millimetres read as metres: at scale 0.001 the mesh is {} m across, {}× the radius of gyration",
                    fmt_num(2.0 * r * MM, 3),
                    fmt_num(r * MM / gyr, 3)
                )
            } else {
                "a unit or scale slip in the mesh, or a placeholder mass/inertia on the body".into()
            };
            let f = match at {
                Some(loc) => cx.finding(msg, loc).element(format!("body {bname}"), loc),
                None => cx.at_elem(ElemKind::Geom, g.id, &g.name, msg),
            };
            let f = f
                .label(if mm { "mesh likely in millimetres" } else { "mesh far larger than its body" })
                .note(format!(
                    "MuJoCo reads mesh vertices in metres; {cause}. A hull this size meets the floor and every other body at once"
                ))
                .help(if mm {
                    "convert the mesh to metres, or set scale=\"0.001 0.001 0.001\" on the <mesh> (MJCF asset or URDF geometry)"
                } else {
                    "check the mesh's unit and scale, and the body's mass and inertia"
                })
                .subject(Subject::Body(g.body))
                .measured(2.0 * r, "m")
                .expected(2.0 * ratio * gyr, "m");
            out.push(f);
        }
    }
}
