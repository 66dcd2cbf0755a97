"""Write a CSV dataset's episodes in other log formats with each format's own Python library.

    python3 write_logs.py FORMAT SRC_DIR OUT_DIR

SRC_DIR is a `modellint synth --out` dataset (episodes/*.csv, truth_commands/*.csv). The CSV is
read here with Python's csv module, not with modellint. Written under OUT_DIR:

* csv/NAME.csv        the equivalent CSV (t, <j>.q, <j>.qd, <j>.q_cmd, control_rate_hz; for
                      mcap also control_t0_s = the first command's stamp)
* npz  (numpy):       npz/NAME.npz with t, dof_pos, des_dof_pos, dof_vel (time x joint) in
                      DEGREES, joint_names, a scalar control_rate_hz
* pt   (torch):       pt/NAME.pt, torch.save of a dict: time (float64 tensor), dof_pos (a
                      non-contiguous float64 view: the transpose of a joint x time tensor),
                      des_dof_pos (a list of per-row float64 tensors, as a logger appends them),
                      dof_vel, joint_names (list of str), control_rate_hz (float); radians
* lerobot (pyarrow):  lerobot/meta/info.json (fps, names "main_<joint>") and
                      lerobot/data/chunk-000/file-000.parquet, every episode in one file
* lerobot32:          the same with the timestamp column in float32, as LeRobot writes it
* mcap (mcap, mcap-ros2-support): mcap/NAME.mcap, /joint_states (sensor_msgs/JointState, one
                      message per row) and /forward_position_controller/commands
                      (std_msgs/Float64MultiArray, one per control tick, from truth_commands),
                      stamped from 1.7e9 s (Unix-epoch-like)

Exit 3 when the format's library is not installed (the caller skips).
"""
import csv
import json
import math
import os
import sys


def read_csv(path):
    meta, rows, header = {}, [], None
    with open(path, newline="") as f:
        for line in f:
            line = line.rstrip("\n")
            if header is None and line.startswith("#"):
                k, _, v = line[1:].partition(":")
                meta[k.strip()] = v.strip()
                continue
            if header is None:
                header = next(csv.reader([line]))
                continue
            if line.strip():
                rows.append(next(csv.reader([line])))
    cols = {h: [float(r[i]) for r in rows] for i, h in enumerate(header)}
    joints = [h[:-2] for h in header if h.endswith(".q")]
    return meta, cols, joints


def write_equiv(out, name, meta, cols, joints, t0=None):
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, name + ".csv"), "w") as f:
        f.write("# control_rate_hz: %s\n" % meta["control_rate_hz"])
        if t0 is not None:
            f.write("# control_t0_s: %r\n" % t0)
        f.write(",".join(["t"] + [f"{j}.{s}" for j in joints for s in ("q", "qd", "q_cmd")]) + "\n")
        for i in range(len(cols["t"])):
            vals = [cols["t"][i]] + [cols[f"{j}.{s}"][i] for j in joints for s in ("q", "qd", "q_cmd")]
            f.write(",".join(repr(v) for v in vals) + "\n")


