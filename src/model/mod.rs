//! Loading robot models: MuJoCo's compiled model is the semantic truth (defaults, includes,
//! units are resolved by MuJoCo itself); the XML source index supplies spans for diagnostics.

pub mod cache;
pub mod mj;
pub mod mjcf;
pub mod source;
pub mod urdf_packages;

use std::path::{Path, PathBuf};

use mujoco_rs::prelude::*;

use crate::error::LoadError;
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
}

#[derive(Debug, Clone)]
pub struct Body {
    pub id: usize,
    pub name: String,
    pub parent: usize,
    pub mass: f64,
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
}

/// Gravity, timestep, integrator.
#[derive(Debug, Clone)]
pub struct Options {
    pub timestep: f64,
    pub integrator: i32,
    pub gravity: [f64; 3],
}

/// A loaded robot model.
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
    pub fn body_name(&self, id: usize) -> &str {
        self.bodies.get(id).map(|b| b.name.as_str()).unwrap_or("")
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

    pub fn total_mass(&self) -> f64 {
        self.bodies.iter().map(|b| b.mass).sum()
    }
}

/// Attributes that hold names or paths, never numbers (skipped by the NaN/inf check).
const STRING_ATTRS: &[&str] = &[
    "name",
    "class",
    "childclass",
    "file",
    "joint",
    "joint1",
    "joint2",
    "body",
    "body1",
    "body2",
    "geom",
    "geom1",
    "geom2",
    "site",
    "site1",
    "site2",
    "tendon",
    "tendon1",
    "tendon2",
    "mesh",
    "material",
    "texture",
    "hfield",
    "target",
    "objname",
    "objtype",
    "type",
    "meshdir",
    "texturedir",
    "assetdir",
    "model",
    "prefix",
    "content_type",
    "refsite",
    "cranksite",
    "slidersite",
    "actuator",
    "plugin",
    "instance",
    "key",
    "mode",
    "link",
    "parent",
    "child",
    "filename",
    "version",
];

fn check_numbers(map: &SourceMap, n: &XNode) -> Result<(), LoadError> {
    for a in &n.attrs {
        if STRING_ATTRS.contains(&a.name.as_str()) {
            continue;
        }
        let toks: Vec<&str> = a.value.split_whitespace().collect();
        if toks.is_empty() {
            continue;
        }
        let parsed: Vec<Option<f64>> = toks.iter().map(|t| t.parse::<f64>().ok()).collect();
        if parsed.iter().all(Option::is_some)
            && parsed.iter().any(|v| !v.unwrap_or(0.0).is_finite())
        {
            return Err(LoadError::at(
                map,
                a.loc,
                format!(
                    "<{}> attribute `{}` is not a finite number: \"{}\"",
                    n.tag, a.name, a.value
                ),
            ));
        }
    }
    for c in &n.children {
        check_numbers(map, c)?;
    }
    Ok(())
}

/// Asset attributes that name files MuJoCo reads (cube and skybox textures use the six faces).
const FILE_ATTRS: &[&str] =
    &["file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback"];

/// Checks that every asset file the model names exists, pointing at the attribute when not, and
/// returns them (the inputs of the compile, for the cache key).
fn check_assets(
    map: &SourceMap,
    root: &XNode,
    model_dir: &Path,
) -> Result<Vec<PathBuf>, LoadError> {
    let mut files = Vec::new();
    let mut meshdir = None;
    let mut texturedir = None;
    for c in root.children_tagged("compiler") {
        if let Some(d) = c.get("assetdir") {
            meshdir.get_or_insert(d.to_string());
            texturedir.get_or_insert(d.to_string());
        }
        if let Some(d) = c.get("meshdir") {
            meshdir = Some(d.to_string());
        }
        if let Some(d) = c.get("texturedir") {
            texturedir = Some(d.to_string());
        }
    }
    for asset in root.children_tagged("asset") {
        for a in &asset.children {
            let dir = match a.tag.as_str() {
                "mesh" | "hfield" | "skin" => &meshdir,
                "texture" => &texturedir,
                _ => &None,
            };
            for f in FILE_ATTRS.iter().filter_map(|n| a.attr(n)) {
                let p = Path::new(&f.value);
                let full = if p.is_absolute() {
                    p.to_path_buf()
                } else {
                    model_dir.join(dir.as_deref().unwrap_or("")).join(p)
                };
                if !full.is_file() {
                    return Err(LoadError::at(
                        map,
                        f.loc,
                        format!(
                            "<{}> file not found: {} (looked for {})",
                            a.tag,
                            f.value,
                            full.display()
                        ),
                    ));
                }
                files.push(full);
            }
        }
    }
    Ok(files)
}

