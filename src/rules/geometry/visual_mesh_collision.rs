use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::source::XNode;
use crate::model::{Format, Geom, GeomType};
use crate::rules::{Context, Rule, RuleMeta};

declare_rule! {
    /// ## What it does
    /// Finds robot meshes that are drawn and collide: a mesh geom of a robot body (not the
    /// world body) with `contype` or `conaffinity` non-zero, not fully transparent (alpha 0:
    /// not drawn), in a geom group the viewer shows by
    /// default (0–2). It is reported when the compiled model shows that the mesh is a visual one
    /// left colliding:
    ///
    /// - **beside collision geoms**: other robot geoms collide in a hidden group (3 or higher),
    ///   the model's own collision set, and this mesh is not in it; or
    /// - **in a visual group**: its group holds robot geoms with `contype = conaffinity = 0`,
    ///   the model's visual-only geoms, and its body has no such geom of its own (so the mesh is
    ///   what draws the body); or
    /// - **the visual mesh again**: its body draws the same mesh asset through a visual-only
    ///   geom (`contype = conaffinity = 0`) beside it, so the collision geom is that visual
    ///   mesh drawn a second time, colliding; or
    /// - **no collision set at all**: the model has neither visual-only geoms nor a hidden
    ///   collision group, and the body collides through this mesh alone (no primitive collides
    ///   on the body or on a body welded to it with no joint between: one rigid part).
    ///
    /// A robot with no collision geometry at all — every geom of its bodies has `contype =
    /// conaffinity = 0`, none is named by an explicit `<contact><pair>`, and the model keeps
    /// contacts on (no `<flag contact="disable"/>`) — is reported once instead: it collides
    /// through nothing.
    ///
    /// Everything is read from the compiled model (geom type, group, contype/conaffinity); class
    /// names are not evidence. A URDF declares its collision geometry — MuJoCo's importer
    /// compiles each `<collision>` as a colliding geom and each kept `<visual>` with `contype =
    /// conaffinity = 0` — so the cases above do not apply to it; it is read from its own
    /// `<link>`s instead, and reported when none of its links has a `<collision>` while
    /// they have `<visual>`s, the robot has a moving joint and contacts are on (the importer
    /// discards visuals — `discardvisual`, true by default for URDF — or keeps them with
    /// `contype = conaffinity = 0`, so nothing of the robot collides), and when a link's
    /// `<collision>` mesh is the very file (and scale) its `<visual>` draws: the visual mesh
    /// declared again as collision geometry. Not reported: collision primitives beside visual meshes with
    /// `contype = conaffinity = 0`; collision meshes (a convex decomposition) kept in their own
    /// group beside separate visual geoms; a body whose drawn meshes collide beside colliding
    /// primitives of the same group when the model has no visual/collision split (nothing shows
    /// which of them is cosmetic).
    ///
    /// ## Why is this bad?
    /// MuJoCo collides a mesh as its convex hull. A visual mesh is a shell of the part's outer
    /// surface, cable guides and covers included; its hull fills every concavity, so links that
    /// clear each other on the real robot touch in simulation (self-collision through cosmetic
    /// shells, most at bent joints), and a hull the size of a housing meets the floor where the
    /// real part does not. Mesh–mesh and mesh–primitive pairs go through the general convex
    /// collider (GJK/EPA or MPR on every hull vertex's support) rather than a closed-form
    /// primitive test: slower per step, and one contact point per pair unless `multiccd` is on,
    /// so a flat face resting on another rocks and the contact set chatters. A policy trained on
    /// that learns to avoid or exploit contacts the hardware never makes. MuJoCo documentation,
    /// Modeling › Collision detection (convex hulls of meshes; `contype`/`conaffinity`
    /// filtering; `<option><flag multiccd>`).
    ///
    /// ## How it is confirmed
    /// Static: compiled geom types, groups and contact masks. The finding counts the geom pairs
    /// with one of these meshes that MuJoCo's collision filters leave in (`model::contact`: not
    /// one weld body, not a weld body and its parent's unless `filterparent` is disabled, no
    /// `<exclude>`, masks that match; none with `<flag contact="disable"/>`); no simulation is
    /// needed to show that the pairs exist.
    ///
    /// ## How to fix
    /// Give the visual geoms `contype="0" conaffinity="0"` (usually in their `<default class>`)
    /// and a visual group (2), and add collision geoms in their own group (3): primitives
    /// (capsules, boxes, spheres) fitted to each link, or a convex decomposition of the mesh
    /// when the shape matters.
    pub VisualMeshCollision {
        id: "visual-mesh-collision",
        group: "geometry",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

fn is_robot_collider(g: &Geom) -> bool {
    g.body != 0 && g.collides() && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield)
}

/// Why a drawn, colliding mesh counts as a visual one.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Case {
    /// Other robot geoms collide in a hidden group (the collision set).
    BesideCollisionGroup(i32),
    /// Its own group holds visual-only robot geoms.
    InVisualGroup,
    /// No visual/collision split at all; the body collides only through its drawn meshes.
    NoCollisionSet,
    /// The body's visual-only geom draws the same mesh: the collision geom is its twin.
    VisualTwin,
}

