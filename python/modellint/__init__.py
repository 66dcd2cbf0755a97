"""modellint from Python: lint MuJoCo/URDF robot models, measure and fit the sim-to-real gap.

    import modellint
    findings = modellint.lint("robot.xml")                 # list of Finding
    gap = modellint.gap("robot.xml", ["logs/"])             # GapResult
    fit = modellint.fit("robot.xml", ["logs/"], told=["viscous_damping@elbow"])
    fit.write_model("robot_fitted.xml")

Each call runs the same library code as the `modellint` command with the same options and
returns what `--format json` prints, as typed objects (`.raw` holds the JSON itself). Options
are the CLI's flags as keywords (`control_hz=100` is `--control-hz 100`, a list repeats the
flag, `True` sets a switch). The work runs with the GIL released. See docs/python.md.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import warnings
from typing import Any, Callable, Iterable, List, Mapping, Optional, Union

from . import _native
from ._recordings import Recording, materialise
from ._types import (
    Effect,
    Finding,
    Findings,
    FitProgress,
    FitResult,
    Fold,
    HeldOutEpisode,
    RotationResult,
    GapResult,
    JointGap,
    Label,
    Location,
    ProbeResult,
    Quantity,
    SpecInfo,
)
from .errors import ModelError, ModellintError, RecordingError, UsageError, from_native

__version__ = _native.__version__

__all__ = [
    "lint",
    "gap",
    "fit",
    "Recording",
    "Finding",
    "Findings",
    "Location",
    "Quantity",
    "Label",
    "ProbeResult",
    "SpecInfo",
    "GapResult",
    "JointGap",
    "FitResult",
    "RotationResult",
    "Fold",
    "HeldOutEpisode",
    "Effect",
    "FitProgress",
    "ModellintError",
    "ModelError",
    "RecordingError",
    "UsageError",
    "ModellintWarning",
]

PathLike = Union[str, "os.PathLike[str]"]
Progress = Union[None, bool, Callable[[FitProgress], Any]]


class ModellintWarning(UserWarning):
    """A warning `modellint gap` / `fit` printed on stderr (also in the result's `warnings`)."""


def _flags(options: Mapping[str, Any]) -> List[str]:
    """Keyword options as the CLI's flags: `control_hz=100` → `--control-hz=100`; True → the
    switch alone; False / None → left out; a list or tuple → the flag once per item;
    `packages={"name": dir}` → `--package=name=dir` per entry."""
    out: List[str] = []
    for key, value in options.items():
        if key == "packages":
            for name, d in (value or {}).items():
                out.append(f"--package={name}={os.fspath(d)}")
            continue
        flag = "--" + key.replace("_", "-")
        if value is None or value is False:
            continue
        if value is True:
            out.append(flag)
        elif isinstance(value, (list, tuple)):
            out.extend(f"{flag}={_text(v)}" for v in value)
        else:
            out.append(f"{flag}={_text(value)}")
    return out


def _text(v: Any) -> str:
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, os.PathLike):
        return os.fspath(v)
    return str(v)


def _call(fn, *args, recordings=None):
    try:
        return fn(*args)
    except _native.NativeError as e:
        raise from_native(e, recordings) from None


def _warn(ws: Iterable[str]) -> None:
    for w in ws:
        warnings.warn(w, ModellintWarning, stacklevel=3)


