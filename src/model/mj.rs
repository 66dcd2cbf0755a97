//! Thin, safe accessors over MuJoCo's compiled model and data arrays (mujoco-rs FFI structs).
//! All unsafe pointer reads of mjModel/mjData live here.

use mujoco_rs::mujoco_c as c;
use mujoco_rs::prelude::*;

/// A view of `n` elements starting at `ptr` (empty when the pointer is null or n == 0).
pub fn slice<'a, T>(ptr: *const T, n: usize) -> &'a [T] {
    if ptr.is_null() || n == 0 {
        &[]
    } else {
        // SAFETY: MuJoCo allocates every model/data array with the documented length and keeps it
        // alive as long as the model/data; callers pass those lengths.
        unsafe { std::slice::from_raw_parts(ptr, n) }
    }
}

pub fn slice_mut<'a, T>(ptr: *mut T, n: usize) -> &'a mut [T] {
    if ptr.is_null() || n == 0 {
        &mut []
    } else {
        // SAFETY: as above; the caller holds the only mutable handle to the model/data.
        unsafe { std::slice::from_raw_parts_mut(ptr, n) }
    }
}

/// Name of object `id` given the model's `name_*adr` array for its kind ("" when unnamed).
pub fn name_at(m: &MjModel, adr: *const i32, n: usize, id: usize) -> String {
    let r = raw(m);
    let adrs = slice(adr, n);
    let names = slice(r.names as *const u8, r.nnames as usize);
    let Some(&start) = adrs.get(id) else { return String::new() };
    let start = start.max(0) as usize;
    if start >= names.len() {
        return String::new();
    }
    let end = names[start..].iter().position(|&b| b == 0).map(|p| start + p).unwrap_or(names.len());
    String::from_utf8_lossy(&names[start..end]).into_owned()
}

pub fn raw(m: &MjModel) -> &c::mjModel {
    m.ffi()
}

/// Mutable raw model for fitting (parameters written in place between simulations).
pub fn raw_mut(m: &mut MjModel) -> &mut c::mjModel {
    // SAFETY: exclusive borrow of the model; only numeric parameter arrays are written.
    unsafe { m.ffi_mut() }
}

/// Sets DoF `dof`'s armature to `value`, keeping `dof_M0` (the compiled diagonal inertia at
/// qpos0, which MuJoCo uses directly for "simple" DoFs — a single body on a hinge) consistent:
/// writing `dof_armature` alone changes nothing on such a DoF.
pub fn set_armature(m: &mut MjModel, dof: usize, value: f64) {
    let r = raw_mut(m);
    let nv = r.nv as usize;
    if dof >= nv {
        return;
    }
    let arm = slice_mut(r.dof_armature, nv);
    let delta = value - arm[dof];
    arm[dof] = value;
    let m0 = slice_mut(r.dof_M0, nv);
    m0[dof] += delta;
}

pub fn data_raw<'a>(d: &'a MjData<&MjModel>) -> &'a c::mjData {
    d.ffi()
}

pub fn data_raw_mut<'a>(d: &'a mut MjData<&MjModel>) -> &'a mut c::mjData {
    // SAFETY: exclusive borrow of the data.
    unsafe { d.ffi_mut() }
}

/// Dense joint-space inertia matrix (nv × nv, row-major) at the data's current state.
pub fn full_mass_matrix(m: &MjModel, d: &MjData<&MjModel>) -> Vec<f64> {
    let nv = raw(m).nv as usize;
    let mut out = vec![0.0; nv * nv];
    if nv > 0 {
        // SAFETY: dst has nv*nv entries as mj_fullM requires; qM is current after mj_forward.
        unsafe { c::mj_fullM(raw(m), d.ffi(), out.as_mut_ptr()) };
    }
    out
}

unsafe extern "C" fn quiet_warning(_msg: *const std::os::raw::c_char) {}

/// MuJoCo prints warnings to stdout/stderr by default; modellint reads them from
/// `mjData.warning` instead and reports them as findings, so silence the printing.
pub fn silence_warnings() {
    // SAFETY: a plain function-pointer store into MuJoCo's global hook, done before any
    // simulation starts (called from the CLI entry point and probe/replay setup).
    unsafe {
        c::mju_user_warning = Some(quiet_warning);
    }
}

/// Signed distance between two geoms at the data's current state (negative: penetration),
/// capped at `distmax`.
pub fn geom_distance(
    m: &MjModel,
    d: &mut MjData<&MjModel>,
    g1: usize,
    g2: usize,
    distmax: f64,
) -> f64 {
    let mut fromto = [0.0f64; 6];
    // SAFETY: valid model/data pair, geom ids checked by the caller against ngeom, fromto has 6.
    unsafe { c::mj_geomDistance(raw(m), d.ffi_mut(), g1 as i32, g2 as i32, distmax, &mut fromto) }
}

/// Normal force of contact `i` of the data's current contact list (N, ≥ 0).
pub fn contact_normal_force(m: &MjModel, d: &MjData<&MjModel>, i: usize) -> f64 {
    let mut res = [0.0f64; 6];
    if i >= d.ffi().ncon.max(0) as usize {
        return 0.0;
    }
    // SAFETY: i < ncon; res has 6 entries as mj_contactForce requires.
    unsafe { c::mj_contactForce(raw(m), d.ffi(), i as i32, &mut res) };
    res[0]
}
