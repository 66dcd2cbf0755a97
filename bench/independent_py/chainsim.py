#!/usr/bin/env python3
"""A "real robot" with its own physics (numpy only, no MuJoCo): a planar serial chain of hinges
about parallel axes (y) on a fixed base, for the hard classes of concealed effects.

usage: chainsim.py CASE...      record cases of cases.py whose `sim` is "chain"
       chainsim.py --selftest   physics checks (energy, small-oscillation frequency, dead band)

Writes $INDEP_OUT/data/CASE/{nominal.xml, episodes/ep_0N.csv, truth.json} like realsim.py (the
same command generator and recorder, reclog.py; the case plan, the links' mass properties, the
body effects and the stepping between command switches shared in simcommon.py). What it models:
- rigid links in the x–z plane, each a list of parts (mass, centre of mass (x, z) in the link's
  frame, moment of inertia about y through that centre), the parts' inertias worked out by hand
  (simcommon.py) from the nominal MJCF's geoms (capsule: cylinder + two hemispheres; box);
- mass matrix M_jk = sum over parts of links i >= max(j, k) of m (p - o_j)·(p - o_k) + I_yy, and
  bias forces (gravity, centripetal/Coriolis) by projecting each part's velocity-product and
  gravity acceleration on the joints (a planar recursive Newton–Euler with qdd = 0);
- rotor armature on M's diagonal; viscous damping; a position servo tau = kp (u - q) - kv qd
  clipped to its force range; classical RK4 at 4 kHz (5 kHz with backlash), a step split at
  every command switch;
- concealed effects, each as its own physics: backlash (the servo drives a motor angle of inertia
  = the joint's armature, which pushes the link through a dead band of total width b with a stiff
  spring and damper outside it; the servo's feedback is the motor's angle, the log the link's);
  Stribeck friction -(Fc + (Fs - Fc) exp(-(v/vs)^2)) tanh(v/0.005), Coulomb friction the same with
  Fs = Fc; armature; a payload (a solid sphere added to a link), a centre-of-mass shift (every
  part of the link moved) and an inertia scale (the link's moment about y through its centre of
  mass × s, mass and centre of mass kept: a massless part at the centre of mass holding the
  difference).
It does not model: contacts or joint limits (the recorded motion stays inside the nominal ranges,
checked), out-of-plane motion, a floating base, motor electrics.
"""
import json
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from reclog import CTRL_HZ, SETTLE_S, make_commands, record  # noqa: E402
from simcommon import (Rk4, body_truth, box_iyy, capsule_iyy, case_setup, check_ranges,  # noqa: E402
                       episode_file, episode_plan, run_commands, ticks,
                       with_body_effects)

G = 9.81
STRIBECK_EPS = 0.005  # rad/s: the friction's smoothing velocity (sharper than a replay's)


# Link descriptions matching the nominal MJCF (read off the XML by hand): `pos` is the joint's
# place in the parent link's frame (x, z), parts are (mass, (x, z), I_yy about the part's centre).
CHAINS = {
    "leg3": [  # bench/independent_py/models/leg3.xml
        dict(joint="hip_pitch", pos=(0.0, 0.0), parts=[(2.6, (0.0, -0.18), capsule_iyy(2.6, 0.04, 0.36))],
             armature=0.04, kp=80.0, kv=2.5, force=80.0, range=(-1.5, 1.5)),
        dict(joint="knee", pos=(0.0, -0.36), parts=[(1.7, (0.0, -0.16), capsule_iyy(1.7, 0.03, 0.32))],
             armature=0.03, kp=60.0, kv=2.0, force=50.0, range=(-0.1, 2.4)),
        dict(joint="ankle", pos=(0.0, -0.32), parts=[(0.9, (0.05, -0.03), box_iyy(0.9, 0.10, 0.02))],
             armature=0.012, kp=30.0, kv=1.0, force=25.0, range=(-1.0, 1.0)),
    ],
    "stance3": [  # bench/independent_py/models/stance3.xml: the foot pinned, the trunk on top
        dict(joint="ankle", pos=(0.0, 0.0), parts=[(1.7, (0.0, 0.16), capsule_iyy(1.7, 0.03, 0.32))],
             armature=0.03, kp=400.0, kv=8.0, force=200.0, range=(-0.6, 0.6)),
        dict(joint="knee", pos=(0.0, 0.32), parts=[(2.6, (0.0, 0.18), capsule_iyy(2.6, 0.04, 0.36))],
             armature=0.04, kp=300.0, kv=6.0, force=150.0, range=(-1.2, 0.4)),
        dict(joint="hip_pitch", pos=(0.0, 0.36), parts=[(8.0, (0.0, 0.2), box_iyy(8.0, 0.08, 0.2))],
             armature=0.04, kp=200.0, kv=4.0, force=100.0, range=(-0.6, 1.2)),
    ],
    "pendulum": [  # fixtures/synth/pendulum_servo.xml: a massless arm, 0.5 kg at 0.1 m
        dict(joint="servo", pos=(0.0, 0.0), parts=[(0.5, (0.0, -0.1), 1e-8)],
             armature=0.0, kp=2.0, kv=0.0335, force=None, range=(-2.0, 2.0)),
    ],
}