impl Rule for VisualMeshCollision {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        if robot.format == Format::Urdf {
            // Every colliding geom is a declared <collision> (see the rule's docs); only a URDF
            // that declares none is judged.
            out.extend(urdf_without_collision(cx));
            out.extend(urdf_visual_twins(cx));
            return;
        }
        let robot_geoms = || robot.geoms.iter().filter(|g| g.body != 0);
        if let Some(f) = no_collision_geometry(cx) {
            out.push(f);
            return;
        }
        let visual_only: Vec<&Geom> = robot_geoms()
            .filter(|g| !g.collides() && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield))
            .collect();
        // The lowest hidden group that holds colliding robot geoms: the collision set.
        let hidden_collision =
            robot_geoms().filter(|g| is_robot_collider(g) && g.group >= 3).map(|g| g.group).min();
        let body_has_visual =
            |b: usize| robot_geoms().any(|g| g.body == b && !g.collides() && g.group <= 2);
        // Primitive collision geoms on the same rigid part: the body or a body welded to it
        // (MuJoCo's weld body; e.g. a chassis box on a child body with no joint).
        let weld = |b: usize| robot.bodies.get(b).map_or(b, |x| x.weld);
        let body_has_prim = |b: usize, group: i32| {
            robot_geoms().any(|g| {
                weld(g.body) == weld(b)
                    && is_robot_collider(g)
                    && g.gtype != GeomType::Mesh
                    && g.group == group
            })
        };
        // A geom whose colour is fully transparent is not drawn, whatever its group: a mesh
        // made invisible (alpha 0) on purpose is a collision geom (MuJoCo draws a geom with its
        // own rgba when that differs from the default, else with its material's).
        let (rgba, matid, mat_rgba) =
            (robot.mj.geom_rgba(), robot.mj.geom_matid(), robot.mj.mat_rgba());
        let drawn = |g: &Geom| {
            let own = rgba.get(g.id).copied().unwrap_or([0.5, 0.5, 0.5, 1.0]);
            let alpha = match matid.get(g.id).and_then(|&m| usize::try_from(m).ok()) {
                Some(m) if own == [0.5, 0.5, 0.5, 1.0] => mat_rgba.get(m).map_or(1.0, |c| c[3]),
                _ => own[3],
            };
            alpha > 0.0
        };
        let mut hits: Vec<(Case, &Geom)> = Vec::new();
        for g in robot_geoms() {
            if g.gtype != GeomType::Mesh
                || !is_robot_collider(g)
                || !(0..=2).contains(&g.group)
                || !drawn(g)
            {
                continue;
            }
            let case = if let Some(h) = hidden_collision {
                Case::BesideCollisionGroup(h)
            } else if body_has_visual(g.body) {
                // A drawn collision mesh beside the body's own visual is evidence only when
                // the visual draws the very same mesh.
                let twin = robot_geoms().any(|v| {
                    v.body == g.body
                        && !v.collides()
                        && v.gtype == GeomType::Mesh
                        && v.mesh == g.mesh
                });
                if !twin {
                    continue;
                }
                Case::VisualTwin
            } else if visual_only.iter().any(|v| v.group == g.group) {
                Case::InVisualGroup
            } else if visual_only.is_empty() && !body_has_prim(g.body, g.group) {
                Case::NoCollisionSet
            } else {
                continue;
            };
            hits.push((case, g));
        }
        if hits.is_empty() {
            return;
        }
        let case = hits.iter().map(|h| h.0).min().unwrap_or(Case::NoCollisionSet);
        let meshes: Vec<&Geom> = hits.iter().filter(|h| h.0 == case).map(|h| h.1).collect();
        // Pairs MuJoCo would test with one of these meshes: robot colliders that no filter
        // separates (weld body, parent, <exclude>, masks: `model::contact::filtered`).
        let colliders: Vec<&Geom> = robot_geoms().filter(|g| is_robot_collider(g)).collect();
        let mut pairs = 0usize;
        for (i, a) in colliders.iter().enumerate() {
            for b in &colliders[i + 1..] {
                let hit = |g: &Geom| meshes.iter().any(|m| m.id == g.id);
                if (hit(a) || hit(b))
                    && crate::model::contact::filtered(robot, a.id, b.id).is_none()
                {
                    pairs += 1;
                }
            }
        }
        let verts: i64 = {
            let vn = robot.mj.mesh_vertnum();
            meshes
                .iter()
                .filter_map(|g| usize::try_from(g.mesh).ok().and_then(|m| vn.get(m)))
                .map(|&n| n as i64)
                .sum()
        };
        let mut bodies: Vec<usize> = meshes.iter().map(|g| g.body).collect();
        bodies.dedup();
        let names: Vec<String> = bodies.iter().map(|&b| robot.body_name(b).to_string()).collect();
        let shown = if names.len() > 6 {
            format!("{}, … ({} bodies)", names[..6].join(", "), names.len())
        } else {
            names.join(", ")
        };
        let n = meshes.len();
        let (what, label) = match case {
            Case::BesideCollisionGroup(h) => (
                format!(
                    "{n} drawn mesh geom{} collide beside the collision geoms of group {h}: {shown}",
                    if n == 1 { "" } else { "s" }
                ),
                format!("drawn mesh (group {}) with contact masks set", meshes[0].group),
            ),
            Case::InVisualGroup => (
                format!(
                    "{n} mesh geom{} in the visual group {} collide{} while the group's other geoms have contype = conaffinity = 0: {shown}",
                    if n == 1 { "" } else { "s" },
                    meshes[0].group,
                    if n == 1 { "s" } else { "" }
                ),
                "visual mesh with contact masks set".to_string(),
            ),
            Case::VisualTwin => (
                format!(
                    "{n} drawn mesh geom{} collide{} through the very mesh {} body draws with a visual-only geom beside it (the visual mesh twice, once colliding): {shown}",
                    if n == 1 { "" } else { "s" },
                    if n == 1 { "s" } else { "" },
                    if n == 1 { "its" } else { "each one's" }
                ),
                "the body's visual mesh again, with contact masks set".to_string(),
            ),
            Case::NoCollisionSet => (
                format!(
                    "the robot collides only through its visual meshes ({n} drawn mesh geom{}, no collision geoms of their own): {shown}",
                    if n == 1 { "" } else { "s" }
                ),
                "drawn mesh, the body's only collision geometry".to_string(),
            ),
        };
        let g0 = meshes[0];
        let mut f = cx.at_elem(ElemKind::Geom, g0.id, &g0.name, what).label(label);
        for g in meshes.iter().skip(1).take(3) {
            f = f.secondary(
                robot.elem_loc(ElemKind::Geom, g.id, &g.name),
                "also drawn and colliding",
            );
        }
        let f = f
            .note(format!(
                "MuJoCo collides a mesh as its convex hull, with the general convex collider (one contact per pair without multiccd): cosmetic shells fill in, {pairs} geom pair{} with one of these meshes can touch, and the hulls of {verts} mesh vertices enter every such test — slower steps, chattering contacts and self-collisions the hardware does not have",
                if pairs == 1 { "" } else { "s" }
            ))
            .help("set contype=\"0\" conaffinity=\"0\" group=\"2\" on the visual geoms (in their default class) and add collision geoms in group 3: primitives fitted to each link, or a convex decomposition where the shape matters")
            .subject(Subject::Model)
            .measured(n as f64, "geoms")
            .expected(0.0, "geoms")
            .with("mesh_pairs", pairs as f64)
            .with("hull_vertices", verts as f64);
        out.push(f);
    }
}

