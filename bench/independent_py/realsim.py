#!/usr/bin/env python3
"""Independent "real robot" simulator + logger for the modellint fit tryout.

usage: realsim.py CASE_NAME...   (cases defined in cases.py)

Writes $INDEP_OUT/data/CASE/{nominal.xml, episodes/ep_0N.csv, truth.json} (INDEP_OUT defaults
to out/ beside this file). Written for a new-user tryout (2026-11-26) from
docs/recording-format.md and the independent_arm2 README only, without reading the fit's code;
it shares nothing with `modellint synth` or the replay.
The robot = the nominal MJCF compiled by MuJoCo, then concealed effects written into the
MjModel arrays (dof_damping, dof_armature, dof_frictionloss, jnt_stiffness + qpos_spring=key,
actuator gainprm/biasprm), plus an own command queue for action delay and an encoder offset.
Body effects (`bodies`) are built through MuJoCo's own model editor before compiling: a payload
is a child body with a sphere geom of its mass (MuJoCo composes it), a centre-of-mass shift moves
every geom of the body (the whole mass distribution translated).
Logging: 100 Hz controller (or the model's `ctrl_hz`) with phase control_t0_s, async recorder ~rate_hz with jitter,
q = quantise(q_true + offset + N(0, q_noise)), qd + N(0, qd_noise), drops, 2 s settle.
"""
import json, math, os, sys
import numpy as np
import mujoco

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from cases import CASES, MODELS  # noqa: E402
from reclog import CTRL_HZ, SETTLE_S, make_commands, record  # noqa: E402
from simcommon import case_setup, episode_file, episode_plan, ticks  # noqa: E402


def conceal(m, eff, key_qpos):
    """Apply concealed effects to MjModel m in place; return resolved [nominal, real] per joint."""
    resolved = {}
    for jname, e in eff.get("joints", {}).items():
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, jname)
        assert jid >= 0, jname
        dof = m.jnt_dofadr[jid]
        qadr = m.jnt_qposadr[jid]
        r = {}
        if "damping" in e:
            r["damping"] = [float(m.dof_damping[dof]), None]
            m.dof_damping[dof] = e["damping"]
            r["damping"][1] = float(m.dof_damping[dof])
        if "armature" in e:
            r["armature"] = [float(m.dof_armature[dof]), None]
            m.dof_armature[dof] = e["armature"]
            r["armature"][1] = float(m.dof_armature[dof])
        if "frictionloss" in e:
            r["frictionloss"] = [float(m.dof_frictionloss[dof]), None]
            m.dof_frictionloss[dof] = e["frictionloss"]
            r["frictionloss"][1] = float(m.dof_frictionloss[dof])
        if "stiffness" in e:
            r["stiffness"] = [float(m.jnt_stiffness[jid]), None]
            m.jnt_stiffness[jid] = e["stiffness"]
            m.qpos_spring[qadr] = key_qpos[qadr]
            r["stiffness"][1] = float(m.jnt_stiffness[jid])
            r["springref"] = float(m.qpos_spring[qadr])
        if "kp_scale" in e or "kd_scale" in e:
            aid = [a for a in range(m.nu) if m.actuator_trnid[a, 0] == jid]
            assert len(aid) == 1
            a = aid[0]
            kp0 = float(m.actuator_gainprm[a, 0]); kv0 = float(-m.actuator_biasprm[a, 2])
            sp = e.get("kp_scale", 1.0); sd = e.get("kd_scale", 1.0)
            m.actuator_gainprm[a, 0] *= sp
            m.actuator_biasprm[a, 1] *= sp
            m.actuator_biasprm[a, 2] *= sd
            r["actuator.kp"] = [kp0, float(m.actuator_gainprm[a, 0])]
            r["actuator.kv"] = [kv0, float(-m.actuator_biasprm[a, 2])]
            assert abs(m.actuator_gainprm[a, 0] + m.actuator_biasprm[a, 1]) < 1e-9
        if "offset" in e:
            r["position_offset"] = [0.0, e["offset"]]
        if "delay" in e:
            r["delay_s"] = [0.0, e["delay"]]
        resolved[jname] = r
    return resolved


