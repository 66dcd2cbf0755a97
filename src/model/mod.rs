//! Loading robot models: MuJoCo's compiled model is the semantic truth (defaults, includes,
//! units are resolved by MuJoCo itself); the XML source index supplies spans for diagnostics.

pub mod cache;
mod checks;
pub mod contact;
mod errloc;
mod extract;
pub mod floated;
mod limbs;
pub mod mirror;
pub mod mj;
pub mod mjcf;
pub mod plugins;
pub mod region;
pub mod source;
pub mod urdf_inertia;
pub mod urdf_packages;
pub mod urdf_transmissions;
pub mod xml_prefix;

use std::path::{Path, PathBuf};

use mujoco_rs::prelude::*;

use crate::error::LoadError;
pub(crate) use checks::c_number;
use checks::{check_assets, check_numbers};
use errloc::{
    attribute_error_location, missing_file_location, mujoco_element_location, mujoco_error_location,
};
use extract::extract;
pub use extract::{key_state, pose_state};
use mjcf::{ElemKind, ElemSrc, SourceIndex};
use source::{Loc, SourceMap, XNode};

#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    Mjcf,
    Urdf,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum JointType {
    Free,
    Ball,
    Slide,
    Hinge,
}

#[derive(Debug, Clone)]
pub struct Joint {
    pub id: usize,
    pub name: String,
    pub jtype: JointType,
    pub body: usize,
    pub qposadr: usize,
    pub dofadr: usize,
    pub limited: bool,
    pub range: [f64; 2],
    /// Effective armature at the joint (kg·m², or kg for a slide): the joint's own `armature`
    /// plus every actuator's `armature`·gear² and every fixed tendon's armature·coef² (MuJoCo
    /// ≥ 3.17 adds those to the mass matrix but leaves `dof_armature` at the joint's own value).
    pub armature: f64,
    /// Effective linear damping at the joint: own `damping` + actuator `damping`·gear² + tendon
    /// damping·coef² + a `<dcmotor>`'s back-EMF damping K²/R·gear².
    pub damping: f64,
    /// Where `armature` came from (the joint's own value first, when non-zero).
    pub armature_parts: Vec<Part>,
    /// Where `damping` came from.
    pub damping_parts: Vec<Part>,
    pub stiffness: f64,
    pub frictionloss: f64,
    pub springref: f64,
    pub axis: [f64; 3],
}

/// Where one contribution to a joint's effective armature or damping is written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PartSource {
    /// The joint's own `armature` / `damping`.
    Joint,
    /// An actuator's `armature` / `damping` × gear² (actuator id, gear).
    Actuator(usize, f64),
    /// A fixed tendon's `armature` / `damping` × coef² (tendon id, coef).
    Tendon(usize, f64),
    /// An actuator on a fixed tendon: value × gear² × coef² (actuator id, tendon id, gear, coef).
    TendonActuator(usize, usize, f64, f64),
    /// A `<dcmotor>`'s back-EMF: K²/R × gear² (actuator id, gear).
    BackEmf(usize, f64),
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Part {
    pub source: PartSource,
    /// Contribution at the joint.
    pub value: f64,
}

