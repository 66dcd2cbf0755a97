#!/usr/bin/env bash
# Installs the Python libraries that tests/log_formats.rs writes its fixtures with (each log
# format's own library: numpy, pyarrow, mcap + mcap-ros2-support) into a venv at
# target/pyfixtures, where the tests look first. Takes ~15 s with PyPI at hand. Skips visibly
# (exit 0) without python3, venv or PyPI: the tests then skip each format visibly.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="$root/target/pyfixtures"
skip() { echo "setup-py-fixtures: skipping: $*" >&2; exit 0; }
command -v python3 >/dev/null || skip "python3 not found"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv" >/dev/null 2>&1 || skip "python3 has no venv module"
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check \
  numpy pyarrow mcap mcap-ros2-support 2>&1 | tail -3 \
  || skip "cannot install from PyPI"
"$venv/bin/python" -c "import numpy, pyarrow, mcap_ros2" 2>/dev/null \
  || skip "the libraries did not install (no PyPI?)"
echo "setup-py-fixtures: numpy, pyarrow, mcap-ros2-support in $venv"
