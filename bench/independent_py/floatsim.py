#!/usr/bin/env python3
"""A "real robot" on a free base with its own physics (numpy only, no MuJoCo): a planar trunk
(x, z, pitch) standing on two three-joint legs, feet on the ground through a penalty contact.

usage: floatsim.py CASE...      record cases of cases.py whose `sim` is "float"
       floatsim.py --selftest   physics checks (energy of the free tree, standing at rest)

Writes $INDEP_OUT/data/CASE/{nominal.xml, episodes/ep_0N.csv, truth.json} like chainsim.py (the
same command generator and recorder, reclog.py). What it models:
- a planar tree in the x–z plane: the trunk on two slides (x, z) and a hinge (pitch, about y),
  and under it two legs (hip pitch → thigh → knee → shank → ankle → foot, all about y) at the
  same place in the plane (the model's legs sit apart along y, which changes nothing in the
  plane); links as lists of parts (mass, centre of mass (x, z) in the link's frame, moment of
  inertia about y through that centre; chainsim.py's capsule and box formulas);
- M(q) = Σ over parts m J_j·J_k (+ I_yy where both j and k are hinges on the part's path) and
  the bias (gravity, centripetal/Coriolis) from each part's velocity-product acceleration
  projected on its Jacobian (J of a slide: its direction; of a hinge at o, at a point p: the
  90°-turned p − o);
- the ground: the plane z = 0 pushing on each foot's heel and toe (the corners of the sole) with
  a spring-damper normal force max(0, k·depth − c·ż) and a regularised Coulomb friction
  −μ·N·tanh(ẋ / v_ε) (k 1e5 N/m, c 1000 N·s/m, μ 0.9, v_ε 0.01 m/s) — not MuJoCo's soft
  constraint: the contact models differ, as a real floor differs from any simulator's;
- rotor armature on M's diagonal, position servos tau = kp (u − q) − kv q̇ clipped to their
  force range, RK4 at 4 kHz split at every command switch; both legs get the same commands
  (a planar robot whose legs differed would fight itself through the ground): a squat, a hip
  swing and an ankle that keeps the soles flat under a trunk pitching by a third, small signal
  (run_episode); the trunk is unactuated;
- concealed body effects on a link as in chainsim.py (simcommon.py: a payload sphere, a
  centre-of-mass shift, an inertia scale).
The log records the six leg joints (q, q̇, command) and the trunk's three base joints (q, q̇,
no command: passive). It does not model: out-of-plane motion, joint limits (checked), rolling
of the sole's edge (two points), motor electrics.
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
                       episode_file, episode_plan, run_commands, ticks, with_body_effects)

G = 9.81
GROUND = dict(k=1e5, c=1000.0, mu=0.9, v_eps=0.01)


def leg(side):
    return [
        dict(name=f"{side}_thigh", joint=f"{side}_hip_pitch", kind="hinge", parent="trunk", pos=(0.0, 0.0),
             parts=[(2.6, (0.0, -0.18), capsule_iyy(2.6, 0.04, 0.36))],
             armature=0.04, kp=300.0, kv=12.0, force=150.0, range=(-1.0, 1.0)),
        dict(name=f"{side}_shank", joint=f"{side}_knee", kind="hinge", parent=f"{side}_thigh", pos=(0.0, -0.36),
             parts=[(1.7, (0.0, -0.16), capsule_iyy(1.7, 0.03, 0.32))],
             armature=0.03, kp=300.0, kv=12.0, force=150.0, range=(0.0, 1.8)),
        dict(name=f"{side}_foot", joint=f"{side}_ankle", kind="hinge", parent=f"{side}_shank", pos=(0.0, -0.32),
             parts=[(0.9, (0.05, -0.03), box_iyy(0.9, 0.10, 0.02))],
             armature=0.012, kp=300.0, kv=10.0, force=120.0, range=(-1.0, 1.0),
             contacts=[(-0.05, -0.05), (0.15, -0.05)]),
    ]


# models/biped2.xml by hand: the trunk's joints first (slides at the trunk's origin, then the
# hinge), `pos` is the link's origin in its parent's frame (x, z).
TRUNK_Z = 0.676
BODIES = {
    "biped2": [
        dict(name="trunk", joint="root_x", kind="slide_x", parent=None, pos=(0.0, TRUNK_Z), parts=[]),
        dict(name="trunk", joint="root_z", kind="slide_z", parent=None, pos=(0.0, 0.0), parts=[]),
        dict(name="trunk", joint="root_pitch", kind="hinge", parent=None, pos=(0.0, 0.0),
             parts=[(8.0, (0.0, 0.2), box_iyy(8.0, 0.08, 0.2))], armature=0.0),
    ] + leg("left") + leg("right"),
}


class Tree:
    """Planar rigid-body tree: `links` in order, each with one dof (a slide or a hinge); the
    trunk's three dofs are links 0–2 chained (the parts on the last)."""

    def __init__(self, links, gravity=G):
        self.links = links
        self.n = len(links)
        self.g = gravity
        names = {}
        self.parent = []
        for i, l in enumerate(links):
            if i in (1, 2):
                p = i - 1  # the trunk's z slide and pitch hinge sit on the dof before
            else:
                p = names.get(l["parent"], -1) if l["parent"] else -1
            self.parent.append(p)
            names[l["name"]] = i
        self.path = []
        for i in range(self.n):
            p, path = i, []
            while p >= 0:
                path.append(p)
                p = self.parent[p]
            self.path.append(path[::-1])
        self.hinge = [l["kind"] == "hinge" for l in links]
        self.pos = [tuple(map(float, l["pos"])) for l in links]
        self.parts = [[(float(m), tuple(map(float, c)), float(iy)) for m, c, iy in l["parts"]] for l in links]

    def frames(self, q, qd):
        """Per dof: origin (x, z), angle, angular velocity and the origin's velocity-product
        acceleration (qdd = 0) with gravity as an upward acceleration of the base."""
        o, th, w, a = [None] * self.n, [0.0] * self.n, [0.0] * self.n, [None] * self.n
        for i, l in enumerate(self.links):
            p = self.parent[i]
            if p < 0:
                po, pth, pw, pa = (0.0, 0.0), 0.0, 0.0, (0.0, self.g)
            else:
                po, pth, pw, pa = o[p], th[p], w[p], a[p]
            c, s = math.cos(pth), math.sin(pth)
            px, pz = self.pos[i]
            ox, oz = po[0] + c * px + s * pz, po[1] - s * px + c * pz
            ax, az = pa[0] - pw * pw * (ox - po[0]), pa[1] - pw * pw * (oz - po[1])
            if l["kind"] == "slide_x":
                ox += q[i]
            elif l["kind"] == "slide_z":
                oz += q[i]
            o[i], a[i] = (ox, oz), (ax, az)
            th[i] = pth + (q[i] if self.hinge[i] else 0.0)
            w[i] = pw + (qd[i] if self.hinge[i] else 0.0)
        return o, th, w, a

    def jac(self, o, i, px, pz):
        """Jacobian columns (x, z) of the point (px, pz) on link i, over i's path."""
        out = []
        for j in self.path[i]:
            k = self.links[j]["kind"]
            if k == "slide_x":
                out.append((j, 1.0, 0.0))
            elif k == "slide_z":
                out.append((j, 0.0, 1.0))
            else:
                out.append((j, pz - o[j][1], -(px - o[j][0])))
        return out

    def world(self, o, th, i, cx, cz):
        c, s = math.cos(th[i]), math.sin(th[i])
        return o[i][0] + c * cx + s * cz, o[i][1] - s * cx + c * cz

    def mass_bias(self, q, qd):
        n = self.n
        o, th, w, a = self.frames(q, qd)
        M = np.zeros((n, n))
        bias = np.zeros(n)
        for i in range(n):
            hinges = [j for j in self.path[i] if self.hinge[j]]
            for m, (cx, cz), iy in self.parts[i]:
                px, pz = self.world(o, th, i, cx, cz)
                ax = a[i][0] - w[i] ** 2 * (px - o[i][0])
                az = a[i][1] - w[i] ** 2 * (pz - o[i][1])
                J = self.jac(o, i, px, pz)
                for j, jx, jz in J:
                    bias[j] += m * (jx * ax + jz * az)
                    for k, kx, kz in J:
                        M[j, k] += m * (jx * kx + jz * kz)
                for j in hinges:
                    for k in hinges:
                        M[j, k] += iy
        return M, bias

    def energy(self, q, qd):
        M, _ = self.mass_bias(q, np.zeros(self.n))
        o, th, _, _ = self.frames(q, np.zeros(self.n))
        pot = sum(m * self.g * self.world(o, th, i, c[0], c[1])[1]
                  for i in range(self.n) for m, c, _ in self.parts[i])
        return 0.5 * qd @ M @ qd + pot