impl Joint {
    /// The joint's own `armature` attribute (compiled `dof_armature`).
    pub fn own_armature(&self) -> f64 {
        self.armature_parts.iter().filter(|p| p.source == PartSource::Joint).map(|p| p.value).sum()
    }
    /// The joint's own `damping` attribute (compiled `dof_damping`).
    pub fn own_damping(&self) -> f64 {
        self.damping_parts.iter().filter(|p| p.source == PartSource::Joint).map(|p| p.value).sum()
    }
    /// Whether any part of the effective armature comes from an actuator or tendon.
    pub fn armature_elsewhere(&self) -> bool {
        self.armature_parts.iter().any(|p| p.source != PartSource::Joint && p.value != 0.0)
    }
    /// Hinge and slide joints: one scalar DoF a motor can drive.
    pub fn is_scalar(&self) -> bool {
        matches!(self.jtype, JointType::Hinge | JointType::Slide)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Transmission {
    Joint,
    JointInParent,
    Tendon,
    SliderCrank,
    Site,
    Body,
}

/// How an actuator turns `ctrl` into force, classified from the compiled gain/bias parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum ActuatorKind {
    /// force = kp·(ctrl − q) − kv·q̇
    Position {
        kp: f64,
        kv: f64,
    },
    /// force = gear·ctrl
    Motor,
    /// force = kv·(ctrl − q̇)
    Velocity {
        kv: f64,
    },
    /// `<dcmotor>` (MuJoCo ≥ 3.17): force = K/R·(v − K·q̇) in its voltage mode; `resistance` R
    /// (Ω) and motor constant K (geometric mean of Kt and Ke). `voltage`: its only control is
    /// the terminal voltage (ctrlrange in volts), not a position/velocity controller input.
    DcMotor {
        resistance: f64,
        k: f64,
        voltage: bool,
    },
    Other,
}

#[derive(Debug, Clone)]
pub struct Actuator {
    pub id: usize,
    pub name: String,
    pub trn: Transmission,
    /// Joint/tendon/site/body id the transmission targets (−1 when missing).
    pub target: i32,
    pub gear: f64,
    pub kind: ActuatorKind,
    pub gainprm: [f64; 3],
    pub biasprm: [f64; 3],
    pub ctrllimited: bool,
    pub ctrlrange: [f64; 2],
    pub forcelimited: bool,
    pub forcerange: [f64; 2],
    pub delay: f64,
    /// The actuator's own `armature` (reflected to its transmission as armature·gear²).
    pub armature: f64,
    /// The actuator's own `damping` (applied at its transmission as damping·gear²).
    pub damping: f64,
    /// The PD servo this actuator is, whatever its gain scale (see [`Servo`]).
    pub servo: Option<Servo>,
}

impl Actuator {
    /// A servo's ctrlrange as the range of joint positions it commands (setpoints over gear,
    /// ascending); `None` for a non-servo or an actuator without a ctrlrange.
    pub fn setpoint_range(&self) -> Option<[f64; 2]> {
        let s = self.servo.filter(|_| self.ctrllimited)?;
        let g = if self.gear != 0.0 { self.gear } else { 1.0 };
        let (x, y) = (s.setpoint(self.ctrlrange[0]) / g, s.setpoint(self.ctrlrange[1]) / g);
        Some([x.min(y), x.max(y)])
    }
    /// The ctrl that holds joint position `q` (servos only; `q`·gear otherwise).
    pub fn ctrl_for_joint(&self, q: f64) -> f64 {
        let g = if self.gear != 0.0 { self.gear } else { 1.0 };
        self.servo.map_or(q * g, |s| s.ctrl_for(q * g))
    }
}

/// A fixed-gain, affine-bias actuator (`<position>`, or `<general biastype="affine">` with
/// gain g > 0 and bias (b0, b1 < 0, b2)): force = g·ctrl + b0 + b1·L + b2·L̇ = kp·(setpoint − L)
/// − kv·L̇ with kp = −b1, kv = −b2 and setpoint = scale·ctrl + offset, where scale = g/kp and
/// offset = b0/kp (L the actuator length, gear·q on a joint). A `<position>` has scale 1 and
/// offset 0; a scaled servo (the Menagerie 2F-85's gainprm 0.3137, biasprm 0 −100 −10) takes
/// its ctrl in its own units, not in the joint's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Servo {
    pub kp: f64,
    pub kv: f64,
    pub scale: f64,
    pub offset: f64,
}

impl Servo {
    /// The length the servo holds for `ctrl` (rad or m of actuator length).
    pub fn setpoint(&self, ctrl: f64) -> f64 {
        self.scale * ctrl + self.offset
    }
    /// The ctrl that holds actuator length `length`.
    pub fn ctrl_for(&self, length: f64) -> f64 {
        (length - self.offset) / self.scale
    }
    /// A `<position>`-style servo: ctrl is the setpoint itself.
    pub fn is_unit(&self) -> bool {
        (self.scale - 1.0).abs() <= 1e-9 && self.offset == 0.0
    }
}