class Chain:
    """Rigid-body dynamics of one planar chain (links as in CHAINS, possibly modified)."""

    def __init__(self, links, gravity=G):
        self.links = links
        self.n = len(links)
        self.g = gravity
        self.pos = [tuple(map(float, l["pos"])) for l in links]
        self.parts = [[(float(m), tuple(map(float, c)), float(i)) for m, c, i in l["parts"]] for l in links]

    def kinematics(self, q):
        """Joint origins and every part's (mass, centre of mass, I_yy) in the world (x, z); plain
        floats (a 3-link chain is too small for numpy to pay)."""
        ox = oz = th = 0.0
        c, s = 1.0, 0.0
        origins, pts = [], []
        for i in range(self.n):
            px, pz = self.pos[i]
            ox, oz = ox + c * px + s * pz, oz - s * px + c * pz
            th += q[i]
            c, s = math.cos(th), math.sin(th)
            origins.append((ox, oz))
            pts.append([(m, ox + c * cx + s * cz, oz - s * cx + c * cz, iy)
                        for m, (cx, cz), iy in self.parts[i]])
        return origins, pts

    def mass_bias(self, q, qd):
        """M(q) (links only, no armature) and bias(q, qd) = Coriolis/centripetal + gravity, so
        that M qdd + bias = joint torques: each part's velocity-product and gravity acceleration
        (qdd = 0, the base accelerating upwards at g) projected on the joints, M from the parts'
        joint Jacobians (a column of joint j at point p is (p − o_j) turned by 90°)."""
        n = self.n
        origins, pts = self.kinematics(q)
        M = [[0.0] * n for _ in range(n)]
        bias = [0.0] * n
        ax, az = 0.0, self.g
        w = 0.0
        for i in range(n):
            oix, oiz = origins[i]
            if i > 0:
                ax -= w * w * (oix - origins[i - 1][0])
                az -= w * w * (oiz - origins[i - 1][1])
            w += qd[i]
            w2 = w * w
            for m, px, pz, iy in pts[i]:
                apx, apz = ax - w2 * (px - oix), az - w2 * (pz - oiz)
                d = [(px - origins[j][0], pz - origins[j][1]) for j in range(i + 1)]
                for j in range(i + 1):
                    dj = d[j]
                    bias[j] += m * (dj[1] * apx - dj[0] * apz)
                    Mj = M[j]
                    for k in range(j + 1):
                        v = m * (dj[0] * d[k][0] + dj[1] * d[k][1]) + iy
                        Mj[k] += v
                        if k != j:
                            M[k][j] += v
        return np.array(M), np.array(bias)

    def energy(self, q, qd):
        M, _ = self.mass_bias(q, np.zeros(self.n))
        _, pts = self.kinematics(q)
        pot = sum(m * self.g * pz for ps in pts for m, _, pz, _ in ps)
        return 0.5 * qd @ M @ qd + pot