class Robot(Rk4):
    def __init__(self, links, eff, gravity=G, ground=GROUND):
        links = with_body_effects(links, eff)
        self.tree = Tree(links, gravity)
        self.links = links
        n = self.n = len(links)
        self.act = [i for i, l in enumerate(links) if "kp" in l]
        self.kp = [links[i]["kp"] for i in self.act]
        self.kv = [links[i]["kv"] for i in self.act]
        self.force = [links[i]["force"] for i in self.act]
        self.arm = np.array([l.get("armature", 0.0) for l in links])
        self.contacts = [(i, c) for i, l in enumerate(links) for c in l.get("contacts", [])]
        self.gr = ground
        self.u = [0.0] * len(self.act)
        self.peak = np.zeros(len(self.act))
        self.min_normal = math.inf

    def contact_forces(self, q, qd):
        """Generalised forces of the ground and the (x, z, N) of every contact point."""
        t = self.tree
        o, th, _, _ = t.frames(q, qd)
        tau = np.zeros(self.n)
        pts = []
        for i, (cx, cz) in self.contacts:
            px, pz = t.world(o, th, i, cx, cz)
            J = t.jac(o, i, px, pz)
            vx = sum(jx * qd[j] for j, jx, _ in J)
            vz = sum(jz * qd[j] for j, _, jz in J)
            depth = -pz
            fn = max(0.0, self.gr["k"] * depth - self.gr["c"] * vz) if depth > 0 else 0.0
            ft = -self.gr["mu"] * fn * math.tanh(vx / self.gr["v_eps"])
            for j, jx, jz in J:
                tau[j] += jx * ft + jz * fn
            pts.append((px, pz, fn))
        return tau, pts

    def deriv(self, x):
        n = self.n
        q, qd = x[:n], x[n:]
        tau = np.zeros(n)
        ts = []
        for k, i in enumerate(self.act):
            v = self.kp[k] * (self.u[k] - q[i]) - self.kv[k] * qd[i]
            v = max(-self.force[k], min(self.force[k], v))
            tau[i] += v
            ts.append(v)
        tc, _ = self.contact_forces(q, qd)
        M, bias = self.tree.mass_bias(q, qd)
        M[np.diag_indices(n)] += self.arm
        qdd = np.linalg.solve(M, tau + tc - bias)
        return np.concatenate([qd, qdd]), ts

    def standing(self, legq):
        """q with the leg joints at `legq` (per leg, both alike), the trunk level and its height
        such that the soles are at the ground's static depth (weight / (k × contact points))."""
        q = np.zeros(self.n)
        for k, i in enumerate(self.act):
            q[i] = legq[k % len(legq)]
        q[2] = -sum(legq)  # the trunk's pitch that leaves the soles flat
        _, pts = self.contact_forces(q, np.zeros(self.n))
        mass = sum(m for l in self.links for m, _, _ in l["parts"])
        depth = mass * self.tree.g / (self.gr["k"] * len(self.contacts))
        q[1] = -min(p[1] for p in pts) - depth
        return q