/// A URDF whose links declare `<visual>` geometry and no `<collision>` at all: MuJoCo's importer
/// drops the visuals (or keeps them non-colliding), so no geom of the robot collides.
fn urdf_without_collision(cx: &Context) -> Option<Finding> {
    let robot = cx.robot;
    let links: Vec<&XNode> = robot.tree.children_tagged("link").collect();
    if links.iter().any(|l| l.children_tagged("collision").next().is_some()) {
        return None;
    }
    let drawn: Vec<&XNode> =
        links.iter().copied().filter(|l| l.children_tagged("visual").next().is_some()).collect();
    let visuals: usize = drawn.iter().map(|l| l.children_tagged("visual").count()).sum();
    let moves =
        robot.joints.iter().any(|j| j.is_scalar() || j.jtype == crate::model::JointType::Free);
    let in_pair = |g: &Geom| robot.pairs.iter().any(|p| p.geom1 == g.id || p.geom2 == g.id);
    let first = drawn.first()?;
    if !moves
        || robot.geoms.iter().any(|g| g.body != 0 && (g.collides() || in_pair(g)))
        || crate::model::contact::contacts_disabled(robot)
    {
        return None;
    }
    let name = first.get("name").unwrap_or("");
    Some(
        cx.finding(
            format!(
                "no link of the URDF has a <collision>: {} of its {} links draw {visuals} <visual>{}, which MuJoCo's importer does not collide, so no geom of the robot collides",
                drawn.len(),
                links.len(),
                if visuals == 1 { "" } else { "s" }
            ),
            first.loc,
        )
        .element(format!("link `{name}`"), first.loc)
        .label("a <visual> only, like every other link")
        .note("with contacts on and no collision geometry the simulated robot passes through itself, the floor and every object it should touch or avoid: self-collisions, grasps and impacts the hardware has never happen in training")
        .help("add a <collision> to each link (primitives fitted to the link, or a convex mesh where the shape matters)")
        .subject(Subject::Model)
        .measured(0.0, "geoms")
        .with("visual_geoms", visuals as f64),
    )
}