class Robot(Rk4):
    """The chain with its drives: servos, armature, damping, friction, backlash."""

    def __init__(self, links, eff, gravity=G):
        links = with_body_effects(links, eff)
        self.chain = Chain(links, gravity)
        n = self.n = len(links)
        je = [eff.get("joints", {}).get(l["joint"], {}) for l in links]
        self.kp = np.array([l["kp"] for l in links])
        self.kv = np.array([l["kv"] for l in links])
        self.force = np.array([l["force"] if l["force"] else np.inf for l in links])
        self.arm = np.array([e.get("armature", l["armature"]) for l, e in zip(links, je)])
        self.damp = np.array([e.get("damping", 0.0) for e in je])
        fc = [e.get("stribeck", {}).get("dynamic", e.get("frictionloss", 0.0)) for e in je]
        fs = [e.get("stribeck", {}).get("static", f) for e, f in zip(je, fc)]
        self.fc, self.fs = np.array(fc), np.array(fs)
        self.vs = np.array([e.get("stribeck", {}).get("v_stribeck", 1.0) for e in je])
        self.back = [i for i in range(n) if je[i].get("backlash", 0.0) > 0]
        self.b = np.array([je[i]["backlash"] for i in self.back])
        # the gear's stiffness outside the play: 1000 × kp (0.1 mrad under the servo's full
        # torque per 0.1 rad of error), damped at ζ 0.7 on the motor's inertia
        self.kg = np.array([1000.0 * self.kp[i] for i in self.back])
        for i in self.back:
            assert self.arm[i] > 0, "backlash needs a motor inertia (armature)"
        self.cg = np.array([2 * 0.7 * math.sqrt(k * self.arm[i]) for k, i in zip(self.kg, self.back)])
        self.link_arm = self.arm.copy()
        self.link_arm[self.back] = 0.0  # the rotor sits behind the play
        self.u = np.zeros(n)
        self.peak = np.zeros(n)
        # plain-float copies for deriv()
        self.bidx = [self.back.index(i) if i in self.back else -1 for i in range(n)]
        self.kp_, self.kv_, self.force_ = self.kp.tolist(), self.kv.tolist(), self.force.tolist()
        self.damp_, self.fc_, self.fs_, self.vs_ = (a.tolist() for a in (self.damp, self.fc, self.fs, self.vs))
        self.arm_, self.b_, self.kg_, self.cg_ = (a.tolist() for a in (self.arm, self.b, self.kg, self.cg))

    def deriv(self, x):
        """x = [q (n), qd (n), qm (nb), qmd (nb)] → (dx/dt, servo torques)."""
        n, nb = self.n, len(self.back)
        xs = x.tolist()
        q, qd = xs[:n], xs[n:2 * n]
        qm, qmd = xs[2 * n:2 * n + nb], xs[2 * n + nb:]
        tau_s, tau_link, qmdd = [0.0] * n, [0.0] * n, [0.0] * nb
        for i in range(n):
            v = qd[i]
            k = self.bidx[i]
            pos, vel = (q[i], v) if k < 0 else (qm[k], qmd[k])  # the servo reads the motor
            ts = self.kp_[i] * (self.u[i] - pos) - self.kv_[i] * vel
            ts = max(-self.force_[i], min(self.force_[i], ts))
            tau_s[i] = ts
            t = -self.damp_[i] * v
            if self.fs_[i] > 0:
                t -= (self.fc_[i] + (self.fs_[i] - self.fc_[i]) * math.exp(-(v / self.vs_[i]) ** 2)) \
                    * math.tanh(v / STRIBECK_EPS)
            if k < 0:
                t += ts
            else:  # the gear: a dead band of total width b, a stiff spring and damper outside
                d, dv, hb = qm[k] - q[i], qmd[k] - v, self.b_[k] / 2
                tc = 0.0
                if d > hb:
                    tc = max(self.kg_[k] * (d - hb) + self.cg_[k] * dv, 0.0)
                elif d < -hb:
                    tc = min(self.kg_[k] * (d + hb) + self.cg_[k] * dv, 0.0)
                t += tc
                qmdd[k] = (ts - tc) / self.arm_[i]
            tau_link[i] = t
        M, bias = self.chain.mass_bias(q, qd)
        M[np.diag_indices(n)] += self.link_arm
        qdd = np.linalg.solve(M, np.array(tau_link) - bias)
        return np.concatenate([x[n:2 * n], qdd, x[2 * n + nb:], qmdd]), tau_s

    def start(self, q0):
        """At rest at q0, the motors behind a play resting on the flank gravity loads."""
        _, bias = self.chain.mass_bias(q0, np.zeros(self.n))
        qm = np.array([q0[i] + math.copysign(self.b[k] / 2, bias[i]) for k, i in enumerate(self.back)])
        return np.concatenate([q0, np.zeros(self.n), qm, np.zeros(len(self.back))])