def real_model(src, eff):
    """The robot's MjModel: the nominal MJCF with the concealed body effects built in by
    MjSpec (so MuJoCo's compiler, not this script, combines masses and inertias). Returns
    (model, resolved body truth)."""
    bodies = eff.get("bodies", {})
    if not bodies:
        return mujoco.MjModel.from_xml_path(src), {}
    nominal = mujoco.MjModel.from_xml_path(src)
    spec = mujoco.MjSpec.from_file(src)
    resolved = {}
    for bname, e in bodies.items():
        b = spec.body(bname)
        assert b is not None, bname
        bid = mujoco.mj_name2id(nominal, mujoco.mjtObj.mjOBJ_BODY, bname)
        jid = [j for j in range(nominal.njnt) if nominal.jnt_bodyid[j] == bid]
        r = {"nominal_mass": float(nominal.body_mass[bid]),
             "nominal_com": [float(x) for x in nominal.body_ipos[bid]],
             "joint_axis": [float(x) for x in nominal.jnt_axis[jid[0]]] if jid else None,
             "joint": mujoco.mj_id2name(nominal, mujoco.mjtObj.mjOBJ_JOINT, jid[0]) if jid else None}
        if "payload" in e:
            pl = e["payload"]
            c = b.add_body(name=f"{bname}_payload", pos=pl["pos"])
            c.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[pl.get("radius", 0.03), 0, 0],
                       mass=pl["mass"], contype=0, conaffinity=0)
            r["payload"] = {"mass": pl["mass"], "pos": list(pl["pos"])}
        if "inertia_scale" in e:
            # The body's own mass properties made explicit, its principal moments scaled
            # (mass and centre of mass kept): MuJoCo's compiler checks the result is a body.
            k = e["inertia_scale"]
            b.explicitinertial = True
            b.mass = float(nominal.body_mass[bid])
            b.ipos = [float(x) for x in nominal.body_ipos[bid]]
            b.iquat = [float(x) for x in nominal.body_iquat[bid]]
            b.inertia = [float(nominal.body_inertia[bid][i]) * k[i] for i in range(3)]
            r["inertia_scale"] = list(k)
            r["nominal_inertia"] = [float(x) for x in nominal.body_inertia[bid]]
            r["nominal_iquat"] = [float(x) for x in nominal.body_iquat[bid]]
        if "com_shift" in e:
            d = e["com_shift"]
            for g in b.geoms:
                if not any(math.isnan(x) for x in g.fromto):
                    g.fromto = [g.fromto[k] + d[k % 3] for k in range(6)]
                else:
                    g.pos = [g.pos[k] + d[k] for k in range(3)]
            r["com_shift"] = list(d)
        resolved[bname] = r
    m = spec.compile()
    for bname, r in resolved.items():
        bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, bname)
        r["real_body_com"] = [float(x) for x in m.body_ipos[bid]]
        r["real_subtree_mass"] = float(m.body_subtreemass[bid])
    return m, resolved


