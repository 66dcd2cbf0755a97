"""The Python API against the installed CLI: same inputs, same JSON (same numbers, bit for
bit), typed objects that say what the JSON says, errors located as the CLI locates them."""

import csv
import re
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import modellint
from conftest import SHARED

MODEL = "models/asimov.xml"
ARM3 = "fixtures/gap/arm3.xml"

# Wall-clock figures of a fit (they differ between any two runs, CLI or API).
TIMING = re.compile(r"\(\d+(\.\d+)? s simulating\)")


def without_timing(fit_json: dict) -> dict:
    d = dict(fit_json)
    d["search"] = {k: v for k, v in d["search"].items() if k != "seconds"}
    d["notes"] = [TIMING.sub("(… s simulating)", n) for n in d["notes"]]
    return d


# ---------------------------------------------------------------- lint


@pytest.mark.parametrize("probes", [True, False])
def test_lint_is_the_cli_json(cli, probes):
    args = [MODEL] + ([] if probes else ["--no-probe"])
    expected = cli.json(*args)
    found = modellint.lint(MODEL, probes=probes)
    assert found.raw == expected
    assert found.model == MODEL
    assert found.summary == expected["summary"]
    assert found.spec.path == expected["spec"]["path"]
    assert [f.rule for f in found] == [f["rule"] for f in expected["findings"]]
    # Every typed field is the JSON's.
    for f, j in zip(found, expected["findings"]):
        assert (f.severity, f.message, f.element, f.note, f.help) == (
            j["severity"],
            j["message"],
            j["element"],
            j["note"],
            j["help"],
        )
        loc = f.location
        assert (loc.file, loc.line, loc.column, loc.end_line, loc.end_column) == (
            j["file"],
            j["line"],
            j["column"],
            j["end_line"],
            j["end_column"],
        )
        assert f.data == j["data"]
        if j["measured"] is not None:
            assert (f.measured.value, f.measured.unit) == (
                j["measured"]["value"],
                j["measured"]["unit"],
            )
        assert [(x.file, x.line, x.message) for x in f.labels] == [
            (x["file"], x["line"], x["message"]) for x in j["labels"]
        ]
        if probes and j["probe"] is not None:
            assert f.probe.status == j["probe"]["status"]
            assert f.probe.measured == j["probe"]["measured"]
        if not probes:
            assert f.probe is None or f.probe.status != "confirmed"


def test_lint_finds_the_underdamped_knee_with_its_numbers():
    # models/asimov.xml: kp 65 N·m/rad, kv 5 N·m·s/rad on the hip pitch (docs/rules).
    found = modellint.lint(MODEL)
    f = next(x for x in found if x.rule == "underdamped-pd-gains")
    assert f.severity == "error" and f.at_least("warning")
    assert f.data["kp"] == 65.0 and f.data["kd"] == 5.0
    assert f.measured.value == pytest.approx(f.data["zeta"])
    assert f.probe.status == "confirmed"
    assert str(f).startswith(f"{MODEL}:{f.location.line}:{f.location.column}: error [underdamped-pd-gains]")
    assert f in found.at_least("error")


def test_lint_select_and_spec_options_are_the_cli_flags(cli):
    expected = cli.json(MODEL, "--no-probe", "--select", "underdamped-pd-gains", "--spec", "models/asimov.toml")
    found = modellint.lint(MODEL, spec="models/asimov.toml", probes=False, select=["underdamped-pd-gains"])
    assert found.raw == expected
    assert {f.rule for f in found} == {"underdamped-pd-gains"}


def test_lint_error_carries_file_line_column(cli, tmp_path):
    bad = tmp_path / "robot.xml"
    bad.write_text('<mujoco>\n  <worldbody>\n    <body name="a">\n      <joint type="hinge" range="0 x"/>\n')
    p = cli.run(bad, check_codes=(2,))
    with pytest.raises(modellint.ModelError) as e:
        modellint.lint(bad)
    err = e.value
    assert err.file == str(bad) and err.line is not None
    # The CLI names the same place.
    assert f"{bad}:{err.line}:{err.column}" in p.stderr
    assert isinstance(err, modellint.ModellintError)


def test_lint_missing_file():
    with pytest.raises(modellint.ModelError) as e:
        modellint.lint("no/such/robot.xml")
    assert e.value.file == "no/such/robot.xml"


# ---------------------------------------------------------------- gap


