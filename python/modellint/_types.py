"""Typed results of the Python API, made from the JSON the CLI prints with `--format json`
(docs/schemas/findings.md for lint; `gap` and `fit` as in docs/python.md). Every object keeps
the JSON it was made from in `raw`, so nothing the CLI reports is out of reach."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Tuple

SEVERITIES = ("info", "warning", "error")


# ---------------------------------------------------------------- lint


@dataclass(frozen=True)
class Location:
    """The tightest span of a finding (1-based lines and columns)."""

    file: str
    line: int
    column: int
    end_line: int
    end_column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"


@dataclass(frozen=True)
class Quantity:
    """A value in SI units (`unit` '' or '1' for a ratio)."""

    value: float
    unit: str


@dataclass(frozen=True)
class Label:
    """A related place: the default class a value was inherited from, a spec line."""

    file: str
    line: int
    column: int
    message: str


@dataclass(frozen=True)
class ProbeResult:
    """What the MuJoCo probe run measured for a finding (docs/probes.md)."""

    name: str
    status: str  # confirmed | measured | inconclusive | refuted | skipped
    measured: Dict[str, float]
    note: Optional[str]
    reason: Optional[str]
    steps: Optional[int]
    preconditions: Tuple[Dict[str, Any], ...]

    @classmethod
    def from_json(cls, d: Optional[dict]) -> Optional["ProbeResult"]:
        if d is None:
            return None
        return cls(
            name=d["name"],
            status=d["status"],
            measured=dict(d.get("measured") or {}),
            note=d.get("note"),
            reason=d.get("reason"),
            steps=d.get("steps"),
            preconditions=tuple(d.get("preconditions") or ()),
        )


def _quantity(d: Optional[dict]) -> Optional[Quantity]:
    return None if d is None else Quantity(d["value"], d["unit"])


@dataclass(frozen=True)
class Finding:
    """One lint finding: which rule, how severe, where, what is wrong and the numbers."""

    rule: str
    severity: str  # error | warning | info
    message: str
    location: Location
    element: Optional[str]
    note: Optional[str]
    help: Optional[str]
    measured: Optional[Quantity]
    expected: Optional[Quantity]
    data: Dict[str, float]
    labels: Tuple[Label, ...]
    probe: Optional[ProbeResult]
    raw: Dict[str, Any] = field(repr=False, compare=False)

    @classmethod
    def from_json(cls, d: dict) -> "Finding":
        return cls(
            rule=d["rule"],
            severity=d["severity"],
            message=d["message"],
            location=Location(d["file"], d["line"], d["column"], d["end_line"], d["end_column"]),
            element=d.get("element"),
            note=d.get("note"),
            help=d.get("help"),
            measured=_quantity(d.get("measured")),
            expected=_quantity(d.get("expected")),
            data=dict(d.get("data") or {}),
            labels=tuple(
                Label(x["file"], x["line"], x["column"], x["message"]) for x in d.get("labels") or ()
            ),
            probe=ProbeResult.from_json(d.get("probe")),
            raw=d,
        )

    def at_least(self, severity: str) -> bool:
        """Severity at or above `severity` ('info' < 'warning' < 'error')."""
        return SEVERITIES.index(self.severity) >= SEVERITIES.index(severity)

    def __str__(self) -> str:
        return f"{self.location}: {self.severity} [{self.rule}] {self.message}"


@dataclass(frozen=True)
class SpecInfo:
    """The hardware spec in use, where it was looked for, and without one the rules skipped
    or weakened."""

    path: Optional[str]
    searched: Tuple[str, ...]
    skipped_rules: Tuple[str, ...]
    weakened_rules: Tuple[str, ...]


class Findings(list):
    """The findings of one model (a list of `Finding`, in the CLI's order), with the model
    path, the spec in use, the counts per severity and the JSON (`raw`)."""

    model: str
    spec: Optional[SpecInfo]
    summary: Dict[str, int]
    raw: Dict[str, Any]

    @classmethod
    def from_json(cls, d: dict) -> "Findings":
        out = cls(Finding.from_json(f) for f in d["findings"])
        out.model = d["model"]
        s = d.get("spec")
        out.spec = (
            None
            if s is None
            else SpecInfo(
                s.get("path"),
                tuple(s.get("searched", ())),
                tuple(s.get("skipped_rules", ())),
                tuple(s.get("weakened_rules", ())),
            )
        )
        out.summary = dict(d["summary"])
        out.raw = d
        return out

    def at_least(self, severity: str) -> List[Finding]:
        """The findings at or above `severity` (what `--fail-on severity` fails on)."""
        return [f for f in self if f.at_least(severity)]

    def __str__(self) -> str:
        """One line per finding (`file:line:col: severity [rule] message`) and the counts."""
        counts = ", ".join(f"{self.summary.get(s, 0)} {s}" for s in reversed(SEVERITIES))
        return "\n".join([str(f) for f in self] + [f"{self.model}: {counts}"])


# ---------------------------------------------------------------- gap


@dataclass(frozen=True)
class JointGap:
    """The gap on one joint (radians, rad/s; `corr` the real-vs-sim correlation)."""

    name: str
    region: Optional[str]
    samples: int
    mae: float
    rmse: float
    max: float
    corr: float
    vel_mae: Optional[float]
    vel_rmse: Optional[float]
    raw: Dict[str, Any] = field(repr=False, compare=False)

    @classmethod
    def from_json(cls, d: dict) -> "JointGap":
        return cls(
            d["name"],
            d.get("region"),
            d["samples"],
            d["mae"],
            d["rmse"],
            d["max"],
            d["corr"],
            d.get("vel_mae"),
            d.get("vel_rmse"),
            raw=d,
        )


@dataclass(frozen=True)
class GapResult:
    """`modellint gap`'s report: the recordings replayed in MuJoCo against the real traces
    (SI units: rad, rad/s; the gap scores are dimensionless, 0 = no gap)."""

    position_mae: float
    position_rmse: float
    position_max: float
    velocity_mae: Optional[float]
    velocity_rmse: Optional[float]
    correlation_mean: float
    gap_overall: float
    episodes: int
    samples: int
    duration_s: float
    per_joint: Tuple[JointGap, ...]
    diverged: Tuple[Any, ...]
    warnings: Tuple[str, ...]
    notes: Tuple[str, ...]
    raw: Dict[str, Any] = field(repr=False, compare=False)

    @classmethod
    def from_json(cls, d: dict) -> "GapResult":
        return cls(
            position_mae=d["position_mae"],
            position_rmse=d["position_rmse"],
            position_max=d["position_max"],
            velocity_mae=d.get("velocity_mae"),
            velocity_rmse=d.get("velocity_rmse"),
            correlation_mean=d["correlation_mean"],
            gap_overall=d["gap_overall"],
            episodes=d["episodes"],
            samples=d["samples"],
            duration_s=d["duration_s"],
            per_joint=tuple(JointGap.from_json(j) for j in d.get("per_joint", ())),
            diverged=tuple(d.get("diverged") or ()),
            warnings=tuple(d.get("warnings") or ()),
            notes=tuple(d.get("notes") or ()),
            raw=d,
        )

    def joint(self, name: str) -> JointGap:
        """The gap on joint `name` (KeyError when it was not scored)."""
        for j in self.per_joint:
            if j.name == name:
                return j
        raise KeyError(name)


# ---------------------------------------------------------------- fit


@dataclass(frozen=True)
class Effect:
    """A missing physical effect the fit kept: its parameters (SI, `fit --help` lists the
    units) with their standard errors (None: not determined by the data), the parameters the
    data do not determine (`unidentified`: their values are not answers), and the held-out
    position RMSE [rad] before and after it was added."""

    effect: str
    joints: Tuple[str, ...]
    params: Dict[str, float]
    stderr: Dict[str, Optional[float]]
    identifiable: bool
    unidentified: Tuple[str, ...]
    evidence: Dict[str, float]
    heldout_improvement: float
    heldout_rmse_before: float
    heldout_rmse_after: float
    raw: Dict[str, Any] = field(repr=False, compare=False)

    @classmethod
    def from_json(cls, d: dict) -> "Effect":
        return cls(
            effect=d["effect"],
            joints=tuple(d["joints"]),
            params=dict(d["params"]),
            stderr=dict(d["stderr"]),
            identifiable=d["identifiable"],
            unidentified=tuple(d.get("unidentified", ())),
            evidence=dict(d["evidence"]),
            heldout_improvement=d["heldout_improvement"],
            heldout_rmse_before=d["heldout_rmse_before"],
            heldout_rmse_after=d["heldout_rmse_after"],
            raw=d,
        )


@dataclass(frozen=True)
class FitProgress:
    """Where a running `fit` (or `gap`'s replay) is: passed to the `progress` callback."""

    phase: str
    round: Optional[int] = None
    candidate: Optional[Tuple[int, int, str]] = None
    simulations: Optional[int] = None
    rollouts: Optional[int] = None
    elapsed_s: Optional[float] = None
    done: Optional[int] = None
    total: Optional[int] = None


@dataclass(frozen=True)
class FitResult:
    """`modellint fit`'s result: the effects kept and the held-out episodes before → after
    (`before`, `after`: the gap on them without and with the effects)."""

    effects: Tuple[Effect, ...]
    before: GapResult
    after: GapResult
    split: Dict[str, Any]
    stopped_at_floor: bool
    warnings: Tuple[str, ...]
    notes: Tuple[str, ...]
    raw: Dict[str, Any] = field(repr=False, compare=False)
    _native: Any = field(default=None, repr=False, compare=False)

    @classmethod
    def from_json(cls, d: dict, native: Any = None) -> "FitResult":
        return cls(
            effects=tuple(Effect.from_json(e) for e in d["missing_physics"]),
            before=GapResult.from_json(d["before"]),
            after=GapResult.from_json(d["after"]),
            split=dict(d["split"]),
            stopped_at_floor=d["stopped_at_floor"],
            warnings=tuple(d.get("warnings") or ()),
            notes=tuple(d.get("notes") or ()),
            raw=d,
            _native=native,
        )

    def write_model(self, path) -> List[str]:
        """Writes the model with the fitted values MuJoCo can express (as `fit --write-model
        PATH`: the MJCF edited in place, each value in the file that holds it). Returns the
        notes: which files were written, what could not be expressed."""
        from . import errors
        from . import _native

        try:
            return list(self._native.write_model(str(path)))
        except _native.NativeError as e:
            raise errors.from_native(e) from None


# ---------------------------------------------------------------- holdout_by rotation


@dataclass(frozen=True)
class HeldOutEpisode:
    """One held-out episode of a rotation fold: its position MAE [rad] without and with the
    fold's effects."""

    source: str
    position_mae_before: float
    position_mae_after: float


@dataclass(frozen=True)
class Fold:
    """One fold of `holdout_by="KEY"`: the selection run with KEY = `value` held out."""

    value: str
    train: int
    effects: Tuple[Tuple[str, Tuple[str, ...], Dict[str, float]], ...]
    heldout: Tuple[HeldOutEpisode, ...]
    position_mae_before: float
    position_mae_after: float
    warnings: Tuple[str, ...]
    notes: Tuple[str, ...]
    raw: Dict[str, Any] = field(repr=False, compare=False)

    @classmethod
    def from_json(cls, d: dict) -> "Fold":
        return cls(
            value=d["value"],
            train=d["train"],
            effects=tuple((s["effect"], tuple(s["joints"]), dict(s["params"])) for s in d["selected"]),
            heldout=tuple(
                HeldOutEpisode(e["source"], e["position_mae_before"], e["position_mae_after"])
                for e in d["heldout"]
            ),
            position_mae_before=d["position_mae_before"],
            position_mae_after=d["position_mae_after"],
            warnings=tuple(d.get("warnings") or ()),
            notes=tuple(d.get("notes") or ()),
            raw=d,
        )


@dataclass(frozen=True)
class RotationResult:
    """`fit(..., holdout_by="KEY")` (the CLI's `fit --holdout-by KEY`): every value of KEY held
    out in turn, one fit per value; the held-out position MAE [rad] before → after, per fold and
    averaged over every episode (each held out once). Nothing to write: a model comes from one
    fit (`holdout_by="KEY=VALUE"`)."""

    holdout_by: str
    folds: Tuple[Fold, ...]
    position_mae_before: float
    position_mae_after: float
    episodes: int
    raw: Dict[str, Any] = field(repr=False, compare=False)

    @property
    def warnings(self) -> Tuple[str, ...]:
        """Every fold's warnings, each prefixed `KEY = VALUE: ` (as the CLI prints them)."""
        return tuple(f"{self.holdout_by} = {f.value}: {w}" for f in self.folds for w in f.warnings)

    @classmethod
    def from_json(cls, d: dict) -> "RotationResult":
        return cls(
            holdout_by=d["holdout_by"],
            folds=tuple(Fold.from_json(f) for f in d["folds"]),
            position_mae_before=d["position_mae_before"],
            position_mae_after=d["position_mae_after"],
            episodes=d["episodes"],
            raw=d,
        )
