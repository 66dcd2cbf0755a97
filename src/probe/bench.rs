//! The test bench every probe runs on: the compiled model put in a known state (keyframe,
//! targets held), with optional isolation of one joint.
//!
//! A bench that changes nothing (no isolation, contacts and gravity on) simulates the robot's
//! own model directly. One that changes armature (and with it `dof_M0`, see
//! [`mj::set_armature`]) or option flags works on a scratch copy kept
//! per thread and reset from the robot's model each time, instead of a fresh copy per probe: a
//! mesh-heavy model is tens of megabytes (mostly mesh BVHs), and copying it for every probe cost
//! more than the probes' own simulation steps.

use std::cell::RefCell;
use std::ops::Deref;

use mujoco_rs::prelude::*;

use crate::model::{Robot, mj};

/// How to prepare the copy.
#[derive(Debug, Clone, Copy, Default)]
pub struct Setup {
    /// Freeze every DoF except this one (armature 1e7 on the others, reset each step): the
    /// probed joint then sees exactly its own row of the mass matrix, as on a fixed test stand.
    pub isolate_dof: Option<usize>,
    /// Freeze only the floating base (free joints), as if the robot hung on a stand.
    pub pin_base: bool,
    pub no_contact: bool,
    pub no_gravity: bool,
}

pub const FROZEN_ARMATURE: f64 = 1e7;

/// The model a bench simulates: the robot's own (read only) or this thread's scratch copy.
pub enum BenchModel<'a> {
    Shared(&'a MjModel),
    Scratch(Option<MjModel>, u64),
}

impl Deref for BenchModel<'_> {
    type Target = MjModel;
    fn deref(&self) -> &MjModel {
        match self {
            BenchModel::Shared(m) => m,
            BenchModel::Scratch(Some(m), _) => m,
            BenchModel::Scratch(None, _) => unreachable!("scratch model is only taken in drop"),
        }
    }
}

impl Drop for BenchModel<'_> {
    fn drop(&mut self) {
        if let BenchModel::Scratch(m, source) = self
            && let Some(m) = m.take()
        {
            SCRATCH.with(|s| *s.borrow_mut() = Some((*source, m)));
        }
    }
}

thread_local! {
    /// (uid of the robot whose model it was copied from, copy). The robot's model is never
    /// changed after loading, so resetting what a bench changes (armature, option flags) makes
    /// the copy equal to it again.
    static SCRATCH: RefCell<Option<(u64, MjModel)>> = const { RefCell::new(None) };
}

/// A copy of `robot.mj` with its armature and option flags as in the robot's model: this
/// thread's scratch copy when it was made from the same model, else a fresh copy.
fn scratch(robot: &Robot) -> (MjModel, u64) {
    let source = robot.uid;
    let reuse = SCRATCH.with(|s| match s.borrow_mut().take() {
        Some((src, m)) if src == source => Some(m),
        _ => None,
    });
    let mut m = match reuse {
        Some(m) => m,
        None => return (robot.mj.clone(), source),
    };
    let orig = &robot.mj;
    m.dof_armature_mut().copy_from_slice(orig.dof_armature());
    m.dof_m0_mut().copy_from_slice(orig.dof_m0());
    m.opt_mut().disableflags = orig.opt().disableflags;
    (m, source)
}

pub struct Bench<'a> {
    pub m: BenchModel<'a>,
    frozen: Vec<(usize, f64)>, // (qpos index, value) to hold
    frozen_dofs: Vec<usize>,
}

