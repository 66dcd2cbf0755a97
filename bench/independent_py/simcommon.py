"""What the independent simulators share (realsim.py: MuJoCo; chainsim.py and floatsim.py: numpy
planar physics of their own): a case's output directory and episode plan, the controller's
ticks, the planar links' mass properties and concealed body effects, RK4 and the stepping
between command switches. No physics of a particular robot here, and no MuJoCo.
"""
import math
import os
import shutil

import numpy as np

from reclog import CTRL_HZ, SETTLE_S

# ---------------- a case: where it is written, its episodes ----------------


def case_setup(case, cases, models, here):
    """(case, model config, logging config, output directory) of `case`; the directory made
    afresh with episodes/ and the nominal model copied in as nominal.xml."""
    c = cases[case]
    mcfg = models[c["model"]]
    cfg = dict(mcfg)
    cfg.update(c.get("logging", {}))
    out = os.path.join(os.environ.get("INDEP_OUT", os.path.join(here, "out")), "data", case)
    if os.path.exists(out):
        shutil.rmtree(out)
    os.makedirs(os.path.join(out, "episodes"))
    # The model `fit` is given: the simulated robot's own file unless the case gives the robot
    # file a user would have (`nominal`: a floating base the recordings hold on a stand).
    shutil.copy(os.path.join(here, "models", mcfg.get("nominal", mcfg["xml"])),
                os.path.join(out, "nominal.xml"))
    return c, mcfg, cfg, out


def episode_plan(c, out):
    """[(index, split, seconds, csv path)] of a case: `episodes` (6) of `seconds` (5 s), the
    `heldout` ones (the last) split off."""
    n = c.get("episodes", 6)
    secs = c.get("seconds", 5.0)
    heldout = set(c.get("heldout", [n - 1]))
    return [(e, "heldout" if e in heldout else "train", secs,
             os.path.join(out, "episodes", f"ep_{e:02d}.csv")) for e in range(n)]


def episode_file(out_csv):
    """An episode's file as truth.json names it (relative to the case directory)."""
    return os.path.relpath(out_csv, os.path.dirname(os.path.dirname(out_csv)))


def ticks(cfg, seconds, t0_ctrl):
    """The controller's ticks in recording time, from before the settle to after the end:
    (rate, tick times, issued_index) where issued_index(t) is the index of the tick in force
    (issued) at time t."""
    ctrl_hz = float(cfg.get("ctrl_hz", CTRL_HZ))
    kmin = math.floor((-SETTLE_S - 0.1 - t0_ctrl) * ctrl_hz)
    kmax = math.ceil((seconds + 0.1 - t0_ctrl) * ctrl_hz)
    tick_t = t0_ctrl + np.arange(kmin, kmax + 1) / ctrl_hz

    def issued_index(t):
        return int(math.floor((t - t0_ctrl) * ctrl_hz + 1e-9)) - kmin

    return ctrl_hz, tick_t, issued_index


# ---------------- planar links: parts (mass, centre (x, z), I_yy) ----------------


def capsule_iyy(m, r, length):
    """Moment about an axis across a capsule through its centre: a cylinder of `length` and two
    hemispheres of radius r, one density; a hemisphere's own moment 83/320 m r^2 about its
    centre of mass, 3r/8 from its flat face."""
    vc, vh = math.pi * r * r * length, 2.0 / 3.0 * math.pi * r ** 3
    mc, mh = m * vc / (vc + 2 * vh), m * vh / (vc + 2 * vh)
    cyl = mc * (r * r / 4 + length * length / 12)
    hemi = mh * (83.0 / 320.0 * r * r + (length / 2 + 3 * r / 8) ** 2)
    return cyl + 2 * hemi


def box_iyy(m, hx, hz):
    """Moment about y through the centre of a box of half sizes hx (x) and hz (z)."""
    return m * ((2 * hx) ** 2 + (2 * hz) ** 2) / 12.0


def link_inertia(parts):
    """A link's mass, centre of mass (x, z) and moment about y through it, from its parts."""
    m = sum(p[0] for p in parts)
    c = tuple(sum(p[0] * p[1][k] for p in parts) / m for k in range(2))
    i = sum(iy + pm * ((pc[0] - c[0]) ** 2 + (pc[1] - c[1]) ** 2) for pm, pc, iy in parts)
    return m, c, i