def run_episode(robot, cfg, rng, seconds, ep_idx, split, out_csv, t0_ctrl, joints, key):
    n = robot.n
    ctrl_hz, tick_t, issued_index = ticks(cfg, seconds, t0_ctrl)
    # three signals: a squat (the knee bent by s0, hip and ankle by −s0/2 each: the hip stays
    # over the ankle), a hip swing s1 and the trunk's pitch s2; the ankle takes the rest, so that
    # the soles stay flat under a trunk that pitches only by s2
    s3, segs = make_commands(rng, tick_t, [0.0, 0.0, 0.0], cfg["amp"], seconds, ctrl_hz)
    sq, sw, pt = s3[:, 0], s3[:, 1], s3[:, 2]
    cmd3 = np.asarray(key) + np.stack([-sq / 2 + sw, sq, -sq / 2 - sw - pt], axis=1)
    cmd = np.concatenate([cmd3, cmd3], axis=1)  # both legs alike
    x = np.concatenate([robot.standing(key), np.zeros(n)])
    robot.peak[:] = 0.0
    nmin = [math.inf, math.inf]

    def loads(t, x):  # the heel's and the toe's least load while recorded: the feet stay flat
        if t > 0:
            _, pts = robot.contact_forces(x[:n], x[n:])
            nmin[:] = [min(nmin[0], pts[0][2] + pts[2][2]), min(nmin[1], pts[1][2] + pts[3][2])]
    T, Q, QD, qmin, qmax = run_commands(robot, x, n, tick_t, cmd, issued_index, seconds,
                                        1.0 / 4000.0, loads)
    check_ranges(robot.links, qmin, qmax)
    assert abs(qmax[2]) < 0.6 and abs(qmin[2]) < 0.6, "the trunk fell"
    order = [robot.links.index(next(l for l in robot.links if l["joint"] == j)) for j in joints]
    full_cmd = np.concatenate([np.zeros((len(cmd), 3)), cmd], axis=1)  # the base: no command
    n_rows, n_drop = record(rng, cfg, T, Q[:, order], QD[:, order], full_cmd[:, order], issued_index,
                            [0.0] * len(joints), seconds, out_csv, ep_idx, split, joints, t0_ctrl,
                            ctrl_hz, note="recorded by floatsim.py (own planar free-base physics, "
                            "penalty ground contact, no MuJoCo)", passive=3)
    return {"file": episode_file(out_csv),
            "split": split, "seconds": seconds, "samples": n_rows, "dropped": n_drop,
            "segments": segs, "peak_abs_tau": [round(float(v), 3) for v in robot.peak],
            "least_heel_toe_load_n": [round(v, 1) for v in nmin],
            "q_range": [[round(float(a), 4), round(float(b), 4)] for a, b in zip(qmin, qmax)]}