#[derive(Debug, Clone)]
pub struct Body {
    pub id: usize,
    pub name: String,
    pub parent: usize,
    pub mass: f64,
    /// MuJoCo's `body_weldid`: the body's top ancestor with no joint in between (bodies with
    /// the same weld body move as one and never collide with each other; 0 for the world's).
    pub weld: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum GeomType {
    Plane,
    Hfield,
    Sphere,
    Capsule,
    Ellipsoid,
    Cylinder,
    Box,
    Mesh,
    Sdf,
    Other,
}

#[derive(Debug, Clone)]
pub struct Geom {
    pub id: usize,
    pub name: String,
    pub body: usize,
    pub gtype: GeomType,
    pub size: [f64; 3],
    pub contype: i32,
    pub conaffinity: i32,
    pub condim: i32,
    pub friction: [f64; 3],
    pub group: i32,
    pub mesh: i32,
    pub rbound: f64,
    /// Contact priority: of two geoms in contact, the higher one's parameters are used.
    pub priority: i32,
    /// Weight of this geom's solref/solimp when mixed with a geom of equal priority.
    pub solmix: f64,
    pub solref: [f64; 2],
    pub solimp: [f64; 5],
}

impl Geom {
    /// Takes part in collisions at all.
    pub fn collides(&self) -> bool {
        self.contype != 0 || self.conaffinity != 0
    }
}

/// State of the model at the standing keyframe (or qpos0): kinematics and inertia.
#[derive(Debug, Clone, Default)]
pub struct KeyState {
    pub key: Option<usize>,
    pub key_name: Option<String>,
    pub qpos: Vec<f64>,
    pub ctrl: Vec<f64>,
    /// Diagonal of the joint-space inertia matrix M (armature included by MuJoCo), per DoF.
    pub m_diag: Vec<f64>,
    pub geom_xpos: Vec<[f64; 3]>,
    /// Row-major 3×3 rotation per geom.
    pub geom_xmat: Vec<[f64; 9]>,
    pub body_xpos: Vec<[f64; 3]>,
    /// World position of each joint's anchor and its unit world axis (hinge, slide) at the key.
    pub joint_xanchor: Vec<[f64; 3]>,
    pub joint_xaxis: Vec<[f64; 3]>,
    /// With no keyframe, how many limited joints qpos0 placed outside their range and this
    /// state moved to their nearest stop (the static foot rules' pose: `rules::contact::pose`);
    /// 0 at a keyframe or at qpos0 as written.
    pub clamped: usize,
}

/// Gravity, timestep, integrator, disabled features.
#[derive(Debug, Clone)]
pub struct Options {
    pub timestep: f64,
    pub integrator: i32,
    pub gravity: [f64; 3],
    /// `mjOption.disableflags` (`<option><flag ... = "disable"/>`).
    pub disableflags: i32,
}

/// A loaded robot model.
#[derive(Clone)]
pub struct Robot {
    /// Unique per loaded model in this process (probe benches key their scratch copies on it).
    pub uid: u64,
    pub path: PathBuf,
    pub format: Format,
    pub tree: XNode,
    pub src: SourceIndex,
    pub mj: MjModel,
    pub joints: Vec<Joint>,
    pub actuators: Vec<Actuator>,
    pub bodies: Vec<Body>,
    pub geoms: Vec<Geom>,
    pub keys: Vec<String>,
    pub opt: Options,
    pub key: KeyState,
    pub meshes: Vec<String>,
    pub tendons: Vec<String>,
    pub equalities: Vec<Equality>,
    /// Explicit `<contact><pair>` elements (compiled `pair_*`).
    pub pairs: Vec<contact::Pair>,
    /// Body pairs whose contacts `<contact><exclude>` removes (compiled `exclude_signature`),
    /// lower body id first.
    pub excludes: Vec<(usize, usize)>,
}

#[derive(Debug, Clone)]
pub struct Equality {
    pub id: usize,
    pub name: String,
    /// 0 connect, 1 weld, 2 joint, 3 tendon, ...
    pub etype: i32,
    pub obj1: i32,
    pub obj2: i32,
}

impl std::fmt::Debug for Robot {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Robot")
            .field("path", &self.path)
            .field("joints", &self.joints.len())
            .finish()
    }
}