def main():
    fmt, src, out = sys.argv[1], sys.argv[2], sys.argv[3]
    try:
        if fmt == "npz":
            import numpy as np
        elif fmt == "pt":
            import torch
        elif fmt in ("lerobot", "lerobot32"):
            import pyarrow as pa
            import pyarrow.parquet as pq
        elif fmt == "mcap":
            from mcap_ros2.writer import Writer as Ros2Writer
        else:
            sys.exit("unknown format " + fmt)
    except ImportError as e:
        print("missing library: %s" % e, file=sys.stderr)
        sys.exit(3)
    names = sorted(n[:-4] for n in os.listdir(os.path.join(src, "episodes")) if n.endswith(".csv"))
    table = {"observation.state": [], "action": [], "observation.velocity": [], "timestamp": [],
             "frame_index": [], "episode_index": [], "index": []}
    fps = None
    for ei, name in enumerate(names):
        meta, cols, joints = read_csv(os.path.join(src, "episodes", name + ".csv"))
        n = len(cols["t"])
        q = [[cols[j + ".q"][i] for j in joints] for i in range(n)]
        qd = [[cols[j + ".qd"][i] for j in joints] for i in range(n)]
        qc = [[cols[j + ".q_cmd"][i] for j in joints] for i in range(n)]
        if fmt == "npz":
            write_equiv(os.path.join(out, "csv"), name, meta, cols, joints)
            os.makedirs(os.path.join(out, "npz"), exist_ok=True)
            deg = 180.0 / math.pi
            np.savez(os.path.join(out, "npz", name + ".npz"),
                     t=np.array(cols["t"]), dof_pos=np.array(q) * deg,
                     des_dof_pos=np.array(qc) * deg, dof_vel=np.array(qd) * deg,
                     joint_names=np.array(joints),
                     control_rate_hz=np.float64(meta["control_rate_hz"]))
        elif fmt == "pt":
            write_equiv(os.path.join(out, "csv"), name, meta, cols, joints)
            os.makedirs(os.path.join(out, "pt"), exist_ok=True)
            f64 = torch.float64
            torch.save({"time": torch.tensor(cols["t"], dtype=f64),
                        "dof_pos": torch.tensor(q, dtype=f64).t().contiguous().t(),
                        "des_dof_pos": [torch.tensor(r, dtype=f64) for r in qc],
                        "dof_vel": torch.tensor(qd, dtype=f64),
                        "joint_names": list(joints),
                        "control_rate_hz": float(meta["control_rate_hz"])},
                       os.path.join(out, "pt", name + ".pt"))
        elif fmt in ("lerobot", "lerobot32"):
            write_equiv(os.path.join(out, "csv"), name, meta, cols, joints)
            fps = float(meta["control_rate_hz"])
            for i in range(n):
                table["observation.state"].append(q[i])
                table["action"].append(qc[i])
                table["observation.velocity"].append(qd[i])
                table["timestamp"].append(cols["t"][i])
                table["frame_index"].append(i)
                table["episode_index"].append(ei)
                table["index"].append(len(table["index"]))
            feat = {"shape": [len(joints)], "dtype": "float64", "names": ["main_" + j for j in joints]}
            info = {"codebase_version": "v3.0", "fps": fps,
                    "features": {"observation.state": feat, "action": feat, "observation.velocity": feat}}
        elif fmt == "mcap":
            _, tc, _ = read_csv(os.path.join(src, "truth_commands", name + ".csv"))
            write_equiv(os.path.join(out, "csv"), name, meta, cols, joints, t0=tc["t"][0])
            os.makedirs(os.path.join(out, "mcap"), exist_ok=True)
            base = 1_700_000_000 * 10**9
            ns = lambda t: base + round(t * 1e9)
            js_schema = """std_msgs/Header header
string[] name
float64[] position
float64[] velocity
float64[] effort
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec"""
            fa_schema = """std_msgs/MultiArrayLayout layout
float64[] data
================================================================================
MSG: std_msgs/MultiArrayLayout
MultiArrayDimension[] dim
uint32 data_offset
================================================================================
MSG: std_msgs/MultiArrayDimension
string label
uint32 size
uint32 stride"""
            # Events in time order: the command of a tick before a row at the same time.
            events = [(ns(tc["t"][k]), 0, k) for k in range(len(tc["t"]))]
            events += [(ns(cols["t"][i]), 1, i) for i in range(n)]
            events.sort()
            with open(os.path.join(out, "mcap", name + ".mcap"), "wb") as f:
                w = Ros2Writer(f)
                js = w.register_msgdef("sensor_msgs/msg/JointState", js_schema)
                fa = w.register_msgdef("std_msgs/msg/Float64MultiArray", fa_schema)
                for stamp, kind, i in events:
                    if kind == 0:
                        msg = {"layout": {"dim": [{"label": "joints", "size": len(joints), "stride": len(joints)}],
                                          "data_offset": 0},
                               "data": [tc[j + ".q_cmd"][i] for j in joints]}
                        w.write_message("/forward_position_controller/commands", fa, msg, log_time=stamp,
                                        publish_time=stamp)
                    else:
                        msg = {"header": {"stamp": {"sec": stamp // 10**9, "nanosec": stamp % 10**9},
                                          "frame_id": ""},
                               "name": joints, "position": q[i], "velocity": qd[i], "effort": []}
                        w.write_message("/joint_states", js, msg, log_time=stamp, publish_time=stamp)
                w.finish()
    if fmt in ("lerobot", "lerobot32"):
        root = os.path.join(out, "lerobot")
        if fmt == "lerobot32":
            # As LeRobot stores it: 32-bit time stamps (frame_index / fps).
            table["timestamp"] = pa.array(table["timestamp"], type=pa.float32())
        os.makedirs(os.path.join(root, "meta"), exist_ok=True)
        os.makedirs(os.path.join(root, "data", "chunk-000"), exist_ok=True)
        with open(os.path.join(root, "meta", "info.json"), "w") as f:
            json.dump(info, f, indent=2)
        pq.write_table(pa.table(table), os.path.join(root, "data", "chunk-000", "file-000.parquet"))


if __name__ == "__main__":
    main()