def main(case, cases, models):
    c, mcfg, cfg, out = case_setup(case, cases, models, HERE)
    eff = c.get("effects", {})
    links = BODIES[mcfg["chain"]]
    eff_run = dict(eff, bodies_by_joint={b["joint"]: b for b in eff.get("bodies", {}).values()})
    ground = dict(GROUND, **c.get("ground", {}))  # a case may lay its own floor
    robot = Robot(links, eff_run, ground=ground)
    rng = np.random.default_rng(c["seed"])
    eps = [run_episode(robot, cfg, rng, secs, e, split, csv, cfg["t0_ctrl"], mcfg["joints"], mcfg["key"])
           for e, split, secs, csv in episode_plan(c, out)]
    truth = {"case": case, "simulator": "floatsim.py", "model": mcfg["xml"], "joints": mcfg["joints"],
             "effects": eff, "resolved": {"_bodies": body_truth(links, eff)} if eff.get("bodies") else {},
             "ground": ground,
             "logging": {k: cfg[k] for k in ("rec_hz", "jitter", "drop", "q_noise", "qd_noise", "bits",
                                             "t0_ctrl", "amp") if k in cfg},
             "settle_s": SETTLE_S, "control_rate_hz": float(cfg.get("ctrl_hz", CTRL_HZ)),
             "seed": c["seed"], "integrator": "rk4", "step_s": 2.5e-4, "episodes": eps}
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
    print(case, "ok:", [(x["samples"], x["dropped"], x["peak_abs_tau"], x["least_heel_toe_load_n"]) for x in eps])