fn geom_type(t: i32) -> GeomType {
    match t {
        0 => GeomType::Plane,
        1 => GeomType::Hfield,
        2 => GeomType::Sphere,
        3 => GeomType::Capsule,
        4 => GeomType::Ellipsoid,
        5 => GeomType::Cylinder,
        6 => GeomType::Box,
        7 => GeomType::Mesh,
        8 => GeomType::Sdf,
        _ => GeomType::Other,
    }
}

/// Loads an MJCF or URDF model. `keyframe` names the standing keyframe, when known.
pub fn load(map: &mut SourceMap, path: &Path, keyframe: Option<&str>) -> Result<Robot, LoadError> {
    load_cached(map, path, keyframe, None, &[])
}

/// As `load`, with the compiled model taken from (or written to) the cache in `cache_dir`.
/// `extra_inputs` (the spec) join the cache key. URDF models are always compiled: MuJoCo
/// resolves their mesh paths its own way, so their inputs are not known here.
pub fn load_cached(
    map: &mut SourceMap,
    path: &Path,
    keyframe: Option<&str>,
    cache_dir: Option<&Path>,
    extra_inputs: &[PathBuf],
) -> Result<Robot, LoadError> {
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
    let model_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let assets =
        if format == Format::Mjcf { Some(check_assets(map, &tree, &model_dir)?) } else { None };
    let src = match format {
        Format::Mjcf => mjcf::index_mjcf(&tree),
        Format::Urdf => mjcf::index_urdf(&tree),
    };
    let key = match (cache_dir, &assets) {
        (Some(_), Some(assets)) => {
            let mut inputs: Vec<(PathBuf, Option<&str>)> = map.files[first..]
                .iter()
                .map(|f| (f.path.clone(), Some(f.text.as_str())))
                .collect();
            inputs.extend(assets.iter().chain(extra_inputs).map(|p| (p.clone(), None)));
            cache::key(&inputs)
        }
        _ => None,
    };
    let cached = match (cache_dir, &key) {
        (Some(dir), Some(k)) => cache::load(dir, k),
        _ => None,
    };
    let mj = match cached {
        Some(m) => m,
        None => {
            // URDF `package://` meshes: MuJoCo compiles a resolved copy (same line numbers).
            let resolved = if format == Format::Urdf {
                urdf_packages::resolved_copy(map, first)?
            } else {
                None
            };
            let m = MjModel::from_xml(resolved.as_deref().unwrap_or(path));
            if let Some(t) = &resolved {
                let _ = std::fs::remove_file(t);
            }
            let m = m.map_err(|e| {
                let msg = format!("MuJoCo could not compile the model: {e}");
                mujoco_error_location(map, first, &msg)
                    .or_else(|| missing_file_location(map, first, &msg))
                    .unwrap_or_else(|| LoadError::plain(path, msg))
            })?;
            if let (Some(dir), Some(k), Some(bytes)) =
                (cache_dir, &key, cache_dir.and_then(|_| cache::serialize(&m)))
            {
                cache::store_in_background(dir, k, bytes);
            }
            m
        }
    };
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

/// "Error opening file 'X'": the attribute that names X (by its file name), at its file:line.
fn missing_file_location(map: &SourceMap, first_file: usize, msg: &str) -> Option<LoadError> {
    let i = msg.find("Error opening file '")? + "Error opening file '".len();
    let name = msg[i..].split('\'').next()?;
    let base = name.rsplit(['/', '\\']).next().filter(|b| !b.is_empty())?;
    for f in first_file..map.files.len() {
        let text = &map.file(f).text;
        for pat in ["filename=\"", "file=\""] {
            let mut from = 0;
            while let Some(k) = text[from..].find(pat) {
                let vs = from + k + pat.len();
                let ve = text[vs..].find('"').map_or(text.len(), |e| vs + e);
                if text[vs..ve].ends_with(base) {
                    return Some(LoadError::at(
                        map,
                        Loc { file: f, start: vs, end: ve },
                        format!("{msg} (file not found)"),
                    ));
                }
                from = ve;
            }
        }
    }
    None
}

/// MuJoCo reports XML problems as "... line N, column M" or with a file name; map them back.
fn mujoco_error_location(map: &SourceMap, first_file: usize, msg: &str) -> Option<LoadError> {
    let lower = msg.to_lowercase();
    let li = lower.find("line ")?;
    let rest = &msg[li + 5..];
    let line: usize = rest.split(|c: char| !c.is_ascii_digit()).next()?.parse().ok()?;
    let col = lower
        .find("column ")
        .and_then(|ci| msg[ci + 7..].split(|c: char| !c.is_ascii_digit()).next()?.parse().ok());
    // Prefer the file MuJoCo names, else the top-level model.
    let file = (first_file..map.files.len())
        .find(|&i| {
            map.file(i).path.file_name().and_then(|f| f.to_str()).is_some_and(|f| msg.contains(f))
        })
        .unwrap_or(first_file);
    Some(LoadError::at_line(map, file, line, col.unwrap_or(1), msg.to_string()))
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

fn extract(path: &Path, format: Format, tree: XNode, src: SourceIndex, mj: MjModel) -> Robot {
    let r = mj::raw(&mj);
    // Per-actuator arrays have `nactuator` rows; controls (`nu`) and force outputs (`nout`) can
    // differ from it in MuJoCo ≥ 3.17 (a `<dcmotor>` may take 0 or several controls).
    let (njnt, nu, nbody, ngeom, nkey) = (
        r.njnt as usize,
        r.nactuator as usize,
        r.nbody as usize,
        r.ngeom as usize,
        r.nkey as usize,
    );
    let nctrl = r.nu as usize;
    let jt: Vec<i32> = mj.jnt_type().iter().map(|&t| t as i32).collect();
    let jb = mj.jnt_bodyid();
    let jq = mj.jnt_qposadr();
    let jd = mj.jnt_dofadr();
    let jl = mj.jnt_limited();
    let jr = mj.jnt_range().as_flattened();
    let js = mj.jnt_stiffness();
    let jax = mj.jnt_axis().as_flattened();
    let darm = mj.dof_armature();
    let ddamp = mj.dof_damping();
    let dfl = mj.dof_frictionloss();
    let qspring = mj.qpos_spring();
    let joints = (0..njnt)
        .map(|i| {
            let d = jd[i].max(0) as usize;
            Joint {
                id: i,
                name: mj::name_at(&mj, mj.name_jntadr(), i),
                jtype: match jt[i] {
                    0 => JointType::Free,
                    1 => JointType::Ball,
                    2 => JointType::Slide,
                    _ => JointType::Hinge,
                },
                body: jb[i].max(0) as usize,
                qposadr: jq[i].max(0) as usize,
                dofadr: d,
                limited: jl[i],
                range: [jr[2 * i], jr[2 * i + 1]],
                armature: darm.get(d).copied().unwrap_or(0.0),
                damping: ddamp.get(d).copied().unwrap_or(0.0),
                armature_parts: own_part(darm.get(d).copied().unwrap_or(0.0)),
                damping_parts: own_part(ddamp.get(d).copied().unwrap_or(0.0)),
                stiffness: js[i],
                frictionloss: dfl.get(d).copied().unwrap_or(0.0),
                springref: qspring.get(jq[i].max(0) as usize).copied().unwrap_or(0.0),
                axis: [jax[3 * i], jax[3 * i + 1], jax[3 * i + 2]],
            }
        })
        .collect::<Vec<Joint>>();
    let mut joints = joints;
    let trn: Vec<i32> = mj.actuator_trntype().iter().map(|&t| t as i32).collect();
    let trnid = mj.actuator_trnid().as_flattened();
    let gear = mj.actuator_gear().as_flattened();
    let cadr = mj.actuator_ctrladr();
    let cnum = mj.actuator_ctrlnum();
    let oadr = mj.actuator_outadr();
    let aarm = mj.actuator_armature();
    let cspec = mj.actuator_ctrlspec();
    let adamp = mj.actuator_damping();
    let gt: Vec<i32> = mj.actuator_gaintype().iter().map(|&t| t as i32).collect();
    let bt: Vec<i32> = mj.actuator_biastype().iter().map(|&t| t as i32).collect();
    let gp = mj.actuator_gainprm().as_flattened();
    let bp = mj.actuator_biasprm().as_flattened();
    let cl = mj.actuator_ctrllimited();
    let cr = mj.actuator_ctrlrange().as_flattened();
    let fl = mj.actuator_forcelimited();
    let fr = mj.actuator_forcerange().as_flattened();
    let dl = mj.actuator_delay();
    let actuators = (0..nu)
        .map(|i| {
            let g = [gp[10 * i], gp[10 * i + 1], gp[10 * i + 2]];
            let b = [bp[10 * i], bp[10 * i + 1], bp[10 * i + 2]];
            // First control of the actuator (none for a passive `<dcmotor input="none">`).
            let c = (cnum[i] > 0 && (cadr[i].max(0) as usize) < nctrl)
                .then_some(cadr[i].max(0) as usize);
            // gaintype 0 = fixed; biastype 0 = none, 1 = affine.
            // gaintype/biastype 3 = dcmotor: gainprm[0] = resistance, gainprm[1] = motor constant.
            let kind = if gt[i] == 3 && bt[i] == 3 {
                ActuatorKind::DcMotor {
                    resistance: g[0],
                    k: g[1],
                    voltage: cspec.get(i) == Some(&8),
                }
            } else if gt[i] == 0 && bt[i] == 0 && g[0] != 0.0 {
                ActuatorKind::Motor
            } else if gt[i] == 0
                && bt[i] == 1
                && g[0] > 0.0
                && (b[1] + g[0]).abs() <= 1e-9 * g[0].abs().max(1.0)
                && b[0] == 0.0
            {
                ActuatorKind::Position { kp: g[0], kv: -b[2] }
            } else if gt[i] == 0
                && bt[i] == 1
                && b[1] == 0.0
                && (b[2] + g[0]).abs() <= 1e-9 * g[0].abs().max(1.0)
            {
                ActuatorKind::Velocity { kv: g[0] }
            } else {
                ActuatorKind::Other
            };
            Actuator {
                id: i,
                name: mj::name_at(&mj, mj.name_actuatoradr(), i),
                trn: match trn[i] {
                    0 => Transmission::Joint,
                    1 => Transmission::JointInParent,
                    2 => Transmission::SliderCrank,
                    3 => Transmission::Tendon,
                    4 => Transmission::Site,
                    _ => Transmission::Body,
                },
                target: trnid[2 * i],
                gear: gear.get(6 * (oadr[i].max(0) as usize)).copied().unwrap_or(1.0),
                kind,
                gainprm: g,
                biasprm: b,
                ctrllimited: c.is_some_and(|c| cl[c]),
                ctrlrange: c.map(|c| [cr[2 * c], cr[2 * c + 1]]).unwrap_or([0.0, 0.0]),
                forcelimited: fl[i],
                forcerange: [fr[2 * i], fr[2 * i + 1]],
                delay: dl.get(i).copied().unwrap_or(0.0),
                armature: aarm.get(i).copied().unwrap_or(0.0),
                damping: adamp.get(i).copied().unwrap_or(0.0),
            }
        })
        .collect::<Vec<Actuator>>();
    add_transmission_parts(&mj, &mut joints, &actuators);
    let bp_ = mj.body_parentid();
    let bm = mj.body_mass();
    let bodies = (0..nbody)
        .map(|i| Body {
            id: i,
            name: mj::name_at(&mj, mj.name_bodyadr(), i),
            parent: bp_[i].max(0) as usize,
            mass: bm[i],
        })
        .collect();
    let gtp: Vec<i32> = mj.geom_type().iter().map(|&t| t as i32).collect();
    let gb = mj.geom_bodyid();
    let gs = mj.geom_size().as_flattened();
    let gct = mj.geom_contype();
    let gca = mj.geom_conaffinity();
    let gcd = mj.geom_condim();
    let gf = mj.geom_friction().as_flattened();
    let gg = mj.geom_group();
    let gd = mj.geom_dataid();
    let grb = mj.geom_rbound();
    let geoms = (0..ngeom)
        .map(|i| Geom {
            id: i,
            name: mj::name_at(&mj, mj.name_geomadr(), i),
            body: gb[i].max(0) as usize,
            gtype: geom_type(gtp[i]),
            size: [gs[3 * i], gs[3 * i + 1], gs[3 * i + 2]],
            contype: gct[i],
            conaffinity: gca[i],
            condim: gcd[i],
            friction: [gf[3 * i], gf[3 * i + 1], gf[3 * i + 2]],
            group: gg[i],
            mesh: if gtp[i] == 7 { gd[i] } else { -1 },
            rbound: grb[i],
        })
        .collect();
    let keys = (0..nkey).map(|i| mj::name_at(&mj, mj.name_keyadr(), i)).collect();
    let nmesh = r.nmesh as usize;
    let meshes = (0..nmesh).map(|i| mj::name_at(&mj, mj.name_meshadr(), i)).collect();
    let ntendon = r.ntendon as usize;
    let tendons = (0..ntendon).map(|i| mj::name_at(&mj, mj.name_tendonadr(), i)).collect();
    let neq = r.neq as usize;
    let et: Vec<i32> = mj.eq_type().iter().map(|&t| t as i32).collect();
    let e1 = mj.eq_obj1id();
    let e2 = mj.eq_obj2id();
    let equalities = (0..neq)
        .map(|i| Equality {
            id: i,
            name: mj::name_at(&mj, mj.name_eqadr(), i),
            etype: et[i],
            obj1: e1[i],
            obj2: e2[i],
        })
        .collect();
    let opt =
        Options { timestep: r.opt.timestep, integrator: r.opt.integrator, gravity: r.opt.gravity };
    static NEXT_UID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    Robot {
        uid: NEXT_UID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
        path: path.to_path_buf(),
        format,
        tree,
        src,
        mj,
        joints,
        actuators,
        bodies,
        geoms,
        keys,
        opt,
        key: KeyState::default(),
        meshes,
        tendons,
        equalities,
    }
}

fn own_part(v: f64) -> Vec<Part> {
    if v != 0.0 { vec![Part { source: PartSource::Joint, value: v }] } else { Vec::new() }
}

/// Adds what actuators and fixed tendons contribute to each joint's armature and damping
/// (MuJoCo ≥ 3.17): actuator armature/damping × gear², tendon armature/damping × coef² (with the
/// tendon's actuators' values × gear² added to the tendon's), and a `<dcmotor>`'s back-EMF
/// K²/R × gear² as damping.
fn add_transmission_parts(m: &MjModel, joints: &mut [Joint], actuators: &[Actuator]) {
    let (tadr, tnum) = (m.tendon_adr(), m.tendon_num());
    let (tarm, tdamp) = (m.tendon_armature(), m.tendon_damping());
    let wt: Vec<i32> = m.wrap_type().iter().map(|&t| t as i32).collect();
    let (wo, wp) = (m.wrap_objid(), m.wrap_prm());
    let push = |parts: &mut Vec<Part>, source: PartSource, value: f64| {
        if value != 0.0 && value.is_finite() {
            parts.push(Part { source, value });
        }
    };
    for a in actuators {
        if a.target < 0 {
            continue;
        }
        let g2 = a.gear * a.gear;
        let emf = match a.kind {
            ActuatorKind::DcMotor { resistance, k, .. } if resistance > 0.0 => k * k / resistance,
            _ => 0.0,
        };
        match a.trn {
            Transmission::Joint | Transmission::JointInParent => {
                let Some(j) = joints.get_mut(a.target as usize) else { continue };
                if !j.is_scalar() {
                    continue;
                }
                push(&mut j.armature_parts, PartSource::Actuator(a.id, a.gear), a.armature * g2);
                push(&mut j.damping_parts, PartSource::Actuator(a.id, a.gear), a.damping * g2);
                push(&mut j.damping_parts, PartSource::BackEmf(a.id, a.gear), emf * g2);
            }
            Transmission::Tendon => {
                let t = a.target as usize;
                let (Some(&adr), Some(&num)) = (tadr.get(t), tnum.get(t)) else { continue };
                for w in adr.max(0) as usize..(adr.max(0) + num.max(0)) as usize {
                    if wt.get(w) != Some(&1) {
                        continue;
                    }
                    let (Some(&jid), Some(&coef)) = (wo.get(w), wp.get(w)) else { continue };
                    let Some(j) = joints.get_mut(jid.max(0) as usize) else { continue };
                    let c2 = coef * coef;
                    push(
                        &mut j.armature_parts,
                        PartSource::TendonActuator(a.id, t, a.gear, coef),
                        a.armature * g2 * c2,
                    );
                    push(
                        &mut j.damping_parts,
                        PartSource::TendonActuator(a.id, t, a.gear, coef),
                        a.damping * g2 * c2,
                    );
                    push(
                        &mut j.damping_parts,
                        PartSource::BackEmf(a.id, a.gear * coef),
                        emf * g2 * c2,
                    );
                }
            }
            _ => {}
        }
    }
    for t in 0..tadr.len().min(tnum.len()).min(tarm.len()).min(tdamp.len()) {
        if tarm[t] == 0.0 && tdamp[t] == 0.0 {
            continue;
        }
        for w in tadr[t].max(0) as usize..(tadr[t].max(0) + tnum[t].max(0)) as usize {
            if wt.get(w) != Some(&1) {
                continue;
            }
            let (Some(&jid), Some(&coef)) = (wo.get(w), wp.get(w)) else { continue };
            let Some(j) = joints.get_mut(jid.max(0) as usize) else { continue };
            push(&mut j.armature_parts, PartSource::Tendon(t, coef), tarm[t] * coef * coef);
            push(&mut j.damping_parts, PartSource::Tendon(t, coef), tdamp[t] * coef * coef);
        }
    }
    for j in joints.iter_mut() {
        j.armature = j.armature_parts.iter().map(|p| p.value).sum();
        j.damping = j.damping_parts.iter().map(|p| p.value).sum();
    }
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

/// Runs mj_forward at the keyframe (or qpos0) and records what static rules need.
pub fn key_state(m: &MjModel, key: Option<usize>, keys: &[String]) -> KeyState {
    let mut d = MjData::new(m);
    if let Some(k) = key {
        let _ = d.reset_keyframe(k);
    }
    d.forward();
    let nv = mj::raw(m).nv.max(0) as usize;
    let full = mj::full_mass_matrix(&d);
    let m_diag = (0..nv).map(|i| full[i * nv + i]).collect();
    KeyState {
        key,
        key_name: key.and_then(|k| keys.get(k).cloned()),
        qpos: d.qpos().to_vec(),
        ctrl: d.ctrl().to_vec(),
        m_diag,
        geom_xpos: d.geom_xpos().to_vec(),
        geom_xmat: d.geom_xmat().to_vec(),
        body_xpos: d.xpos().to_vec(),
    }
}