impl Robot {
    pub fn joint(&self, name: &str) -> Option<&Joint> {
        self.joints.iter().find(|j| j.name == name)
    }
    /// Where an unnamed geom is: its number among its body's geoms (from 1, in compiled order,
    /// which is the body's order in the file). Unlike MuJoCo's geom id it does not depend on
    /// what a scene file adds around the robot (a floor compiled first shifts every id).
    pub fn geom_no(&self, g: usize) -> usize {
        let Some(body) = self.geoms.get(g).map(|x| x.body) else { return g + 1 };
        self.geoms[..g].iter().filter(|x| x.body == body).count() + 1
    }
    /// An unnamed geom as findings name it: "no. 2 of body `foot`" ([`Self::geom_no`]). A world
    /// geom is counted in its own file (a scene's floor and an included robot file's world geoms
    /// are all the world body's, in an order neither file shows), with MuJoCo's geom id (from 0).
    pub fn unnamed_geom(&self, g: usize) -> String {
        let body = self.geoms.get(g).map_or(0, |x| x.body);
        if body != 0 {
            return format!("no. {} of body `{}`", self.geom_no(g), self.body_name(body));
        }
        let list = self.src.list(ElemKind::Geom);
        let in_file = self.elem(ElemKind::Geom, g, "").and_then(|e| {
            let at = list.iter().position(|x| std::ptr::eq(x, e))?;
            Some(list[..at].iter().filter(|x| x.body.is_none() && x.loc.file == e.loc.file).count())
        });
        match in_file {
            Some(k) => {
                format!("no. {} of the world body in its file (MuJoCo geom id {g})", k + 1)
            }
            None => format!("of the world body with MuJoCo geom id {g}"),
        }
    }
    /// A geom as a message names it: "`name`", else "no. 2 of body `foot`".
    pub fn geom_ref(&self, g: usize) -> String {
        match self.geoms.get(g).map(|x| x.name.as_str()) {
            Some(n) if !n.is_empty() => format!("`{n}`"),
            _ => self.unnamed_geom(g),
        }
    }
    pub fn body_name(&self, id: usize) -> &str {
        self.bodies.get(id).map(|b| b.name.as_str()).unwrap_or("")
    }
    /// The moment arm of actuator `a` at joint `j`: its gear on a joint transmission, gear ×
    /// the joint's coefficient in a fixed tendon (summed if the joint appears more than once),
    /// `None` when the transmission does not reach `j` that way.
    pub fn moment_at_joint(&self, a: &Actuator, j: usize) -> Option<f64> {
        match a.trn {
            Transmission::Joint | Transmission::JointInParent => {
                (a.target == j as i32).then_some(a.gear)
            }
            Transmission::Tendon if a.target >= 0 => {
                let m = &self.mj;
                let t = a.target as usize;
                let (adr, num) = (*m.tendon_adr().get(t)?, *m.tendon_num().get(t)?);
                let (wt, wo, wp) = (m.wrap_type(), m.wrap_objid(), m.wrap_prm());
                let coef: f64 = (adr.max(0) as usize..(adr.max(0) + num.max(0)) as usize)
                    .filter(|&w| wt.get(w).is_some_and(|&t| t as i32 == 1))
                    .filter(|&w| wo.get(w) == Some(&(j as i32)))
                    .filter_map(|w| wp.get(w).copied())
                    .sum();
                (coef != 0.0).then_some(a.gear * coef)
            }
            _ => None,
        }
    }
    /// Actuators whose transmission reaches joint `j` (directly, or through a fixed tendon).
    pub fn actuators_on_joint(&self, j: usize) -> Vec<&Actuator> {
        let m = &self.mj;
        self.actuators
            .iter()
            .filter(|a| match a.trn {
                Transmission::Joint | Transmission::JointInParent => a.target == j as i32,
                Transmission::Tendon if a.target >= 0 => {
                    let t = a.target as usize;
                    let (Some(&adr), Some(&num)) = (m.tendon_adr().get(t), m.tendon_num().get(t))
                    else {
                        return false;
                    };
                    let (adr, num) = (adr.max(0) as usize, num.max(0) as usize);
                    let (wt, wo) = (m.wrap_type(), m.wrap_objid());
                    (adr..adr + num).any(|w| {
                        wt.get(w).map(|&t| t as i32) == Some(1) && wo.get(w) == Some(&(j as i32))
                    })
                }
                _ => false,
            })
            .collect()
    }