def test_gap_is_the_cli_json(cli, arm3_data):
    expected = cli.json("gap", ARM3, arm3_data)
    seen = []
    g = modellint.gap(ARM3, arm3_data, progress=seen.append)
    assert g.raw == expected
    assert g.position_mae == expected["position_mae"]
    assert g.episodes == 3
    elbow = g.joint("elbow_pitch")
    assert elbow.mae == next(j["mae"] for j in expected["per_joint"] if j["name"] == "elbow_pitch")
    # The hidden damping is on the elbow: its gap is the largest.
    assert elbow.mae == max(j.mae for j in g.per_joint)
    assert [(p.phase, p.total) for p in seen] == [("replay", 3)] * len(seen) and seen
    assert sorted(p.done for p in seen) == [1, 2, 3]


def test_gap_replay_options_are_the_cli_flags(cli, arm3_data):
    expected = cli.json("gap", ARM3, arm3_data, "--control-hz", "50", "--command-timing", "sent-after")
    # At 50 Hz the 100 Hz commands fit no tick grid: the CLI's warning is a Python warning.
    with pytest.warns(modellint.ModellintWarning, match="no tick grid"):
        g = modellint.gap(ARM3, arm3_data, control_hz=50.0, command_timing="sent-after", progress=False)
    assert g.raw == expected
    assert g.warnings == tuple(expected["warnings"])


def read_csv(path: Path):
    """A recording read with Python's csv module (not modellint's reader): header keys, arrays."""
    meta, rows = {}, []
    with open(path, newline="") as f:
        lines = [line for line in f]
    body = [line for line in lines if not line.startswith("#")]
    for line in lines:
        if line.startswith("#") and ":" in line:
            k, v = line[1:].split(":", 1)
            meta[k.strip()] = v.strip()
    reader = csv.reader(body)
    header = next(reader)
    rows = np.array([[float(x) for x in r] for r in reader])
    cols = {h: rows[:, i] for i, h in enumerate(header)}
    return meta, cols


def test_gap_on_arrays_is_the_gap_on_the_files(arm3_data):
    files = sorted((arm3_data / "episodes").glob("*.csv"))
    recs = []
    for k, path in enumerate(files):
        meta, cols = read_csv(path)
        # In the file's column order (the order of the joints sets the order of the sums).
        joints = list(dict.fromkeys(h.split(".")[0] for h in cols if h != "t"))
        extra = {m: meta[m] for m in ("split", "base") if m in meta}
        if k % 2:  # the two dict forms: per-signal dicts, and the CSV's column names
            recs.append({"t": cols["t"], **{h: v for h, v in cols.items() if h != "t"},
                         "control_rate_hz": float(meta["control_rate_hz"]),
                         "control_t0_s": float(meta["control_t0_s"]), "meta": extra, "name": path.stem})
        else:
            recs.append(modellint.Recording(
                t=cols["t"],
                q={j: cols[f"{j}.q"] for j in joints},
                qd={j: cols[f"{j}.qd"] for j in joints},
                q_cmd={j: list(cols[f"{j}.q_cmd"]) for j in joints},
                control_rate_hz=float(meta["control_rate_hz"]),
                control_t0_s=float(meta["control_t0_s"]),
                meta=extra,
                name=path.stem,
            ))
    from_files = modellint.gap(ARM3, files, progress=False).raw
    from_arrays = modellint.gap(ARM3, recs, progress=False).raw
    for d in (from_files, from_arrays):
        for e in d["per_episode"]:
            e["source"] = Path(e["source"]).name
    assert from_arrays == from_files


def test_recording_error_carries_file_and_line(cli, arm3_data, tmp_path):
    src = sorted((arm3_data / "episodes").glob("*.csv"))[0]
    lines = src.read_text().splitlines(keepends=True)
    first = next(i for i, line in enumerate(lines) if line[0].isdigit())
    lines[first + 5] = lines[first + 5].replace(",", ",x", 1)  # a non-numeric field
    bad = tmp_path / "bad.csv"
    bad.write_text("".join(lines))
    p = cli.run("gap", ARM3, bad, check_codes=(2,))
    with pytest.raises(modellint.RecordingError) as e:
        modellint.gap(ARM3, bad, progress=False)
    assert e.value.file == str(bad)
    assert e.value.line == first + 6
    assert f"{bad}:{first + 6}:" in p.stderr


def test_array_recording_error_names_the_recording_and_row():
    t = np.arange(0.0, 1.0, 0.01)
    q = np.zeros_like(t)
    q[10] = 200.0  # looks like degrees
    rec = {"t": t, "q": {"elbow_pitch": q}, "q_cmd": {"elbow_pitch": q}, "name": "trial_7"}
    with pytest.raises(modellint.RecordingError) as e:
        modellint.gap(ARM3, rec, progress=False)
    assert e.value.file == "<recording trial_7>"
    assert e.value.line == 11 and "row 11" in str(e.value)


