#!/usr/bin/env python3
"""Where a free-base recording's residual lives, for model variants (issue 48's free-base control).

usage: free_base_residual.py CASE_DIR EPISODE.csv [VARIANT...]

Replays one episode of a floatsim.py case (CASE_DIR/nominal.xml, the biped of models/biped2.xml)
in MuJoCo's own Python bindings — not modellint's replay — from the first row's positions and
velocities, the commands held per control tick as recorded, and prints per recorded joint the
residual's mean and standard deviation [mrad], then for each sole its absolute pitch (planar: the
sum of root_pitch, hip, knee and ankle) recorded and its residual: on a compliant floor the soles
tilt where a model's stiffer contact keeps them flat, which no change of a body can reproduce.

VARIANT (each replayed after the model as given; several joined by "+" apply together):
  com=X,Z            the trunk's centre of mass at (X, Z) in its frame (the model: 0, 0.2)
  inertia=Z,IYY      the trunk's inertial at height Z with moment IYY about y [kg m^2]
  contact=SOLREF/SOLIMP  solref and solimp on the feet and floor ("0.04 1/0.5 0.9 0.001")
"""
import sys

import numpy as np

JOINTS = ["root_x", "root_z", "root_pitch"] + [f"{s}_{j}" for s in ("left", "right")
                                               for j in ("hip_pitch", "knee", "ankle")]
ACTUATED = JOINTS[3:]
TRUNK_GEOM = '<geom name="trunk" type="box" pos="0 0 0.2" size="0.08 0.12 0.2" mass="8"/>'
FRICTION = 'friction="0.9 0.005 0.0001"/>'


def variant_xml(xml, v):
    if v == "as given":
        return xml
    if "+" in v:
        for part in v.split("+"):
            xml = variant_xml(xml, part)
        return xml
    kind, arg = v.split("=", 1)
    if kind == "com":
        x, z = arg.split(",")
        new = TRUNK_GEOM.replace('pos="0 0 0.2"', f'pos="{x} 0 {z}"')
    elif kind == "inertia":
        z, iyy = arg.split(",")
        # x and z moments large enough for any IYY (a planar model moves only about y)
        new = (f'<inertial pos="0 0 {z}" mass="8" diaginertia="0.5 {iyy} 0.5"/>'
               + TRUNK_GEOM.replace('mass="8"', 'mass="0"'))
    elif kind == "contact":
        ref, imp = arg.split("/")
        out = xml.replace(FRICTION, f'friction="0.9 0.005 0.0001" solref="{ref}" solimp="{imp}"/>')
        assert out != xml, "no contact geoms found"
        return out
    else:
        sys.exit(f"free_base_residual.py: unknown variant `{v}`")
    assert TRUNK_GEOM in xml, "not biped2's trunk"
    return xml.replace(TRUNK_GEOM, new)


def read_csv(path):
    lines = [ln for ln in open(path) if not ln.startswith("#")]
    meta = {ln[2:].split(":")[0]: ln.split(":", 1)[1].strip() for ln in open(path)
            if ln.startswith("# ") and ":" in ln}
    head = lines[0].strip().split(",")
    data = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])
    return data, {h: i for i, h in enumerate(head)}, meta


def replay(mujoco, xml, data, col, meta):
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    adr = [m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j)] for j in JOINTS]
    vdr = [m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j)] for j in JOINTS]
    for k, j in enumerate(JOINTS):
        d.qpos[adr[k]] = data[0, col[j + ".q"]]
        d.qvel[vdr[k]] = data[0, col[j + ".qd"]]
    t = data[:, 0]
    hz, t0 = float(meta["control_rate_hz"]), float(meta["control_t0_s"])
    tick = np.floor((t - t0) * hz)
    cmd_cols = [col[j + ".q_cmd"] for j in ACTUATED]
    out = np.zeros((len(t), len(JOINTS)))
    out[0] = [d.qpos[a] for a in adr]
    cmd, r, now = data[0, cmd_cols], 1, t[0]
    while r < len(t):
        rows = np.nonzero(tick == np.floor((now - t0) * hz))[0]
        if len(rows):
            cmd = data[rows[0], cmd_cols]
        d.ctrl[:] = cmd
        mujoco.mj_step(m, d)
        now += m.opt.timestep
        while r < len(t) and t[r] <= now + 1e-12:
            out[r] = [d.qpos[a] for a in adr]
            r += 1
    return out


def main(argv):
    if len(argv) < 2:
        sys.exit(__doc__)
    import mujoco
    case, episode, variants = argv[0], argv[1], ["as given"] + argv[2:]
    xml = open(f"{case}/nominal.xml").read()
    data, col, meta = read_csv(episode)
    real = np.array([data[:, col[j + ".q"]] for j in JOINTS]).T
    soles = {"left": [2, 3, 4, 5], "right": [2, 6, 7, 8]}
    for side, idx in soles.items():
        p = real[:, idx].sum(1)
        print(f"{side} sole pitch recorded: mean {1e3 * p.mean():+.2f} std {1e3 * p.std():.2f} mrad")
    for v in variants:
        res = real - replay(mujoco, variant_xml(xml, v), data, col, meta)
        cells = " ".join(f"{j}:{1e3 * res[:, k].mean():+.2f}/{1e3 * res[:, k].std():.2f}"
                         for k, j in enumerate(JOINTS))
        tilt = " ".join(f"{s}_sole:{1e3 * np.sqrt((res[:, i].sum(1) ** 2).mean()):.2f}"
                        for s, i in soles.items())
        print(f"{v:28s} rms {1e3 * np.sqrt((res ** 2).mean()):.3f} | {cells} | {tilt}")


if __name__ == "__main__":
    main(sys.argv[1:])