# ---------------- one episode ----------------
def run_episode(m, joints, cfg, eff, rng, seconds, ep_idx, split, out_csv, t0_ctrl):
    d = mujoco.MjData(m)
    dt = m.opt.timestep
    nj = len(joints)
    jids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in joints]
    qadr = [m.jnt_qposadr[j] for j in jids]
    dadr = [m.jnt_dofadr[j] for j in jids]
    act_of = {}
    for a in range(m.nu):
        act_of[int(m.actuator_trnid[a, 0])] = a
    aids = [act_of[j] for j in jids]
    key = m.key_qpos[0]
    centre = [float(key[a]) for a in qadr]
    amp = cfg["amp"]
    delay = [eff.get("joints", {}).get(j, {}).get("delay", eff.get("delay", 0.0)) for j in joints]
    offset = [eff.get("joints", {}).get(j, {}).get("offset", 0.0) for j in joints]

    # controller ticks in recording time: t0_ctrl + k/ctrl_hz, k from the settle start to the end
    ctrl_hz, tick_t, issued_index = ticks(cfg, seconds, t0_ctrl)
    cmd, segs = make_commands(rng, tick_t, centre, amp, seconds, ctrl_hz)

    # initial state: at the first command, at rest; settle SETTLE_S s unrecorded
    for i, a in enumerate(qadr):
        d.qpos[a] = cmd[0, i]
    mujoco.mj_forward(m, d)
    # A command reaches actuator i exactly at its tick + delay[i]: a physics step that would
    # straddle such a switch is split there (a real servo does not wait for the simulator's
    # next step; applying each command at the first step after its switch time added a
    # 0.3-1.9 ms latency that no case declared).
    # `physics_div`: the robot integrates at timestep / physics_div (hardware moves in continuous
    # time; the model a user trains with steps at its own timestep).
    h_max = dt / float(cfg.get("physics_div", 1))
    t_end = seconds + 0.05
    switches = np.unique(np.concatenate([tick_t + dl for dl in set(delay)]))
    T = [-SETTLE_S]; Q = [[d.qpos[a] for a in qadr]]; QD = [[d.qvel[a] for a in dadr]]
    peak_tau = np.zeros(nj); sat = np.zeros(nj, int)
    t = -SETTLE_S
    while t < t_end - 1e-12:
        for i in range(nj):
            # command reaching the actuator: the last tick issued at or before t - delay
            k = issued_index(t - delay[i])
            d.ctrl[aids[i]] = cmd[max(k, 0), i]
        nxt = switches[np.searchsorted(switches, t + 1e-9, side="right")] if switches[-1] > t + 1e-9 else np.inf
        h = min(h_max, nxt - t, t_end - t)
        m.opt.timestep = h
        mujoco.mj_step(m, d)
        t = nxt if h == nxt - t else t + h
        T.append(t)
        Q.append([d.qpos[a] for a in qadr])
        QD.append([d.qvel[a] for a in dadr])
        if t - h >= 0:
            f = np.array([d.actuator_force[a] for a in aids])
            peak_tau = np.maximum(peak_tau, np.abs(f))
            for i, a in enumerate(aids):
                if m.actuator_forcelimited[a] and abs(f[i]) >= m.actuator_forcerange[a, 1] - 1e-6:
                    sat[i] += 1

    m.opt.timestep = dt
    T = np.asarray(T); Q = np.asarray(Q); QD = np.asarray(QD)
    n_rows, n_drop = record(rng, cfg, T, Q, QD, cmd, issued_index, offset, seconds, out_csv,
                            ep_idx, split, joints, t0_ctrl, ctrl_hz)
    return {"file": episode_file(out_csv),
            "split": split, "seconds": seconds, "samples": n_rows, "dropped": n_drop,
            "segments": segs, "peak_abs_tau": [round(float(x), 3) for x in peak_tau],
            "saturated_steps": sat.tolist()}


def main(case):
    c, mcfg, cfg, out = case_setup(case, CASES, MODELS, HERE)
    src = os.path.join(HERE, "models", mcfg["xml"])
    eff = c.get("effects", {})
    m, body_truth = real_model(src, eff)
    resolved = conceal(m, eff, m.key_qpos[0].copy())
    if body_truth:
        resolved["_bodies"] = body_truth
    if "delay" in eff:
        resolved["_all_delay_s"] = eff["delay"]
    rng = np.random.default_rng(c["seed"])
    eps = [run_episode(m, mcfg["joints"], cfg, eff, rng, secs, e, split, csv, cfg["t0_ctrl"])
           for e, split, secs, csv in episode_plan(c, out)]
    truth = {"case": case, "model": mcfg["xml"], "joints": mcfg["joints"], "effects": eff,
             "resolved": resolved,
             "logging": {k: cfg[k] for k in ("rec_hz", "jitter", "drop", "q_noise", "qd_noise", "bits", "t0_ctrl", "amp", "rec_start", "declare_t0", "ctrl_hz", "declared_hz", "physics_div") if k in cfg},
             "settle_s": SETTLE_S, "control_rate_hz": float(cfg.get("ctrl_hz", CTRL_HZ)), "seed": c["seed"],
             "timestep": m.opt.timestep, "episodes": eps, "mujoco": mujoco.__version__}
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
    print(case, "ok:", [(x["samples"], x["dropped"], x["peak_abs_tau"], x["saturated_steps"]) for x in eps])


if __name__ == "__main__":
    for a in sys.argv[1:]:
        if a not in CASES:
            sys.exit(f"realsim.py: unknown case `{a}`; known: {', '.join(CASES)}")
        main(a)
