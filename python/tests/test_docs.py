"""docs/python.md's pytest that gates a robot repository on lint findings, run as a user would
run it: copied into a scratch repository with one robot that has errors (models/asimov.xml and
its spec) and one without errors and without a spec, then pytest on it."""

import re
import shutil
import subprocess
import sys

from conftest import ROOT


def gate_test_source() -> str:
    text = (ROOT / "docs" / "python.md").read_text()
    section = text.split("## Gate a robot repository", 1)[1]
    m = re.search(r"```python\n(.*?)```", section, re.S)
    assert m, "docs/python.md: no python block under 'Gate a robot repository'"
    return m.group(1)


def test_the_gate_in_docs_python_md_fails_on_errors_and_passes_clean_models(tmp_path):
    repo = tmp_path / "robot-repo"
    (repo / "tests").mkdir(parents=True)
    (repo / "tests" / "test_models.py").write_text(gate_test_source())
    for name, xml, spec in [
        ("asimov", "models/asimov.xml", "models/asimov.toml"),
        ("clean", "fixtures/rules/underdamped-pd-gains/valid.xml", None),
    ]:
        d = repo / "robots" / name
        d.mkdir(parents=True)
        shutil.copy(ROOT / xml, d / "robot.xml")
        if spec:
            shutil.copy(ROOT / spec, d / "robot.toml")
    p = subprocess.run(
        [sys.executable, "-m", "pytest", "-v", "-p", "no:cacheprovider", "tests"],
        cwd=repo,
        capture_output=True,
        text=True,
    )
    out = p.stdout
    assert p.returncode == 1, out[-3000:]
    assert re.search(r"test_model_has_no_lint_errors\[asimov\] FAILED", out), out[-3000:]
    assert re.search(r"test_model_has_no_lint_errors\[clean\] PASSED", out), out[-3000:]
    assert re.search(r"test_no_model_error_is_hidden_by_a_missing_spec FAILED", out), out[-3000:]
    # The failure names each error at its place in the robot's file.
    assert re.search(r"robots/asimov/robot\.xml:\d+:\d+: error \[underdamped-pd-gains\]", out), out[-3000:]
    assert "robots/clean/robot.xml: no hardware spec" in out, out[-3000:]