/// The `<mesh>` of a `<visual>` or `<collision>`: its file name and scale (as written).
fn mesh_of(x: &XNode) -> Option<(&crate::model::source::XAttr, &str)> {
    let m = x.children_tagged("geometry").flat_map(|g| g.children_tagged("mesh")).next()?;
    Some((m.attr("filename")?, m.get("scale").unwrap_or("1 1 1")))
}

/// URDF links whose `<collision>` is a mesh file their own `<visual>` draws (same file, same
/// scale): the visual mesh declared again as collision geometry.
fn urdf_visual_twins(cx: &Context) -> Option<Finding> {
    let robot = cx.robot;
    let mut twins: Vec<(&str, &crate::model::source::XAttr)> = Vec::new();
    for l in robot.tree.children_tagged("link") {
        let drawn: Vec<(String, &str)> = l
            .children_tagged("visual")
            .filter_map(mesh_of)
            .map(|(f, sc)| (f.value.clone(), sc))
            .collect();
        let twin = l
            .children_tagged("collision")
            .filter_map(mesh_of)
            .find(|(f, sc)| drawn.iter().any(|(v, vs)| *v == f.value && vs == sc));
        if let Some((f, _)) = twin {
            twins.push((l.get("name").unwrap_or(""), f));
        }
    }
    let (first, attr) = *twins.first()?;
    let n = twins.len();
    let names: Vec<&str> = twins.iter().map(|t| t.0).collect();
    let shown = if n > 6 {
        format!("{}, … ({n} links)", names[..6].join(", "))
    } else {
        names.join(", ")
    };
    let mut f = cx
        .finding(
            format!(
                "{n} link{} collide{} through the very mesh file {} <visual> draws (the visual mesh declared again as <collision>): {shown}",
                if n == 1 { "" } else { "s" },
                if n == 1 { "s" } else { "" },
                if n == 1 { "its" } else { "each one's" }
            ),
            attr.loc,
        )
        .element(format!("link `{first}`"), attr.loc)
        .label("the link's visual mesh again, as its collision geometry");
    for (_, a) in twins.iter().skip(1).take(3) {
        f = f.secondary(a.loc, "also the link's visual mesh");
    }
    Some(
        f.note("MuJoCo collides a mesh as its convex hull, with the general convex collider (one contact per pair without multiccd): a visual shell's hull fills every concavity, so links touch where the hardware's clear each other, feet meet the floor at the hull's corners, and contacts chatter")
            .help("give each link a <collision> of its own: primitives fitted to the link, or a convex decomposition where the shape matters; keep the detailed mesh in <visual>")
            .subject(Subject::Model)
            .measured(n as f64, "links")
            .expected(0.0, "links"),
    )
}