class _Reporter:
    """The `progress` argument as a callback for the extension: the user's callable, else a
    tqdm bar on stderr when tqdm is importable (progress=None), else nothing (False)."""

    def __init__(self, progress: Progress, what: str) -> None:
        self.user = progress if callable(progress) else None
        self.bar = None
        if progress is None:
            try:
                from tqdm.auto import tqdm
            except ImportError:
                tqdm = None
            if tqdm is not None:
                unit = "episode" if what == "gap" else "rollout"
                self.bar = tqdm(desc=f"modellint {what}", unit=unit, file=sys.stderr, leave=False)

    def callback(self) -> Optional[Callable[[dict], None]]:
        return self if (self.user is not None or self.bar is not None) else None

    def __call__(self, d: dict) -> None:
        p = FitProgress(**d)
        if self.bar is not None:
            if p.total is not None and self.bar.total != p.total:
                self.bar.total = p.total
            n = p.done if p.done is not None else p.rollouts
            if n is not None and n > self.bar.n:
                self.bar.update(n - self.bar.n)
            if p.round is not None:
                what = f"{p.phase} {p.candidate[0]}/{p.candidate[1]}: {p.candidate[2]}" if p.candidate else p.phase
                self.bar.set_postfix_str(f"round {p.round} · {what}", refresh=False)
        if self.user is not None:
            self.user(p)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def lint(
    path: PathLike,
    spec: Optional[PathLike] = None,
    probes: bool = True,
    *,
    config: Optional[PathLike] = None,
    select: Optional[Iterable[str]] = None,
    ignore: Optional[Iterable[str]] = None,
    cache: bool = True,
    packages: Optional[Mapping[str, PathLike]] = None,
) -> Findings:
    """Lints one model (MJCF or URDF) as `modellint PATH --format json` does: the findings in
    the CLI's order, each confirmed or refuted by its MuJoCo probe unless `probes=False`
    (`--no-probe`). `spec`: the hardware spec TOML (default: `<model>.toml` beside the model,
    as the CLI); `config`: modellint.toml; `select` / `ignore`: rule ids or groups; `cache`:
    the lint cache (`--no-cache` when False); `packages`: URDF `package://` dirs.

    Raises ModelError (with .file, .line, .column) when the model, spec or config cannot be
    loaded (the CLI's exit code 2)."""
    argv = _flags(
        {
            "spec": spec,
            "config": config,
            "select": list(select or ()),
            "ignore": list(ignore or ()),
            "no_probe": not probes,
            "no_cache": not cache,
            "packages": packages,
        }
    )
    out = _call(_native.lint, argv + ["--", os.fspath(path)])
    return Findings.from_json(json.loads(out))


def gap(
    model: PathLike,
    recordings: Any,
    *,
    spec: Optional[PathLike] = None,
    progress: Progress = None,
    **options: Any,
) -> GapResult:
    """Replays `recordings` in MuJoCo and measures the sim-to-real gap, as `modellint gap MODEL
    RECORDINGS --format json`. `recordings`: a path (CSV, BAM JSON, a directory of them), a
    `Recording` or dict of arrays, or a list of these. `options`: the CLI's flags
    (`control_hz`, `command_timing`, `base`, `ignore_columns`, `no_command`, `report`=DIR …).
    `progress`: a callable given a FitProgress per replayed episode; None shows a tqdm bar when
    tqdm is installed; False nothing.

    Raises ModelError for the model, RecordingError (with .file, .line) for a recording,
    UsageError for an option the CLI rejects."""
    with tempfile.TemporaryDirectory(prefix="modellint-") as tmp:
        paths, written = materialise(recordings, tmp)
        argv = ["gap"] + _flags({"spec": spec, **options}) + ["--", os.fspath(model)] + paths
        rep = _Reporter(progress, "gap")
        try:
            out = _call(_native.gap, argv, rep.callback(), recordings=written)
        finally:
            rep.close()
    result = GapResult.from_json(json.loads(out))
    _warn(result.warnings)
    return result


def fit(
    model: PathLike,
    recordings: Any,
    *,
    spec: Optional[PathLike] = None,
    progress: Progress = None,
    **options: Any,
) -> Union[FitResult, RotationResult]:
    """Names the physics the model is missing from `recordings`, fits it and measures the
    held-out improvement, as `modellint fit MODEL RECORDINGS --format json`. `recordings` as for
    `gap`. `options`: the CLI's flags — `effects=[...]`, `joints="*knee*"`,
    `told=["viscous_damping@elbow"]` (no search: fit exactly that), `holdout`, `holdout_by="KEY=VALUE"`,
    `window`, `start_estimate`, `write_model`, `write_actuators`, `report`, the replay options of
    `gap`. `progress`: a callable given a FitProgress (round, phase, candidate, rollouts) as the
    search goes; None shows a tqdm bar when tqdm is installed; False nothing.

    `holdout_by="KEY"` (no `=VALUE`) holds out every value of the metadata KEY in turn, one fit
    per value, as `fit --holdout-by KEY`: the result is then a RotationResult.

    Ctrl-C (KeyboardInterrupt) stops the fit within about a second and is raised; so is an
    exception the progress callback raises (the fit stops at once).

    `FitResult.write_model(path)` writes the fitted model afterwards."""
    with tempfile.TemporaryDirectory(prefix="modellint-") as tmp:
        paths, written = materialise(recordings, tmp)
        argv = ["fit"] + _flags({"spec": spec, **options}) + ["--", os.fspath(model)] + paths
        rep = _Reporter(progress, "fit")
        try:
            out, native = _call(_native.fit, argv, rep.callback(), recordings=written)
        finally:
            rep.close()
    d = json.loads(out)
    result = RotationResult.from_json(d) if "holdout_by" in d else FitResult.from_json(d, native)
    _warn(result.warnings)
    return result