    /// Source element of a compiled object, matched by name, else by compiled order: bodies by
    /// their pre-order position, joints/geoms/sites by their rank inside their (matched) body.
    /// Matching inside the body keeps an unnamed geom on its own line when a scene file adds
    /// world geoms (a floor) that MuJoCo numbers before the robot's.
    pub fn elem(&self, kind: ElemKind, id: usize, name: &str) -> Option<&ElemSrc> {
        if !name.is_empty()
            && let Some(e) = self.src.by_name(kind, name)
        {
            return Some(e);
        }
        let list = self.src.list(kind);
        if kind == ElemKind::Pair {
            // Pairs compile in signature order; each names its two geoms.
            let p = self.pairs.get(id)?;
            let (a, b) =
                (self.geoms.get(p.geom1)?.name.as_str(), self.geoms.get(p.geom2)?.name.as_str());
            if a.is_empty() || b.is_empty() {
                return None;
            }
            return list.iter().find(|e| {
                let v = |k: &str| e.attrs.get(k).map(|o| o.value.as_str()).unwrap_or("");
                let (g1, g2) = (v("geom1"), v("geom2"));
                (g1 == a && g2 == b) || (g1 == b && g2 == a)
            });
        }
        let body_of: Vec<usize> = match kind {
            ElemKind::Joint => self.joints.iter().map(|j| j.body).collect(),
            ElemKind::Geom => self.geoms.iter().map(|g| g.body).collect(),
            ElemKind::Site => self.mj.site_bodyid().iter().map(|&b| b.max(0) as usize).collect(),
            _ => {
                // Compiled order matches source order only when every element was indexed.
                let expected = match kind {
                    ElemKind::Body => self.bodies.len().saturating_sub(1),
                    ElemKind::Actuator => self.actuators.len(),
                    ElemKind::Key => self.keys.len(),
                    _ => usize::MAX,
                };
                let idx = if kind == ElemKind::Body { id.checked_sub(1)? } else { id };
                return if list.len() == expected { list.get(idx) } else { None };
            }
        };
        let b = *body_of.get(id)?;
        let rank = body_of[..id].iter().filter(|&&x| x == b).count();
        let count = body_of.iter().filter(|&&x| x == b).count();
        let src_body = if b == 0 {
            None
        } else {
            let e = self.elem(ElemKind::Body, b, self.body_name(b))?;
            Some(self.src.list(ElemKind::Body).iter().position(|x| std::ptr::eq(x, e))?)
        };
        let in_body: Vec<&ElemSrc> = list.iter().filter(|e| e.body == src_body).collect();
        if in_body.len() == count { in_body.get(rank).copied() } else { None }
    }

    /// Tightest location for attribute `attr` of an object (falls back to the element, then the
    /// model root), and the default class it was inherited from, if any.
    pub fn attr_loc(
        &self,
        kind: ElemKind,
        id: usize,
        name: &str,
        attr: &str,
    ) -> (Loc, Option<String>) {
        match self.elem(kind, id, name) {
            Some(e) => match e.attrs.get(attr) {
                Some(o) => (o.loc, o.class.clone()),
                None => (e.loc, None),
            },
            None => (self.root_loc(), None),
        }
    }

    pub fn elem_loc(&self, kind: ElemKind, id: usize, name: &str) -> Loc {
        self.elem(kind, id, name).map(|e| e.loc).unwrap_or_else(|| self.root_loc())
    }

    pub fn root_loc(&self) -> Loc {
        self.src.root.unwrap_or(Loc { file: 0, start: 0, end: 0 })
    }

    /// (the robot's mass, the static scenery's) [kg]: a body counts as the robot's when it moves
    /// or carries one that moves (a fixed arm's base does, a table or a wall does not).
    pub fn mass_split(&self) -> (f64, f64) {
        let mut robot = vec![false; self.bodies.len()];
        for b in self.bodies.iter().rev().filter(|b| b.id > 0) {
            if b.weld != 0 || robot[b.id] {
                robot[b.id] = true;
                robot[b.parent] = true;
            }
        }
        let sum =
            |own: bool| self.bodies.iter().filter(|b| robot[b.id] == own).map(|b| b.mass).sum();
        (sum(true), sum(false))
    }
}

/// The files a lint of `path` reads as a model, without compiling it (the lint cache's key):
/// the XML and its includes and, for MJCF, every asset file it names. A file that is not a
/// robot model is its only input. `None` for URDF (MuJoCo resolves its mesh paths its own way)
/// and when the files cannot be listed (the model does not load).
pub fn inputs(path: &Path) -> Option<Vec<PathBuf>> {
    let mut map = SourceMap::default();
    let tree = source::parse_xml_tree(&mut map, path, true).ok()?;
    let files = map.files.iter().map(|f| f.path.clone());
    match tree.tag.as_str() {
        "mujoco" => {
            let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
            let assets = check_assets(&map, &tree, &dir).ok()?;
            Some(files.chain(assets).collect())
        }
        "robot" => None,
        _ => Some(files.collect()),
    }
}

