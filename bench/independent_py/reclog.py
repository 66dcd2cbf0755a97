"""Logging shared by the independent simulators (realsim.py: MuJoCo; chainsim.py: numpy only).

The controller's command generator and the robot's recorder: an asynchronous ~rec_hz recorder
with jitter, drops, position noise, an n-bit encoder and velocity noise, writing the CSV of
docs/recording-format.md. Logging only: no physics, no MuJoCo.
"""
import math

import numpy as np

CTRL_HZ = 100.0  # default controller rate; a model may set its own `ctrl_hz` (cases.py)
SETTLE_S = 2.0


# ---------------- command generation (per episode) ----------------
def lowpass2(x, fc, fs):
    # critically damped 2nd-order IIR (two cascaded 1st-order), forward only
    a = math.exp(-2 * math.pi * fc / fs)
    y1 = np.zeros_like(x); y2 = np.zeros_like(x)
    for i in range(1, len(x)):
        y1[i] = a * y1[i - 1] + (1 - a) * x[i]
        y2[i] = a * y2[i - 1] + (1 - a) * y1[i]
    return y2


def make_commands(rng, tick_t, centre, amp, seconds, ctrl_hz=CTRL_HZ):
    """Command per tick (ticks at tick_t, recording time) for each joint. Hold 0.3 s, then a
    shuffled mix of 3 of: linear chirp, smoothed random walk, ramped steps, multisine."""
    nj = len(centre)
    kinds = list(rng.permutation(["chirp", "walk", "steps", "multisine"]))[:3]
    cuts = np.sort(rng.uniform(0.3, seconds, 2))
    bounds = [0.3, cuts[0], cuts[1], seconds + 0.05]
    segs = [(kinds[i], bounds[i], bounds[i + 1]) for i in range(3)]
    cmd = np.tile(np.asarray(centre, float), (len(tick_t), 1))
    for j in range(nj):
        A = amp[j]
        prev = 0.0
        for kind, t0, t1 in segs:
            sel = (tick_t >= t0) & (tick_t < t1)
            if not sel.any():
                continue
            tt = tick_t[sel] - t0
            T = t1 - t0
            if kind == "chirp":
                f0, f1 = 0.2, rng.uniform(3.0, 4.5)
                ph = 2 * math.pi * (f0 * tt + 0.5 * (f1 - f0) / T * tt ** 2)
                y = 0.7 * A * np.sin(ph + rng.uniform(0, 2 * math.pi))
            elif kind == "walk":
                w = rng.normal(0, 1, len(tt) + 200)
                y = lowpass2(w, rng.uniform(0.8, 2.0), ctrl_hz)[200:]
                y = A * y / (np.max(np.abs(y)) + 1e-9)
            elif kind == "steps":
                y = np.zeros(len(tt)); lvl = prev; tnext = 0.0; tr = 0.06
                start_lvl = prev; tstart = 0.0; target = prev
                for i, t in enumerate(tt):
                    if t >= tnext:
                        start_lvl = target if t > 0 else prev
                        target = rng.uniform(-A, A); tstart = t
                        tnext = t + rng.uniform(0.35, 0.9)
                    s = min(1.0, (t - tstart) / tr)
                    y[i] = start_lvl + (target - start_lvl) * s
            else:  # multisine
                y = np.zeros(len(tt))
                for _ in range(3):
                    y += np.sin(2 * math.pi * rng.uniform(0.3, 2.5) * tt + rng.uniform(0, 2 * math.pi))
                y = A * 0.9 * y / 3.0
            # blend from previous end value so segments join smoothly-ish
            y = y + (prev - y[0]) * np.exp(-tt / 0.12)
            cmd[sel, j] = centre[j] + y
            prev = y[-1]
    return cmd, [{"kind": k, "t0": float(a), "t1": float(min(b, seconds))} for k, a, b in segs]


def record(rng, cfg, T, Q, QD, cmd, issued_index, offset, seconds, out_csv, ep_idx, split,
           joints, t0_ctrl, ctrl_hz, note="recorded by an independent tryout simulator", passive=0):
    """Sample the trajectory (T, Q, QD: the robot's states at its integration times) with the
    asynchronous recorder and write the CSV. Returns (rows written, rows dropped). The first
    `passive` joints (a free base's) are written without a command column."""
    nj = len(joints)
    # asynchronous recorder
    ts = [0.0]
    per = 1.0 / cfg["rec_hz"]
    while True:
        nxt = ts[-1] + per * (1 + rng.uniform(-cfg["jitter"], cfg["jitter"]))
        if nxt > seconds:
            break
        ts.append(nxt)
    ts = np.array(ts)
    keep = np.ones(len(ts), bool)
    drops = rng.random(len(ts)) < cfg["drop"]
    drops[0] = drops[-1] = False
    keep &= ~drops
    quantum = None if cfg["bits"] is None else 2 * math.pi / (2 ** cfg["bits"])
    rows = []
    for t in ts[keep]:
        q = np.array([np.interp(t, T, Q[:, i]) for i in range(nj)])
        qd = np.array([np.interp(t, T, QD[:, i]) for i in range(nj)])
        qm = q + np.array(offset) + rng.normal(0, cfg["q_noise"], nj)
        if quantum:  # the joints' encoders (a free base's pose comes from an estimator)
            qm[passive:] = np.round(qm[passive:] / quantum) * quantum
        qdm = qd + rng.normal(0, cfg["qd_noise"], nj)
        qc = cmd[issued_index(t)]
        rows.append((t, qm, qdm, qc))

    # `rec_start` (s): the log begins that long after the settle, mid-motion, its first row
    # wherever the recorder's clock puts it (not on a control tick or a physics step).
    rows = [r for r in rows if r[0] >= cfg.get("rec_start", 0.0)]
    with open(out_csv, "w") as f:
        f.write(f"# robot: {cfg['robot']}\n# episode: {ep_idx}\n# split: {split}\n")
        # `declared_hz`: the rate the header states when the controller really runs at
        # `ctrl_hz` on the recorder's clock (a policy loop off its nominal rate, or two clocks
        # that drift apart).
        f.write(f"# control_rate_hz: {cfg.get('declared_hz', ctrl_hz):g}\n")
        # `declare_t0: False`: the log does not say when the controller ticks (most real logs
        # do not); its first row is wherever the recorder's clock puts it.
        if cfg.get("declare_t0", True):
            f.write(f"# control_t0_s: {t0_ctrl}\n")
        f.write(f"# note: {note}\n")
        f.write("t," + ",".join(f"{j}.q,{j}.qd" + (",{j}.q_cmd".format(j=j) if i >= passive else "")
                                for i, j in enumerate(joints)) + "\n")
        for t, qm, qdm, qc in rows:
            f.write(f"{t:.6f}," + ",".join(f"{qm[i]:.7f},{qdm[i]:.6f}" + (f",{qc[i]:.7f}" if i >= passive else "")
                                          for i in range(nj)) + "\n")
    return len(rows), int(drops.sum())
