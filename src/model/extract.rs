//! The compiled MjModel read into modellint's tables ([`Robot`]): joints, actuators (kinds from
//! gain/bias types), bodies, geoms, keyframes, equalities, and where each joint's effective
//! armature and damping come from ([`Part`]s of joint, actuators, tendons, back-EMF).

use std::path::Path;

use mujoco_rs::prelude::*;

use super::mjcf::SourceIndex;
use super::source::XNode;
use super::*;

pub(super) fn extract(
    path: &Path,
    format: Format,
    tree: XNode,
    src: SourceIndex,
    mj: MjModel,
) -> Robot {
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
            let servo = (gt[i] == 0 && bt[i] == 1 && g[0] > 0.0 && b[1] < 0.0).then(|| Servo {
                kp: -b[1],
                kv: -b[2],
                scale: g[0] / -b[1],
                offset: b[0] / -b[1],
            });
            Actuator {
                servo,
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
    let bw = mj.body_weldid();
    let bodies = (0..nbody)
        .map(|i| Body {
            id: i,
            name: mj::name_at(&mj, mj.name_bodyadr(), i),
            parent: bp_[i].max(0) as usize,
            mass: bm[i],
            weld: bw.get(i).map_or(i, |&w| w.max(0) as usize),
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
    let gpr = mj.geom_priority();
    let gsm = mj.geom_solmix();
    let gsr = mj.geom_solref();
    let gsi = mj.geom_solimp();
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
            priority: gpr[i],
            solmix: gsm[i],
            solref: [gsr[i][0], gsr[i][1]],
            solimp: [gsi[i][0], gsi[i][1], gsi[i][2], gsi[i][3], gsi[i][4]],
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
    let (pairs, excludes) = super::contact::read_pairs(&mj);
    let opt = Options {
        timestep: r.opt.timestep,
        integrator: r.opt.integrator,
        gravity: r.opt.gravity,
        disableflags: r.opt.disableflags,
    };
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
        pairs,
        excludes,
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

/// Runs mj_forward at the keyframe (or qpos0) and records what static rules need.
pub fn key_state(m: &MjModel, key: Option<usize>, keys: &[String]) -> KeyState {
    let mut d = MjData::new(m);
    if let Some(k) = key {
        let _ = d.reset_keyframe(k);
    }
    state_of(m, d, key, keys)
}

/// As [`key_state`] at the pose `qpos` (with no keyframe): the model's qpos0 with `clamped`
/// joints moved into their ranges. `qpos` of the wrong length leaves qpos0.
pub fn pose_state(m: &MjModel, qpos: &[f64], clamped: usize) -> KeyState {
    let mut d = MjData::new(m);
    if d.qpos().len() == qpos.len() {
        d.qpos_mut().copy_from_slice(qpos);
    }
    KeyState { clamped, ..state_of(m, d, None, &[]) }
}

fn state_of(m: &MjModel, mut d: MjData<&MjModel>, key: Option<usize>, keys: &[String]) -> KeyState {
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
        joint_xanchor: d.xanchor().to_vec(),
        joint_xaxis: d.xaxis().to_vec(),
        clamped: 0,
    }
}