def selftest():
    ok = True

    def check(name, cond, detail):
        nonlocal ok
        ok &= bool(cond)
        print(f"{'ok ' if cond else 'FAIL'} {name}: {detail}")

    links = BODIES["biped2"]
    tree = Tree(links)
    n = tree.n
    rng = np.random.default_rng(3)
    q, qd = rng.uniform(-0.5, 0.5, n), rng.uniform(-2, 2, n)
    M, b = tree.mass_bias(q, np.zeros(n))
    gnum = np.array([(tree.energy(q + 1e-6 * np.eye(n)[j], np.zeros(n))
                      - tree.energy(q - 1e-6 * np.eye(n)[j], np.zeros(n))) / 2e-6 for j in range(n)])
    check("gravity force = dV/dq", np.max(np.abs(gnum - b)) < 1e-5, f"max diff {np.max(np.abs(gnum - b)):.2e}")
    check("M SPD", np.allclose(M, M.T) and np.all(np.linalg.eigvalsh(M) > 0), "")
    total = sum(m for l in links for m, _, _ in l["parts"])
    check("M's x–x entry is the total mass", abs(M[0, 0] - total) < 1e-12, f"{M[0, 0]:.4f} kg")
    # energy of the free tree in zero gravity, no ground, no servos
    free = Tree(links, gravity=0.0)
    arm = np.array([l.get("armature", 0.0) for l in links])

    def f(x):
        M, b = free.mass_bias(x[:n], x[n:])
        M[np.diag_indices(n)] += arm
        return np.concatenate([x[n:], np.linalg.solve(M, -b)])
    x, h = np.concatenate([q, qd]), 2.5e-4
    e0 = free.energy(q, qd) + 0.5 * arm @ qd ** 2
    drift = 0.0
    for _ in range(int(1.0 / h)):
        k1 = f(x); k2 = f(x + h / 2 * k1); k3 = f(x + h / 2 * k2); k4 = f(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        drift = max(drift, abs(free.energy(x[:n], x[n:]) + 0.5 * arm @ x[n:] ** 2 - e0))
    check("energy, free tree, 1 s", drift < 1e-6 * e0, f"max |ΔE| {drift:.2e} J of {e0:.3f} J")
    # momentum: no gravity, no ground: the centre of mass's x velocity is constant
    # standing still 3 s from the level start: the ground carries the weight, the sway dies out
    from cases import MODELS
    key = MODELS["biped2_float"]["key"]
    r = Robot(links, {})
    r.u = list(key) * 2
    x = np.concatenate([r.standing(key), np.zeros(n)])
    x0 = x.copy()
    for _ in range(int(3.0 / 2.5e-4)):
        x = r.rk4(x, 2.5e-4)
    _, pts = r.contact_forces(x[:n], x[n:])
    load = sum(p[2] for p in pts)
    check("standing: the ground carries the weight", abs(load - total * G) < 1e-3 * total * G,
          f"{load:.2f} N for {total * G:.2f} N")
    # (the servos give under the weight: the knees' ~12 N·m against kp 300 sink the trunk a few mm)
    check("standing: the trunk settles upright", np.max(np.abs(x[:3] - x0[:3])) < 0.03
          and np.max(np.abs(x[n:])) < 0.02, f"trunk moved {np.round(x[:3] - x0[:3], 4)}, "
          f"|q̇| {np.max(np.abs(x[n:])):.1e}")
    try:
        import mujoco
    except ImportError:
        print("skip the comparison with MuJoCo: no mujoco module")
    else:  # the hand-made links against the compiled nominal model (a check of this file only)
        m = mujoco.MjModel.from_xml_path(os.path.join(HERE, "models", "biped2.xml"))
        for l in links:
            if not l["parts"]:
                continue
            bid = m.jnt_bodyid[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, l["joint"])]
            (mass, c, iy), = l["parts"]
            good = (abs(mass - m.body_mass[bid]) < 1e-9 and np.allclose(c, m.body_ipos[bid][[0, 2]], atol=1e-9)
                    and abs(iy - m.body_inertia[bid][1]) < 1e-6 * iy)
            check(f"{l['name']} vs MuJoCo", good, f"I_yy {iy:.6g} by hand, {m.body_inertia[bid][1]:.6g} compiled")
        d = mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, d, 0)
        mujoco.mj_forward(m, d)
        feet = [m.jnt_bodyid[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j)] for j in ("left_ankle", "right_ankle")]
        o, th, _, _ = Tree(links).frames(np.array(d.qpos), np.zeros(n))  # the same joint order
        for k, b in enumerate(feet):
            i = 5 if k == 0 else 8
            check(f"ankle {k} place vs MuJoCo", np.allclose(o[i], d.xpos[b][[0, 2]], atol=1e-9),
                  f"{np.round(o[i], 4)} by hand, {np.round(d.xpos[b][[0, 2]], 4)} compiled")
    print("selftest", "passed" if ok else "FAILED")
    return ok


if __name__ == "__main__":
    if sys.argv[1:] == ["--selftest"]:
        sys.exit(0 if selftest() else 1)
    from cases import CASES, MODELS  # noqa: E402
    for a in sys.argv[1:]:
        if CASES.get(a, {}).get("sim") != "float":
            sys.exit(f"floatsim.py: `{a}` is not a free-base case")
        main(a, CASES, MODELS)
