"""Fixtures of the Python API's tests: the repository root (tests run from it, as the CLI's
paths in the JSON are relative to it), the installed `modellint` command beside this Python
(the one the wheel installed), and a small dataset recorded by `modellint synth` (its own
MuJoCo loop and CSV writer: it shares no replay, command or reading code with gap/fit)."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "data" / "recordings" / "independent_arm2"


@pytest.fixture(autouse=True)
def at_root(monkeypatch):
    monkeypatch.chdir(ROOT)


def _cli_path() -> str:
    beside = Path(sys.executable).parent / "modellint"
    if beside.exists():
        return str(beside)
    found = shutil.which("modellint")
    if not found:
        pytest.fail("no `modellint` command beside this Python or on PATH (is the wheel installed?)")
    return found


class Cli:
    """The installed `modellint` command: run it, and its JSON."""

    def __init__(self, path: str) -> None:
        self.path = path

    def run(self, *args, check_codes=(0, 1)):
        p = subprocess.run(
            [self.path, *map(str, args)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            env={**os.environ, "NO_COLOR": "1"},
        )
        assert p.returncode in check_codes, (args, p.returncode, p.stderr[-2000:])
        return p

    def json(self, *args):
        return json.loads(self.run(*args, "--format", "json").stdout)


@pytest.fixture(scope="session")
def cli() -> Cli:
    return Cli(_cli_path())


@pytest.fixture(scope="session")
def arm3_data(tmp_path_factory, cli) -> Path:
    """arm3 (fixtures/gap/arm3.xml) with +0.5 N·m·s/rad damping hidden on the elbow: 3
    episodes of 4 s (the last one held out), recorded by `modellint synth`."""
    out = tmp_path_factory.mktemp("arm3") / "data"
    cli.run(
        "synth",
        "fixtures/gap/arm3.xml",
        "--out",
        out,
        "--effects",
        "viscous_damping@elbow_pitch=0.5",
        "--episodes",
        "3",
        "--duration",
        "4",
    )
    return out
