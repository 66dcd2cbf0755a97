"""Recordings given as arrays. Each is written as a CSV recording (docs/recording-format.md)
into a temporary directory and read by the same reader as `modellint gap file.csv`: arrays
and the equivalent CSV file give the same result, and every check of the reader (monotonic
time, degrees, joint names, a driven joint without its command) applies to arrays too. Floats
are written with `repr`, which round-trips every float64 exactly."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple

# Per-joint signals, in the CSV's column order.
SIGNALS = ("q", "qd", "q_cmd", "tau", "kp", "kd", "enabled")


@dataclass
class Recording:
    """One episode as arrays: `t` [s] and, per signal, a mapping joint name → array (numpy
    arrays, lists, anything iterable of numbers, each as long as `t`).

    `q` (measured position [rad or m]) is required for each joint; `q_cmd` (the position
    command in force at each row) is required for a joint an actuator drives. `meta` holds
    further header keys: `split` ('train' | 'heldout'), `command_timing`, `base`, …"""

    t: Sequence[float]
    q: Mapping[str, Sequence[float]]
    q_cmd: Mapping[str, Sequence[float]] = field(default_factory=dict)
    qd: Mapping[str, Sequence[float]] = field(default_factory=dict)
    tau: Mapping[str, Sequence[float]] = field(default_factory=dict)
    kp: Mapping[str, Sequence[float]] = field(default_factory=dict)
    kd: Mapping[str, Sequence[float]] = field(default_factory=dict)
    enabled: Mapping[str, Sequence[Any]] = field(default_factory=dict)
    name: Optional[str] = None
    control_rate_hz: Optional[float] = None
    control_t0_s: Optional[float] = None
    meta: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def from_mapping(cls, d: Mapping[str, Any], name: Optional[str] = None) -> "Recording":
        """From a dict: `t` (or `time`) and either per-signal dicts (`{"q": {"elbow": arr},
        "q_cmd": {"elbow": arr}}`) or the CSV's column names (`{"elbow.q": arr,
        "elbow.q_cmd": arr}`); optional `name`, `control_rate_hz`, `control_t0_s`, `meta`."""
        if "t" in d and "time" in d:
            raise ValueError("recording: give `t` or `time`, not both")
        if "t" not in d and "time" not in d:
            raise ValueError("recording: no `t` (or `time`) array")
        signals: Dict[str, Dict[str, Any]] = {s: {} for s in SIGNALS}
        known = {"t", "time", "name", "control_rate_hz", "control_t0_s", "meta"}
        for key, value in d.items():
            if key in known:
                continue
            if key in SIGNALS:
                if not isinstance(value, Mapping):
                    raise ValueError(
                        f"recording: `{key}` must map joint names to arrays, got {type(value).__name__}"
                    )
                signals[key].update(value)
                continue
            joint, dot, sig = key.rpartition(".")
            if not dot or sig not in SIGNALS or not joint:
                raise ValueError(
                    f"recording: unknown key `{key}`: expected t, {', '.join(SIGNALS)} (dicts "
                    f"joint → array) or `<joint>.<signal>` columns"
                )
            signals[sig][joint] = value
        return cls(
            t=d["t"] if "t" in d else d["time"],
            name=d.get("name", name),
            control_rate_hz=d.get("control_rate_hz"),
            control_t0_s=d.get("control_t0_s"),
            meta=d.get("meta") or {},
            **signals,
        )

    def to_csv(self) -> Tuple[str, int]:
        """The CSV text and its number of lines before the first data row."""
        t = _floats(self.t, "t")
        joints: List[str] = list(self.q)
        for sig in SIGNALS[1:]:
            for j in getattr(self, sig):
                if j not in self.q:
                    raise ValueError(f"recording: joint `{j}` has `{sig}` but no `q`")
        header = ["t"]
        columns: List[List[str]] = [t]
        for j in joints:
            for sig in SIGNALS:
                values = getattr(self, sig).get(j)
                if values is None:
                    continue
                col = (
                    [str(int(bool(v))) for v in values]
                    if sig == "enabled"
                    else _floats(values, f"{j}.{sig}")
                )
                if len(col) != len(t):
                    raise ValueError(
                        f"recording: `{j}.{sig}` has {len(col)} values, `t` has {len(t)}"
                    )
                header.append(f"{j}.{sig}")
                columns.append(col)
        meta: Dict[str, Any] = {}
        if self.control_rate_hz is not None:
            meta["control_rate_hz"] = repr(float(self.control_rate_hz))
        if self.control_t0_s is not None:
            meta["control_t0_s"] = repr(float(self.control_t0_s))
        meta.update(self.meta)
        lines = ["# format: modellint-recording 1"]
        for k, v in meta.items():
            if any(c in str(k) + str(v) for c in "\r\n") or ":" in str(k):
                raise ValueError(f"recording: metadata `{k}` must be one line without ':' in its key")
            lines.append(f"# {k}: {v}")
        lines.append(",".join(header))
        head = len(lines)
        lines.extend(",".join(row) for row in zip(*columns))
        return "\n".join(lines) + "\n", head


def _floats(values: Iterable[Any], what: str) -> List[str]:
    out = []
    for v in values:
        x = float(v)
        # The reader names a non-finite value at its line; `repr` gives 'nan' / 'inf' for it.
        out.append(repr(x) if math.isfinite(x) else str(x))
    return out


def is_in_memory(r: Any) -> bool:
    return isinstance(r, (Recording, Mapping))


def materialise(
    recordings: Any, tmpdir: str
) -> Tuple[List[str], Dict[str, Tuple[str, int]]]:
    """Paths for the CLI: files and directories as given, in-memory recordings written as CSV
    files into `tmpdir`. Also maps each written file to (recording name, header lines) for
    error messages."""
    if isinstance(recordings, (str, os.PathLike)) or is_in_memory(recordings):
        recordings = [recordings]
    paths: List[str] = []
    written: Dict[str, Tuple[str, int]] = {}
    for k, r in enumerate(recordings):
        if isinstance(r, (str, os.PathLike)):
            paths.append(os.fspath(r))
            continue
        if isinstance(r, Mapping):
            r = Recording.from_mapping(r)
        if not isinstance(r, Recording):
            raise TypeError(
                f"recordings[{k}]: expected a path, a dict of arrays or a modellint.Recording, "
                f"got {type(r).__name__}"
            )
        name = r.name or f"recording_{k:03d}"
        if os.sep in name or name in (".", ".."):
            raise ValueError(f"recording name {name!r}: must be a plain file name")
        text, head = r.to_csv()
        path = os.path.join(tmpdir, f"{k:03d}", f"{name}.csv")
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)
        paths.append(path)
        written[os.path.abspath(path)] = (name, head)
    if not paths:
        raise ValueError("no recordings given")
    return paths, written
