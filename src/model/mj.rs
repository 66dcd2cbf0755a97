//! The MuJoCo boundary: what modellint needs from mjModel/mjData beyond mujoco-rs's own
//! length-checked accessors (`m.dof_armature()`, `d.qpos_mut()`, …, used directly everywhere
//! else). Every `unsafe` block of the crate that touches MuJoCo lives here, each with its
//! `// SAFETY:` argument; the functions below are safe to call with any arguments.

use mujoco_rs::mujoco_c as c;
use mujoco_rs::prelude::*;
use mujoco_rs::wrappers::mj_model::traits::ModelType;

/// The compiled model's C struct, read-only: sizes (`nv`, `nu`, …) and options (`opt`). Its
/// array fields are raw pointers; read arrays through mujoco-rs's accessors instead.
pub fn raw(m: &MjModel) -> &c::mjModel {
    m.ffi()
}

/// Name of object `id` given the model's name-address array for its kind (e.g.
/// `m.name_jntadr()`); "" when unnamed or out of range.
pub fn name_at(m: &MjModel, adr: &[i32], id: usize) -> String {
    let names = m.names();
    let Some(&start) = adr.get(id) else { return String::new() };
    let start = start.max(0) as usize;
    if start >= names.len() {
        return String::new();
    }
    let end = names[start..].iter().position(|&b| b == 0).map(|p| start + p).unwrap_or(names.len());
    let bytes: Vec<u8> = names[start..end].iter().map(|&b| b as u8).collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

/// Sets DoF `dof`'s armature to `value`, keeping `dof_M0` (the compiled diagonal inertia at
/// qpos0, which MuJoCo uses directly for "simple" DoFs — a single body on a hinge) consistent:
/// writing `dof_armature` alone changes nothing on such a DoF.
pub fn set_armature(m: &mut MjModel, dof: usize, value: f64) {
    let Some(arm) = m.dof_armature_mut().get_mut(dof) else { return };
    let delta = value - *arm;
    *arm = value;
    if let Some(m0) = m.dof_m0_mut().get_mut(dof) {
        *m0 += delta;
    }
}

/// `actuator_gainprm` (nactuator × 10, row-major), writable.
pub fn actuator_gainprm_mut(m: &mut MjModel) -> &mut [f64] {
    // SAFETY: mujoco-rs marks this accessor unsafe because some model arrays hold ids and
    // addresses MuJoCo indexes with. gainprm holds only floating-point coefficients that MuJoCo
    // multiplies with (for every gain type, including dcmotor's resistance and motor constant),
    // never uses as an index or size, so any value written keeps every access in bounds. The
    // slice borrows `m` exclusively and has the length mujoco-rs computes from `nactuator`.
    unsafe { m.actuator_gainprm_mut() }.as_flattened_mut()
}

/// Writes actuator `a`'s `gainprm[0]`, `biasprm[1]` and `biasprm[2]` (a position servo's kp,
/// −kp, −kd). Nothing when `a` is out of range.
pub fn set_model_gains(m: &mut MjModel, a: usize, g0: f64, b1: f64, b2: f64) {
    if let Some(g) = actuator_gainprm_mut(m).get_mut(10 * a) {
        *g = g0;
    }
    if let Some(row) = m.actuator_biasprm_mut().get_mut(a) {
        row[1] = b1;
        row[2] = b2;
    }
}

/// [`set_model_gains`] on the model `d` simulates, between steps.
pub fn set_actuator_gains(d: &mut MjData<&mut MjModel>, a: usize, g0: f64, b1: f64, b2: f64) {
    // SAFETY: `model_mut` is unsafe because a changed model could stop matching the data's
    // buffers. Only gainprm/biasprm values change here (see `actuator_gainprm_mut`): no size,
    // count, address or id, so the data's buffers stay valid for the model. The data holds the
    // only (mutable) borrow of the model, so nothing else observes the write.
    set_model_gains(unsafe { d.model_mut() }, a, g0, b1, b2);
}

/// Solved force of every scalar constraint row of the data's last `mj_step` / `mj_forward`, with
/// its type and object id (`efc_force`, `efc_type`, `efc_id`; `nefc` rows).
///
/// Crate-private on purpose: `efc_force` is written by the constraint solver only, so reading it
/// is defined only when the last pipeline call on `d` ran the solver. Every `MjData` modellint
/// creates is advanced by `MjData::step`/`forward` (full pipeline) or reset (`nefc` = 0), and no
/// public function of the crate hands out a data that ran a partial stage.
pub(crate) fn constraint_forces<M: ModelType>(d: &MjData<M>) -> Vec<(i32, i32, f64)> {
    // SAFETY: see above: the last pipeline call ran the solver, which writes `efc_force` for all
    // `nefc` rows; mujoco-rs bounds the slice by `nefc`.
    let force = unsafe { d.efc_force() };
    d.efc_type()
        .iter()
        .zip(d.efc_id())
        .zip(force)
        .map(|((&t, &id), &f)| (t as i32, id, f))
        .collect()
}

/// Dense joint-space inertia matrix (nv × nv, row-major) at the data's current state.
pub fn full_mass_matrix<M: ModelType>(d: &MjData<M>) -> Vec<f64> {
    let nv = raw(d.model()).nv.max(0) as usize;
    let mut out = vec![0.0; nv * nv];
    if nv > 0 && d.full_m(&mut out).is_err() {
        out.fill(f64::NAN);
    }
    out
}

unsafe extern "C" fn quiet_warning(_msg: *const std::os::raw::c_char) {}

/// MuJoCo prints warnings to stdout/stderr by default; modellint reads them from
/// `mjData.warning` instead and reports them as findings, so silence the printing.
pub fn silence_warnings() {
    // SAFETY: a plain function-pointer store into MuJoCo's global hook, done before any
    // simulation starts (called from the CLI entry point and probe/replay setup); the hook
    // ignores its argument.
    unsafe {
        c::mju_user_warning = Some(quiet_warning);
    }
}

/// Signed distance between two geoms at the data's current state (negative: penetration),
/// capped at `distmax`; NaN for a geom id out of range.
pub fn geom_distance<M: ModelType>(d: &mut MjData<M>, g1: usize, g2: usize, distmax: f64) -> f64 {
    let mut fromto = [0.0f64; 6];
    d.try_geom_distance(g1, g2, distmax, Some(&mut fromto)).unwrap_or(f64::NAN)
}

/// Normal force of contact `i` of the data's current contact list (N, ≥ 0); 0 when there is no
/// such contact.
pub fn contact_normal_force<M: ModelType>(d: &MjData<M>, i: usize) -> f64 {
    d.try_contact_force(i).map(|f| f[0]).unwrap_or(0.0)
}

/// Room for MuJoCo's load error message: mujoco-rs gives `mj_loadXML` 100 bytes, which cuts
/// "Element name 'arm_left_shoulder_pitch_pos', id 0" after a few letters of the name.
const LOAD_ERROR_LEN: usize = 1000;

/// `short` (mujoco-rs's load error, its MuJoCo message cut at 99 bytes) with MuJoCo's whole
/// message: the load of `path` repeated with [`LOAD_ERROR_LEN`] bytes of room. `short` as it
/// is when the repeat gives no longer message that starts the same way.
pub fn full_load_error(path: &std::path::Path, short: &str) -> String {
    let Some(cpath) = path.to_str().and_then(|p| std::ffi::CString::new(p).ok()) else {
        return short.to_string();
    };
    let mut buf = vec![0 as std::os::raw::c_char; LOAD_ERROR_LEN];
    // SAFETY: `cpath` is a NUL-terminated string that outlives the call, the VFS pointer may be
    // null, and `buf` holds `LOAD_ERROR_LEN` writable bytes, the size passed; a model MuJoCo
    // returns is owned here and freed once.
    let m = unsafe {
        c::mj_loadXML(cpath.as_ptr(), std::ptr::null(), buf.as_mut_ptr(), LOAD_ERROR_LEN as i32)
    };
    if !m.is_null() {
        // SAFETY: `m` was returned by mj_loadXML above and is not used after this.
        unsafe { c::mj_deleteModel(m) };
    }
    let bytes: Vec<u8> = buf.iter().take_while(|&&b| b != 0).map(|&b| b as u8).collect();
    let full = String::from_utf8_lossy(&bytes);
    let head: String = full.chars().take(30).collect();
    match short.find(head.as_str()) {
        Some(k) if !head.is_empty() && full.starts_with(&short[k..]) => {
            format!("{}{full}", &short[..k])
        }
        _ => short.to_string(),
    }
}

/// Replaces every joint of spec body `body` (a base's slides and ball) by one free joint.
pub fn replace_joints_by_free(
    body: &mut mujoco_rs::wrappers::mj_editing::MjsBody,
) -> Result<(), String> {
    let joints: Vec<*mut c::mjsElement> =
        body.joint_iter_mut(false).map(|j| j.element_mut_pointer()).collect();
    for e in joints {
        // SAFETY: `e` points at a joint element of the live spec that owns `body` (collected
        // above, no handle to it is kept), and each is deleted once; `mjs_getSpec` returns that
        // spec for any element of it.
        let failed = unsafe { c::mjs_delete(c::mjs_getSpec(e.cast_const()), e) } != 0;
        if failed {
            return Err("MuJoCo would not remove the base's slide and ball joints".into());
        }
    }
    body.add_free_joint();
    Ok(())
}

/// Adds a static floor plane named `name` at height `z` to spec body `world`, touching every
/// geom whose contype or conaffinity shares a bit with `bits`. Its friction is zero and its
/// condim 1, the least MuJoCo allows: MuJoCo takes the larger of the two geoms' values, so
/// every contact with it has the robot geom's own condim and friction.
pub fn add_floor(
    world: &mut mujoco_rs::wrappers::mj_editing::MjsBody,
    name: &str,
    z: f64,
    bits: i32,
) {
    let bits = if bits == 0 { 1 } else { bits };
    world
        .add_geom()
        .with_name(name)
        .with_type(MjtGeomBase::mjGEOM_PLANE)
        .with_pos([0.0, 0.0, z])
        .with_size([0.0, 0.0, 1.0])
        .with_contype(bits)
        .with_conaffinity(bits)
        .with_condim(1)
        .with_friction([0.0, 0.0, 0.0]);
}

/// Body `body`'s world position and orientation quaternion at keyframe `key` of `m` (the 7
/// numbers of a free joint's qpos); `None` when out of range.
pub fn body_pose_at_key(m: &MjModel, key: usize, body: usize) -> Option<[f64; 7]> {
    let mut d = MjData::new(m);
    d.reset_keyframe(key).ok()?;
    d.forward();
    let p = d.xpos().get(body)?;
    let q = d.xquat().get(body)?;
    Some([p[0], p[1], p[2], q[0], q[1], q[2], q[3]])
}

/// Writes `values` into keyframe `key`'s qpos from address `adr`; nothing out of range.
pub fn set_key_qpos(m: &mut MjModel, key: usize, adr: usize, values: &[f64]) {
    let nq = raw(m).nq.max(0) as usize;
    let start = key * nq + adr;
    if adr + values.len() <= nq
        && let Some(dst) = m.key_qpos_mut().get_mut(start..start + values.len())
    {
        dst.copy_from_slice(values);
    }
}

/// Adds to `spec` an equality that holds joint `joint` at its qpos0 (`<equality><joint
/// joint1=…/>`: with no second joint and MuJoCo's default polycoef 0 1 0 0 0, q − q0 = 0).
pub fn hold_joint(spec: &mut MjSpec, joint: &str) {
    spec.add_equality()
        .with_type(MjtEq::mjEQ_JOINT)
        .with_objtype(MjtObjBase::mjOBJ_JOINT)
        .with_name1(joint);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hinge with armature and a range, a position servo on it.
    const XML: &str = r#"<mujoco><option gravity="0 0 0"/><worldbody><body name="b">
        <joint name="j" type="hinge" axis="0 1 0" armature="0.1" limited="true" range="-0.1 0.1"/>
        <geom type="sphere" size="0.1" pos="0.3 0 0" mass="1"/></body></worldbody>
        <actuator><position name="a" joint="j" kp="10" kv="1"/></actuator></mujoco>"#;

    fn model() -> MjModel {
        MjModel::from_xml_string(XML).expect("compiles")
    }

    #[test]
    fn names_by_id_and_out_of_range() {
        let m = model();
        assert_eq!(name_at(&m, m.name_jntadr(), 0), "j");
        assert_eq!(name_at(&m, m.name_actuatoradr(), 0), "a");
        assert_eq!(name_at(&m, m.name_bodyadr(), 1), "b");
        assert_eq!(name_at(&m, m.name_jntadr(), 1), "");
        assert_eq!(name_at(&m, &[i32::MAX], 0), "");
    }

    #[test]
    fn armature_moves_dof_m0_with_it() {
        let mut m = model();
        let (a0, m00) = (m.dof_armature()[0], m.dof_m0()[0]);
        set_armature(&mut m, 0, 0.5);
        assert_eq!(m.dof_armature()[0], 0.5);
        assert!((m.dof_m0()[0] - (m00 + 0.5 - a0)).abs() < 1e-12);
        set_armature(&mut m, 9, 1.0); // out of range: nothing
        assert_eq!(m.dof_armature(), &[0.5]);
    }

    #[test]
    fn gains_written_through_the_data_drive_the_next_step() {
        let mut m = model();
        let mut d = MjData::new(&mut m);
        d.ctrl_mut()[0] = 0.05;
        d.forward();
        assert!((d.actuator_force()[0] - 10.0 * 0.05).abs() < 1e-9);
        set_actuator_gains(&mut d, 0, 40.0, -40.0, -2.0);
        set_actuator_gains(&mut d, 3, 1.0, 1.0, 1.0); // no such actuator: nothing
        assert_eq!(d.model().actuator_gainprm()[0][0], 40.0);
        assert_eq!(&d.model().actuator_biasprm()[0][..3], &[0.0, -40.0, -2.0]);
        d.forward();
        assert!((d.actuator_force()[0] - 40.0 * 0.05).abs() < 1e-9);
    }

    #[test]
    fn constraint_forces_show_the_joint_limit_row() {
        let m = model();
        let mut d = MjData::new(&m);
        assert!(constraint_forces(&d).is_empty());
        d.ctrl_mut()[0] = 1.0; // far beyond the 0.1 rad stop
        let mut hit = false;
        for _ in 0..500 {
            d.step();
            hit |= constraint_forces(&d).iter().any(|&(ty, id, f)| {
                ty == c::mjtConstraint::mjCNSTR_LIMIT_JOINT as i32 && id == 0 && f.abs() > 1e-9
            });
        }
        assert!(hit, "the servo never pressed the joint into its stop");
    }

    #[test]
    fn distance_and_contact_queries_reject_bad_ids() {
        let m = model();
        let mut d = MjData::new(&m);
        d.forward();
        assert!(geom_distance(&mut d, 0, 5, 1.0).is_nan());
        assert_eq!(contact_normal_force(&d, 0), 0.0);
        assert_eq!(full_mass_matrix(&d).len(), 1);
    }

    #[test]
    fn load_errors_keep_mujocos_whole_message() {
        let dir = std::env::temp_dir().join(format!("ml-loaderr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("m.xml");
        let xml = r#"<mujoco><worldbody><body><joint name="j"/><geom size="0.1"/></body></worldbody>
<sensor><jointpos name="a_sensor_with_a_rather_long_name_to_cut" joint="no_such_joint_anywhere"/></sensor></mujoco>"#;
        std::fs::write(&f, xml).unwrap();
        let short = MjModel::from_xml(&f).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(!short.contains("a_sensor_with_a_rather_long_name_to_cut"), "{short}");
        let full = full_load_error(&f, &short);
        assert!(full.contains("Element name 'a_sensor_with_a_rather_long_name_to_cut'"), "{full}");
        assert!(full.starts_with(&short[..short.len().min(20)]), "{full}");
        // A message that does not come from this load is kept as it is.
        assert_eq!(full_load_error(&f, "something else"), "something else");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