def test_unknown_option_is_a_usage_error(arm3_data):
    with pytest.raises(modellint.UsageError) as e:
        modellint.gap(ARM3, arm3_data, control_rate=100, progress=False)
    assert "control_rate" in str(e.value)
    with pytest.raises(ValueError):  # UsageError is a ValueError
        modellint.gap(ARM3, arm3_data, base="floating", progress=False)
    with pytest.raises(modellint.ModellintError, match="--holdout must be at least 2"):
        modellint.fit(ARM3, arm3_data, holdout=1, progress=False)


# ---------------------------------------------------------------- fit


def test_told_fit_is_the_cli_json_and_writes_the_same_model(cli, arm3_data, tmp_path):
    cli_model = tmp_path / "cli_fitted.xml"
    expected = cli.json("fit", ARM3, arm3_data, "--told", "viscous_damping@elbow_pitch", "-q",
                        "--write-model", cli_model)
    f = modellint.fit(ARM3, arm3_data, told=["viscous_damping@elbow_pitch"], progress=False)
    got = without_timing(f.raw)
    want = without_timing(expected)
    want["notes"] = [n for n in want["notes"] if not n.startswith("fitted model written")]
    assert got == want
    (e,) = f.effects
    assert (e.effect, e.joints) == ("viscous_damping", ("elbow_pitch",))
    assert e.params == expected["missing_physics"][0]["params"]
    assert e.stderr == expected["missing_physics"][0]["stderr"]
    # The hidden +0.5 N·m·s/rad, within a few standard errors (synth's noise and quantisation).
    assert abs(e.params["damping"] - 0.5) < max(5 * e.stderr["damping"], 0.02)
    assert f.after.position_rmse < f.before.position_rmse
    assert f.before.raw == expected["before"] and f.after.raw == expected["after"]
    api_model = tmp_path / "api_fitted.xml"
    notes = f.write_model(api_model)
    assert any(str(api_model) in n for n in notes)
    assert api_model.read_text() == cli_model.read_text()


def test_blind_fit_is_the_cli_json_with_progress(cli, arm3_data):
    opts = ["--effects", "viscous_damping,armature,action_delay"]
    expected = cli.json("fit", ARM3, arm3_data, *opts, "-q")
    seen = []
    f = modellint.fit(ARM3, arm3_data, effects=["viscous_damping", "armature", "action_delay"],
                      progress=seen.append)
    assert without_timing(f.raw) == without_timing(expected)
    assert [(e.effect, e.joints) for e in f.effects][:1] == [("viscous_damping", ("elbow_pitch",))]
    assert seen and all(isinstance(p, modellint.FitProgress) for p in seen)
    assert seen[-1].rollouts > 0 and max(p.round for p in seen) >= 1
    assert [p.elapsed_s for p in seen] == sorted(p.elapsed_s for p in seen)


def test_fit_releases_the_gil(arm3_data):
    """Another Python thread keeps running while a fit runs (no progress callback)."""
    stamps = []
    done = threading.Event()

    def work():
        modellint.fit(ARM3, arm3_data, effects=["viscous_damping", "armature", "action_delay"],
                      progress=False)
        done.set()

    t0 = time.perf_counter()
    th = threading.Thread(target=work)
    th.start()
    while not done.is_set():
        stamps.append(time.perf_counter())
        time.sleep(0.005)
    th.join()
    took = time.perf_counter() - t0
    gaps = np.diff([t0] + stamps)
    # Holding the GIL would stall this loop for the whole fit (≈ 2 s here): one gap of ≈ took.
    assert gaps.max() < took / 2, (took, gaps.max())


def test_an_exception_in_the_progress_callback_is_raised(arm3_data):
    class Stop(Exception):
        pass

    def cb(p):
        raise Stop(p.phase)

    with pytest.raises(Stop):
        modellint.fit(ARM3, arm3_data, told=["viscous_damping@elbow_pitch"], progress=cb)


def without_seconds(rotation_json: dict) -> dict:
    d = {k: v for k, v in rotation_json.items() if k != "seconds"}
    d["folds"] = [
        {**{k: v for k, v in f.items() if k != "seconds"},
         "notes": [TIMING.sub("(… s simulating)", n) for n in f["notes"]]}
        for f in rotation_json["folds"]
    ]
    return d