impl<'a> Bench<'a> {
    pub fn new(robot: &'a Robot, s: Setup) -> Option<Bench<'a>> {
        let changes = s.isolate_dof.is_some() || s.pin_base || s.no_contact || s.no_gravity;
        if !changes {
            return Some(Bench {
                m: BenchModel::Shared(&robot.mj),
                frozen: Vec::new(),
                frozen_dofs: Vec::new(),
            });
        }
        let (mut m, source) = scratch(robot);
        let mut frozen_dofs: Vec<usize> = Vec::new();
        let mut frozen = Vec::new();
        for j in &robot.joints {
            let ndof = match j.jtype {
                crate::model::JointType::Free => 6,
                crate::model::JointType::Ball => 3,
                _ => 1,
            };
            let nq = match j.jtype {
                crate::model::JointType::Free => 7,
                crate::model::JointType::Ball => 4,
                _ => 1,
            };
            let freeze = match s.isolate_dof {
                Some(d) => !(j.dofadr <= d && d < j.dofadr + ndof),
                None => s.pin_base && j.jtype == crate::model::JointType::Free,
            };
            if freeze {
                frozen_dofs.extend(j.dofadr..j.dofadr + ndof);
                for k in 0..nq {
                    frozen.push((
                        j.qposadr + k,
                        robot.key.qpos.get(j.qposadr + k).copied().unwrap_or(0.0),
                    ));
                }
            }
        }
        for &d in &frozen_dofs {
            mj::set_armature(&mut m, d, FROZEN_ARMATURE);
        }
        if s.no_contact {
            m.opt_mut().disableflags |= 1 << 4;
        }
        if s.no_gravity {
            m.opt_mut().disableflags |= 1 << 7;
        }
        Some(Bench { m: BenchModel::Scratch(Some(m), source), frozen, frozen_dofs })
    }

    /// Fresh data at the robot's standing keyframe (or qpos0), ctrl = keyframe ctrl.
    pub fn data(&self, robot: &Robot) -> MjData<&MjModel> {
        let mut d = MjData::new(&*self.m);
        if let Some(k) = robot.key.key {
            let _ = d.reset_keyframe(k);
        }
        // Pre-fill actuator delay buffers with the held command so a delayed actuator does not
        // see a zero target for its first `delay` seconds.
        let ctrl = d.ctrl().to_vec();
        let hadr = self.m.actuator_historyadr().to_vec();
        for (i, &c) in ctrl.iter().enumerate() {
            if hadr.get(i).copied().unwrap_or(-1) >= 0 {
                let _ = d.init_ctrl_history(i, None, &[c]);
            }
        }
        d.forward();
        d
    }

    /// One physics step, then re-impose the frozen coordinates.
    pub fn step(&self, d: &mut MjData<&MjModel>) {
        d.step();
        let qpos = d.qpos_mut();
        for &(i, v) in &self.frozen {
            qpos[i] = v;
        }
        let qvel = d.qvel_mut();
        for &k in &self.frozen_dofs {
            qvel[k] = 0.0;
        }
    }

    pub fn dt(&self) -> f64 {
        mj::raw(&self.m).opt.timestep
    }
}

/// Total number of MuJoCo warnings raised so far (bad qacc/qvel/qpos, full contact buffers, …).
pub fn warnings(d: &MjData<&MjModel>) -> i32 {
    d.ffi().warning.iter().map(|w| w.number).sum()
}

pub fn qpos(d: &MjData<&MjModel>, i: usize) -> f64 {
    d.qpos().get(i).copied().unwrap_or(f64::NAN)
}

pub fn qvel(d: &MjData<&MjModel>, i: usize) -> f64 {
    d.qvel().get(i).copied().unwrap_or(f64::NAN)
}

pub fn set_ctrl(d: &mut MjData<&MjModel>, a: usize, v: f64) {
    if let Some(c) = d.ctrl_mut().get_mut(a) {
        *c = v;
    }
}

/// Holds a filtered actuator's activation at `v` (its `dyntype` filter or filterexact: its force
/// acts on the activation, which follows ctrl with the time constant `dynprm[0]`), so a step
/// written to ctrl and to the activation is the servo loop's own step, not one the filter
/// smooths first. Any other actuator: nothing.
pub fn set_filtered_act(d: &mut MjData<&MjModel>, a: usize, v: f64) {
    use mujoco_rs::mujoco_c::mjtDyn;
    let (dyntype, adr, num) = {
        let m = d.model();
        (
            m.actuator_dyntype().get(a).copied(),
            m.actuator_actadr().get(a).copied().unwrap_or(-1),
            m.actuator_actnum().get(a).copied().unwrap_or(0),
        )
    };
    if !matches!(dyntype, Some(mjtDyn::mjDYN_FILTER | mjtDyn::mjDYN_FILTEREXACT)) || adr < 0 {
        return;
    }
    // The filter's state is the actuator's last activation.
    let i = usize::try_from(adr + num.max(1) - 1).unwrap_or(usize::MAX);
    if let Some(x) = d.act_mut().get_mut(i) {
        *x = v;
    }
}

pub fn ctrl(d: &MjData<&MjModel>, a: usize) -> f64 {
    d.ctrl().get(a).copied().unwrap_or(f64::NAN)
}