/// Loads an MJCF or URDF model. `keyframe` names the standing keyframe, when known.
pub fn load(map: &mut SourceMap, path: &Path, keyframe: Option<&str>) -> Result<Robot, LoadError> {
    let first = map.files.len();
    let tree = source::parse_xml_tree(map, path, true)?;
    let format = match tree.tag.as_str() {
        "mujoco" => Format::Mjcf,
        "robot" => Format::Urdf,
        other => {
            return Err(LoadError::at(
                map,
                tree.loc,
                format!("root element <{other}> is neither MJCF (<mujoco>) nor URDF (<robot>)"),
            ));
        }
    };
    check_numbers(map, &tree)?;
    if format == Format::Urdf {
        checks::check_urdf_names(map, &tree)?;
        checks::check_urdf_numbers(map, &tree)?;
    }
    let model_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    if format == Format::Mjcf {
        check_assets(map, &tree, &model_dir)?;
    }
    let src = match format {
        Format::Mjcf => mjcf::index_mjcf(&tree),
        Format::Urdf => mjcf::index_urdf(&tree),
    };
    // URDF `package://` meshes: MuJoCo compiles a resolved copy (same line numbers).
    let resolved =
        if format == Format::Urdf { urdf_packages::resolved_copy(map, first)? } else { None };
    plugins::load_once();
    let load_path = resolved.as_deref().unwrap_or(path);
    let m =
        MjModel::from_xml(load_path).map_err(|e| mj::full_load_error(load_path, &e.to_string()));
    if let Some(t) = &resolved {
        let _ = std::fs::remove_file(t);
    }
    let mj = m.map_err(|e| {
        let msg = plugins::explain(format!("MuJoCo could not compile the model: {e}"));
        let mut err = errloc::bad_value_location(map, first, &msg)
            .or_else(|| mujoco_error_location(map, first, &msg))
            .or_else(|| mujoco_element_location(map, first, format, &msg))
            .or_else(|| attribute_error_location(map, first, &msg))
            .or_else(|| missing_file_location(map, first, &msg))
            // MuJoCo did not say where: the model's root element, so that the error still
            // names a line of the file.
            .unwrap_or_else(|| LoadError::at(map, tree.loc, msg));
        err.message = urdf_inertia::explain(map, &tree, err.message, format == Format::Urdf);
        err
    })?;
    let mut robot = extract(path, format, tree, src, mj);
    let key = choose_key(&robot.keys, keyframe);
    if let Some(want) = keyframe
        && key.is_none()
    {
        return Err(LoadError::plain(
            path,
            format!(
                "keyframe `{want}` named by the spec is not in the model (keyframes: {:?})",
                robot.keys
            ),
        ));
    }
    robot.key = key_state(&robot.mj, key, &robot.keys);
    Ok(robot)
}

fn choose_key(keys: &[String], want: Option<&str>) -> Option<usize> {
    if let Some(w) = want {
        return keys.iter().position(|k| k == w);
    }
    for pref in ["stand", "standing", "home", "default", "init"] {
        if let Some(i) = keys.iter().position(|k| k.eq_ignore_ascii_case(pref)) {
            return Some(i);
        }
    }
    if keys.is_empty() { None } else { Some(0) }
}

/// "0.005 (joint) + 0.002 × 10² (actuator `ankle`)": where an effective value came from.
pub fn describe_parts(robot: &Robot, parts: &[Part], what: &str) -> String {
    if parts.is_empty() {
        return format!("no {what} on the joint, its actuators or tendons");
    }
    let n = |x: f64| crate::util::fmt_num(x, 4);
    let an = |id: usize| {
        robot
            .actuators
            .get(id)
            .map(|a| if a.name.is_empty() { format!("#{id}") } else { a.name.clone() })
            .unwrap_or_default()
    };
    let tn = |id: usize| {
        robot
            .tendons
            .get(id)
            .map(|t| if t.is_empty() { format!("#{id}") } else { t.clone() })
            .unwrap_or_default()
    };
    let v: Vec<String> = parts
        .iter()
        .map(|p| match p.source {
            PartSource::Joint => format!("{} (joint `{what}`)", n(p.value)),
            PartSource::Actuator(a, g) => {
                format!("{} × {}² (actuator `{}`)", n(p.value / (g * g)), n(g.abs()), an(a))
            }
            PartSource::Tendon(t, c) => {
                format!("{} × {}² (tendon `{}`)", n(p.value / (c * c)), n(c.abs()), tn(t))
            }
            PartSource::TendonActuator(a, t, g, c) => format!(
                "{} × {}² × {}² (actuator `{}` on tendon `{}`)",
                n(p.value / (g * g * c * c)),
                n(g.abs()),
                n(c.abs()),
                an(a),
                tn(t)
            ),
            PartSource::BackEmf(a, g) => format!(
                "{} × {}² (back-EMF K²/R of dcmotor `{}`)",
                n(p.value / (g * g)),
                n(g.abs()),
                an(a)
            ),
        })
        .collect();
    if v.len() == 1 && parts[0].source == PartSource::Joint { v[0].clone() } else { v.join(" + ") }
}