def test_holdout_by_key_rotation_is_the_cli_json(cli, arm3_data):
    """holdout_by="split" (no =VALUE) is `fit --holdout-by split`: one fold per value."""
    effects = ["viscous_damping", "armature"]
    expected = cli.json("fit", ARM3, arm3_data, "--effects", ",".join(effects), "--holdout-by",
                        "split", "-q")
    seen = []
    r = modellint.fit(ARM3, arm3_data, effects=effects, holdout_by="split", progress=seen.append)
    assert isinstance(r, modellint.RotationResult)
    assert without_seconds(r.raw) == without_seconds(expected)
    assert [f.value for f in r.folds] == [f["value"] for f in expected["folds"]] == ["heldout", "train"]
    assert r.episodes == 3 and r.position_mae_after < r.position_mae_before
    assert r.position_mae_before == expected["position_mae_before"]
    for f, j in zip(r.folds, expected["folds"]):
        assert [e.source for e in f.heldout] == [e["source"] for e in j["heldout"]]
        assert [(e[0], list(e[1]), e[2]) for e in f.effects] == [
            (s["effect"], s["joints"], s["params"]) for s in j["selected"]
        ]
    assert seen and seen[-1].rollouts > 0
    # One value only: the CLI's error.
    with pytest.raises(modellint.ModellintError, match="need at least two values of `robot`"):
        modellint.fit(ARM3, arm3_data, effects=effects, holdout_by="robot", progress=False)


CANCEL_SCRIPT = """
import sys, time
import modellint
started = []
def cb(p):
    if not started:
        started.append(time.time())
        print("started", flush=True)
try:
    modellint.fit(sys.argv[1], sys.argv[2], progress=cb)
    print("finished", time.time(), flush=True)
except KeyboardInterrupt:
    print("interrupted", time.time(), flush=True)
"""


@pytest.fixture(scope="module")
def arm3_long(cli, tmp_path_factory):
    """arm3 with the elbow damping, 6 episodes of 10 s: a blind fit of every effect takes 18 s
    uninterrupted on the development machine."""
    data = tmp_path_factory.mktemp("arm3long") / "data"
    cli.run("synth", ARM3, "--out", data, "--effects", "viscous_damping@elbow_pitch=0.5",
            "--episodes", "6", "--duration", "10")
    return data


def test_ctrl_c_stops_a_fit_within_a_second(arm3_long, tmp_path):
    """SIGINT to a Python process running a fit raises KeyboardInterrupt there within about a
    second: the blind fit of arm3_long interrupted 0.5 s in (measured: 0.02–0.06 s from the
    signal to the exception)."""
    import signal
    import subprocess
    import sys

    data = arm3_long
    script = tmp_path / "cancel.py"
    script.write_text(CANCEL_SCRIPT)
    p = subprocess.Popen([sys.executable, str(script), ARM3, str(data)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "started", p.stderr.read()
        time.sleep(0.5)
        sent = time.time()
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=30)
    finally:
        p.kill()
    words = out.split()
    assert words and words[0] == "interrupted", (out, err[-2000:])
    assert float(words[1]) - sent < 1.0, (float(words[1]) - sent, err[-2000:])
    assert p.returncode == 0, err[-2000:]


def test_an_exception_in_the_callback_stops_the_fit_at_once(arm3_long):
    class Stop(Exception):
        pass

    calls = []

    def cb(p):
        calls.append(time.perf_counter())
        if len(calls) == 3:
            raise Stop()

    with pytest.raises(Stop):
        modellint.fit(ARM3, arm3_long, progress=cb)
    # The search stops within about a second of the exception, not at its end (≈ 18 s).
    assert time.perf_counter() - calls[-1] < 1.0
    assert len(calls) == 3


# ---------------------------------------------------------------- shared data


@pytest.mark.skipif(not SHARED.is_dir(), reason=f"{SHARED} is absent (../shared)")
def test_independent_arm2_gap_and_told_fit_are_the_cli_json(cli):
    d = SHARED / "arm2.elbow.viscous_damping"
    model = d / "nominal.xml"
    assert modellint.gap(model, d, progress=False).raw == cli.json("gap", model, d)
    f = modellint.fit(model, d, told=["viscous_damping@elbow"], progress=False)
    assert without_timing(f.raw) == without_timing(
        cli.json("fit", model, d, "--told", "viscous_damping@elbow", "-q")
    )
    # truth.json: +0.8 N·m·s/rad on the elbow (made by the independent simulator).
    assert f.effects[0].params["damping"] == pytest.approx(0.8, rel=0.1)


def test_tqdm_bar_when_tqdm_is_importable(arm3_data, capsys):
    pytest.importorskip("tqdm")
    f = modellint.fit(ARM3, arm3_data, told=["viscous_damping@elbow_pitch"])
    err = capsys.readouterr().err
    assert "modellint fit" in err and "rollout" in err
    assert f.effects[0].effect == "viscous_damping"