def with_body_effects(links, eff):
    """A copy of `links` with the concealed body effects of `eff["bodies_by_joint"]` composed
    by hand into the parts of the link their joint moves: a payload (a solid sphere added), a
    centre-of-mass shift (every part moved) and an inertia scale (the moment about y through
    the link's centre of mass × s, mass and centre of mass kept: a massless part at the centre
    of mass holding the difference)."""
    links = [dict(l, parts=list(l["parts"])) for l in links]
    for l in links:
        b = eff.get("bodies_by_joint", {}).get(l["joint"])
        if not b:
            continue
        if "payload" in b:
            pl = b["payload"]
            r = pl.get("radius", 0.03)
            l["parts"].append((pl["mass"], (pl["pos"][0], pl["pos"][2]), 0.4 * pl["mass"] * r * r))
        if "com_shift" in b:
            d = b["com_shift"]
            l["parts"] = [(m, (c[0] + d[0], c[1] + d[2]), iy) for m, c, iy in l["parts"]]
        if "inertia_scale" in b:
            _, c0, i0 = link_inertia(l["parts"])
            l["parts"].append((0.0, c0, (b["inertia_scale"] - 1.0) * i0))
    return links


def body_truth(links, eff):
    """truth.json `_bodies` in the schema score.py reads (3-vectors, y = 0), from the nominal
    links."""
    out = {}
    for bname, b in eff.get("bodies", {}).items():
        l = next(l for l in links if l["joint"] == b["joint"])
        m0, c0, i0 = link_inertia(l["parts"])
        r = {"nominal_mass": m0, "nominal_com": [c0[0], 0.0, c0[1]], "joint_axis": [0.0, 1.0, 0.0],
             "joint": b["joint"]}
        if "payload" in b:
            r["payload"] = {"mass": b["payload"]["mass"], "pos": list(b["payload"]["pos"])}
        if "com_shift" in b:
            r["com_shift"] = list(b["com_shift"])
        if "inertia_scale" in b:  # about y (the joint axis) only: the in-plane moment
            r.update(nominal_inertia=[i0, i0, i0], nominal_iquat=[1.0, 0.0, 0.0, 0.0],
                     inertia_scale=[1.0, b["inertia_scale"], 1.0])
        out[bname] = r
    return out


# ---------------- integration ----------------


class Rk4:
    """Classical RK4 on `self.deriv(x) → (dx/dt, servo torques)`, keeping each servo's peak
    |torque| (at the steps' starts) in `self.peak`."""

    def rk4(self, x, h):
        k1, tau = self.deriv(x)
        k2, _ = self.deriv(x + 0.5 * h * k1)
        k3, _ = self.deriv(x + 0.5 * h * k2)
        k4, _ = self.deriv(x + h * k3)
        self.peak = np.maximum(self.peak, np.abs(np.asarray(tau)))
        return x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def run_commands(robot, x, n, tick_t, cmd, issued_index, seconds, h_max, after_tick=None):
    """Steps `robot` (an Rk4 with a command vector `u`) from the settle's start to 50 ms past
    the end, a step never straddling a tick (the command switches exactly there), at most
    `h_max`. Returns the times, q and q̇ (the first n of the state and the n after them) and
    each q's least and largest value; `after_tick(t, x)` is called at every tick."""
    t_end = seconds + 0.05
    T, Q, QD = [-SETTLE_S], [x[:n].copy()], [x[n:2 * n].copy()]
    t = -SETTLE_S
    edges = [tt for tt in tick_t if -SETTLE_S < tt < t_end] + [t_end]
    qmin, qmax = x[:n].copy(), x[:n].copy()
    for edge in edges:
        robot.u = [float(v) for v in cmd[max(issued_index(t + 1e-9), 0)]]
        steps = max(1, math.ceil((edge - t) / h_max - 1e-9))
        h = (edge - t) / steps
        for _ in range(steps):
            x = robot.rk4(x, h)
            t += h
            T.append(t); Q.append(x[:n].copy()); QD.append(x[n:2 * n].copy())
            qmin, qmax = np.minimum(qmin, x[:n]), np.maximum(qmax, x[:n])
        if after_tick is not None:
            after_tick(t, x)
        t = edge
    return np.asarray(T), np.asarray(Q), np.asarray(QD), qmin, qmax


def check_ranges(links, qmin, qmax, why=""):
    """Each link with a `range` stayed inside it (the simulators model no joint limits)."""
    for i, l in enumerate(links):
        if "range" in l:
            assert l["range"][0] <= qmin[i] and qmax[i] <= l["range"][1], \
                f"{l['joint']} left its range: [{qmin[i]:.3f}, {qmax[i]:.3f}]{why}"