def run_episode(robot, links, cfg, rng, seconds, ep_idx, split, out_csv, t0_ctrl):
    joints = [l["joint"] for l in links]
    nj = len(joints)
    centre = [l["key"] for l in links]
    ctrl_hz, tick_t, issued_index = ticks(cfg, seconds, t0_ctrl)
    cmd, segs = make_commands(rng, tick_t, centre, cfg["amp"], seconds, ctrl_hz)
    h_max = 1.0 / (5000.0 if robot.back else 4000.0)
    x = robot.start(np.array(cmd[0], float))
    robot.peak[:] = 0.0
    T, Q, QD, qmin, qmax = run_commands(robot, x, nj, tick_t, cmd, issued_index, seconds, h_max)
    check_ranges(links, qmin, qmax, " (chainsim has no limits)")
    n_rows, n_drop = record(rng, cfg, T, Q, QD, cmd, issued_index, [0.0] * nj, seconds, out_csv,
                            ep_idx, split, joints, t0_ctrl, ctrl_hz,
                            note="recorded by chainsim.py (own planar-chain physics, no MuJoCo)")
    return {"file": episode_file(out_csv),
            "split": split, "seconds": seconds, "samples": n_rows, "dropped": n_drop,
            "segments": segs, "peak_abs_tau": [round(float(v), 3) for v in robot.peak],
            "q_range": [[round(float(a), 4), round(float(b), 4)] for a, b in zip(qmin, qmax)]}


def main(case, cases, models):
    c, mcfg, cfg, out = case_setup(case, cases, models, HERE)
    eff = c.get("effects", {})
    links = [dict(l, key=k) for l, k in zip(CHAINS[mcfg["chain"]], mcfg["key"])]
    eff_run = dict(eff, bodies_by_joint={b["joint"]: b for b in eff.get("bodies", {}).values()})
    robot = Robot(links, eff_run)
    resolved = {}
    for l in links:
        e = eff.get("joints", {}).get(l["joint"], {})
        r = {k: [0.0, v] for k, v in e.items() if k in ("backlash", "damping", "frictionloss")}
        if "armature" in e:
            r["armature"] = [l["armature"], e["armature"]]
        if "stribeck" in e:
            r["stribeck"] = dict(e["stribeck"], eps=STRIBECK_EPS)
        if "backlash" in e:
            k = robot.back.index(links.index(l))
            r["gear_stiffness"], r["gear_damping"] = float(robot.kg[k]), float(robot.cg[k])
        if r:
            resolved[l["joint"]] = r
    if eff.get("bodies"):
        resolved["_bodies"] = body_truth(links, eff)
    rng = np.random.default_rng(c["seed"])
    eps = [run_episode(robot, links, cfg, rng, secs, e, split, csv, cfg["t0_ctrl"])
           for e, split, secs, csv in episode_plan(c, out)]
    truth = {"case": case, "simulator": "chainsim.py", "model": mcfg["xml"],
             "joints": [l["joint"] for l in links], "effects": eff, "resolved": resolved,
             "logging": {k: cfg[k] for k in ("rec_hz", "jitter", "drop", "q_noise", "qd_noise", "bits",
                                             "t0_ctrl", "amp") if k in cfg},
             "settle_s": SETTLE_S, "control_rate_hz": float(cfg.get("ctrl_hz", CTRL_HZ)),
             "seed": c["seed"], "integrator": "rk4", "step_s": 2e-4 if robot.back else 2.5e-4,
             "episodes": eps}
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
    print(case, "ok:", [(x["samples"], x["dropped"], x["peak_abs_tau"]) for x in eps])