/// A robot none of whose geoms can collide (every one has `contype = conaffinity = 0`) while the
/// model keeps contacts on: it passes through itself, the floor and every object.
fn no_collision_geometry(cx: &Context) -> Option<Finding> {
    let robot = cx.robot;
    let geoms: Vec<&Geom> = robot
        .geoms
        .iter()
        .filter(|g| g.body != 0 && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield))
        .collect();
    let moves =
        robot.joints.iter().any(|j| j.is_scalar() || j.jtype == crate::model::JointType::Free);
    // An explicit `<contact><pair>` collides its geoms whatever their masks.
    let in_pair = |g: &Geom| robot.pairs.iter().any(|p| p.geom1 == g.id || p.geom2 == g.id);
    if geoms.is_empty()
        || !moves
        || geoms.iter().any(|g| g.collides() || in_pair(g))
        || crate::model::contact::contacts_disabled(robot)
    {
        return None;
    }
    let g0 = geoms[0];
    let mut bodies: Vec<usize> = geoms.iter().map(|g| g.body).collect();
    bodies.sort_unstable();
    bodies.dedup();
    Some(
        cx.at_elem(
            ElemKind::Geom,
            g0.id,
            &g0.name,
            format!(
                "no geom of the robot collides: all {} geoms of its {} bodies have contype = conaffinity = 0",
                geoms.len(),
                bodies.len()
            ),
        )
        .label("visual only, like every other robot geom")
        .note("with contacts on and no collision geometry the simulated robot passes through itself, the floor and every object it should touch or avoid: self-collisions, grasps and impacts the hardware has never happen in training")
        .help("add collision geoms in group 3 (primitives fitted to each link, or a convex decomposition where the shape matters); if the model is meant to make no contact, say so with <option><flag contact=\"disable\"/></option>")
        .subject(Subject::Model)
        .measured(0.0, "geoms")
        .with("visual_geoms", geoms.len() as f64),
    )
}