# ---------------- self-test: physics that can be stated without a simulator ----------------
def selftest():
    ok = True

    def check(name, cond, detail):
        nonlocal ok
        ok &= bool(cond)
        print(f"{'ok ' if cond else 'FAIL'} {name}: {detail}")

    # 1. inertias by hand against textbook limits: a capsule of zero radius is a rod m L^2/12
    check("capsule → rod", abs(capsule_iyy(1.0, 1e-6, 0.3) - 0.3 ** 2 / 12) < 1e-4 * 0.3 ** 2 / 12, f"{capsule_iyy(1.0, 1e-6, 0.3):.6g}")
    check("capsule → sphere", abs(capsule_iyy(1.0, 0.1, 0.0) - 0.4 * 0.01) < 1e-12, f"{capsule_iyy(1.0, 0.1, 0.0):.6g}")

    # 2. energy of the undamped, unactuated three-link chain is conserved
    ch = Chain(CHAINS["leg3"])
    q, qd = np.array([0.9, -0.7, 0.5]), np.array([1.0, -2.0, 3.0])
    arm = np.array([l["armature"] for l in CHAINS["leg3"]])
    e0 = ch.energy(q, qd) + 0.5 * arm @ qd ** 2
    x, h = np.concatenate([q, qd]), 2.5e-4

    def f(x):
        M, b = ch.mass_bias(x[:3], x[3:])
        M[np.diag_indices(3)] += arm
        return np.concatenate([x[3:], np.linalg.solve(M, -b)])
    drift = 0.0
    for _ in range(int(3.0 / h)):
        k1 = f(x); k2 = f(x + h / 2 * k1); k3 = f(x + h / 2 * k2); k4 = f(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        drift = max(drift, abs(ch.energy(x[:3], x[3:]) + 0.5 * arm @ x[3:] ** 2 - e0))
    scale = abs(e0 - ch.energy(np.zeros(3), np.zeros(3)))
    check("energy, free 3-link chain, 3 s", drift < 1e-6 * scale, f"max |ΔE| {drift:.2e} J of {scale:.3f} J")

    # 3. M is symmetric positive definite and bias is gravity's torque at rest (finite difference)
    M, b = ch.mass_bias(q, np.zeros(3))
    gnum = np.array([(ch.energy(q + 1e-6 * np.eye(3)[j], np.zeros(3)) - ch.energy(q - 1e-6 * np.eye(3)[j], np.zeros(3))) / 2e-6 for j in range(3)])
    check("gravity torque = dV/dq", np.max(np.abs(gnum - b)) < 1e-6, f"max diff {np.max(np.abs(gnum - b)):.2e}")
    check("M SPD", np.allclose(M, M.T) and np.all(np.linalg.eigvalsh(M) > 0), f"eig {np.linalg.eigvalsh(M)}")

    # 4. small oscillations of the pendulum (servo off, armature 0.002): ω = sqrt(m g l / I)
    links = [dict(CHAINS["pendulum"][0], kp=0.0, kv=0.0, key=0.0)]
    r = Robot(links, {"joints": {"servo": {"armature": 0.002}}})
    x = r.start(np.array([0.01]))
    ts, qs = [], []
    for k in range(int(2.0 / 2.5e-4)):
        x = r.rk4(x, 2.5e-4); ts.append((k + 1) * 2.5e-4); qs.append(x[0])
    qs = np.array(qs); ts = np.array(ts)
    up = ts[1:][(qs[:-1] < 0) & (qs[1:] >= 0)]
    w_meas = 2 * math.pi / np.mean(np.diff(up))
    w_true = math.sqrt(0.5 * G * 0.1 / (0.5 * 0.01 + 1e-8 + 0.002))
    check("small-oscillation ω", abs(w_meas / w_true - 1) < 1e-3, f"{w_meas:.4f} rad/s measured, {w_true:.4f} predicted")

    # 5. backlash: no gravity, a damped link dragged by its servo through a slow triangle wave;
    # while it moves, motor − link sits at ±b/2 (plus the gear's deflection), both signs seen
    b = 0.04
    links = [dict(CHAINS["pendulum"][0], kp=2.0, kv=0.05, key=0.0)]
    r = Robot(links, {"joints": {"servo": {"backlash": b, "armature": 0.002, "damping": 0.01}}}, gravity=0.0)
    x = r.start(np.array([0.0]))
    gaps, h = [], 1e-4
    for k in range(int(10.0 / h)):
        t = k * h
        r.u = np.array([0.3 * (2 / math.pi) * math.asin(math.sin(2 * math.pi * 0.2 * t))])
        x = r.rk4(x, h)
        if t > 1.0 and abs(x[1]) > 0.05:
            gaps.append(x[2] - x[0])
    gaps = np.array(gaps)
    hi, lo = np.median(gaps[gaps > 0]), np.median(gaps[gaps < 0])
    print(f"     motor − link while moving: +side {hi * 1e3:.2f} mrad, −side {lo * 1e3:.2f} mrad (b/2 = {b / 2 * 1e3:.1f})")
    check("backlash dead band", abs(hi - b / 2) < 0.1 * b / 2 and abs(lo + b / 2) < 0.1 * b / 2,
          f"hysteresis width {1e3 * (hi - lo):.2f} mrad for b = {1e3 * b:.1f} mrad")

    # 6. Stribeck friction holds a joint the Coulomb level alone would let slide: a servo error
    # torque between Fc and Fs leaves the joint stuck (creeping at the smoothing velocity only)
    links = [dict(CHAINS["pendulum"][0], kp=2.0, kv=0.0335, key=0.0)]
    res = {}
    for name, fr in (("stribeck", {"stribeck": {"static": 0.06, "dynamic": 0.03, "v_stribeck": 0.2}}),
                     ("coulomb", {"frictionloss": 0.03})):
        r = Robot(links, {"joints": {"servo": dict(fr, armature=0.001)}}, gravity=0.0)
        x = r.start(np.array([0.0]))
        r.u = np.array([0.02])  # 0.04 N·m of servo torque: above Fc, below Fs
        for _ in range(int(1.0 / 2.5e-4)):
            x = r.rk4(x, 2.5e-4)
        res[name] = x[0]
    check("Stribeck sticks where Coulomb slides", res["stribeck"] < 0.2 * 0.02 and res["coulomb"] > 0.4 * 0.02,
          f"after 1 s: Stribeck q = {res['stribeck'] * 1e3:.2f} mrad, Coulomb q = {res['coulomb'] * 1e3:.2f} mrad (command 20)")

    # 7. when MuJoCo happens to be importable (a check of this file's description of the
    # nominal models only; the dynamics never import it): the hand inertias equal the compiled
    # ones, and the clean robot follows MuJoCo's own RK4 at the same step under the same commands
    try:
        import mujoco
    except ImportError:
        print("skip the comparison with MuJoCo: no mujoco module")
    else:
        for name, xml, key in (("pendulum", "../../fixtures/synth/pendulum_servo.xml", [0.0]),
                               ("leg3", "models/leg3.xml", [-0.4, 0.8, -0.4]),
                               ("stance3", "models/stance3.xml", [0.15, -0.4, 0.3])):
            m = mujoco.MjModel.from_xml_path(os.path.join(HERE, xml))
            for l in CHAINS[name]:
                bid = m.jnt_bodyid[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, l["joint"])]
                if len(l["parts"]) != 1 or m.body_mass[bid] == 0:
                    continue  # the pendulum's massless arm: its mass sits in a child body
                (mass, c, iy), = l["parts"]
                good = (abs(mass - m.body_mass[bid]) < 1e-9 and np.allclose(c, m.body_ipos[bid][[0, 2]], atol=1e-9)
                        and abs(iy - m.body_inertia[bid][1]) < 1e-6 * iy)
                check(f"{l['joint']} link vs MuJoCo", good, f"I_yy {iy:.6g} by hand, {m.body_inertia[bid][1]:.6g} compiled")
            m.opt.integrator, m.opt.timestep = mujoco.mjtIntegrator.mjINT_RK4, 2.5e-4
            d = mujoco.MjData(m)
            r = Robot([dict(l, key=k) for l, k in zip(CHAINS[name], key)], {})
            d.qpos[:] = key
            x = r.start(np.array(key, float))
            rng, err = np.random.default_rng(1), 0.0
            for _ in range(200):  # 2 s of random 100 Hz commands
                d.ctrl[:] = r.u = list(np.array(key) + rng.uniform(-0.3, 0.3, len(key)))
                for _ in range(40):
                    mujoco.mj_step(m, d)
                    x = r.rk4(x, 2.5e-4)
                err = max(err, float(np.max(np.abs(d.qpos - x[:len(key)]))))
            check(f"{name} vs MuJoCo RK4, 2 s", err < 1e-9, f"max |Δq| {err:.1e} rad")
    print("selftest", "passed" if ok else "FAILED")
    return ok


if __name__ == "__main__":
    if sys.argv[1:] == ["--selftest"]:
        sys.exit(0 if selftest() else 1)
    from cases import CASES, MODELS  # noqa: E402
    for a in sys.argv[1:]:
        if CASES.get(a, {}).get("sim") != "chain":
            sys.exit(f"chainsim.py: `{a}` is not a chain case; known: "
                     + ", ".join(k for k, v in CASES.items() if v.get("sim") == "chain"))
        main(a, CASES, MODELS)
