#!/usr/bin/env bash
# Independent-simulator benchmark for `modellint fit`: a Python/MuJoCo "real robot" (realsim.py,
# written apart from the fit code) records each case of cases.py in the logging style of
# ../shared/data/recordings/independent_arm2 (100 Hz controller with a phase, ~88 Hz jittered
# asynchronous recorder, 0.5 mrad noise, 12-bit encoder, 0.5 % dropped rows, 2 s unrecorded
# settle), `modellint fit` sees only the nominal model and the CSVs, and score.py compares its
# JSON with the truth the simulator wrote into its MjModel. Cases with `sim: "chain"` (K*) are
# recorded instead by chainsim.py, a numpy planar-chain simulator with its own physics (backlash
# behind a motor, Stribeck friction, body effects composed by hand); `sim: "float"` cases (KF*)
# by floatsim.py, a planar biped on a free base with its own penalty ground contact;
# `chainsim.py --selftest` and `floatsim.py --selftest` check their physics. Each case with
# something concealed is also fitted *told* the truth (`--told EFFECT@JOINTS` from the
# simulator's truth.json, `score.py --told-args`), and the table gives per case the blind and
# told recording seconds replayed and their ratio (issue 46's target: blind <= 3 x told).
#
# usage: bench/independent_py/run.sh [CASE...]      (default: every case; ~15–30 min on 2 cores)
# Needs python3 with venv and PyPI (mujoco==3.17.0, numpy) — skips with a message otherwise.
# Env: INDEP_OUT (default target/independent_py), MODELLINT (default target/release/modellint).
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
out="${INDEP_OUT:-$repo/target/independent_py}"
bin="${MODELLINT:-$repo/target/release/modellint}"
venv="$out/venv"
mkdir -p "$out/results"
if [ ! -x "$bin" ]; then
  (cd "$repo" && make build >/dev/null) || { echo "cannot build modellint"; exit 2; }
fi
if [ ! -x "$venv/bin/python" ]; then
  if ! python3 -m venv "$venv" >/dev/null 2>&1 ||
     ! "$venv/bin/pip" install -q mujoco==3.17.0 numpy >/dev/null 2>&1; then
    echo "skipping: needs python3 -m venv and PyPI (mujoco==3.17.0, numpy)"
    exit 0
  fi
fi
if [ $# -eq 0 ]; then
  set -- $("$venv/bin/python" -c "import sys; sys.path.insert(0, '$here'); from cases import CASES; print(' '.join(CASES))")
fi
export INDEP_OUT="$out"
for c in "$@"; do
  # `sim: chain` cases are recorded by chainsim.py (own numpy physics), `sim: float` by
  # floatsim.py (own free-base physics and ground contact), the others by realsim.py
  sim=$("$venv/bin/python" -c "import sys; sys.path.insert(0, '$here'); from cases import CASES; print({'chain': 'chainsim', 'float': 'floatsim'}.get(CASES.get('$c', {}).get('sim'), 'realsim'))")
  "$venv/bin/python" "$here/$sim.py" "$c" >/dev/null || { echo "$c: recording failed"; continue; }
  extra=$("$venv/bin/python" -c "import sys; sys.path.insert(0, '$here'); from cases import CASES; print(' '.join(CASES['$c'].get('fit_args', [])))")
  s=$(date +%s.%N)
  # shellcheck disable=SC2086
  "$bin" fit "$out/data/$c/nominal.xml" "$out/data/$c/episodes" --format json --quiet $extra \
    > "$out/results/$c.json" 2> "$out/results/$c.stderr"
  e=$(date +%s.%N)
  python3 -c "print(f'{$e - $s:.1f}')" > "$out/results/$c.time"
  echo "$c: $(cat "$out/results/$c.time") s" >&2
  # the told fit of the truth (no search; what the blind search is timed against, issue 46)
  rm -f "$out/results/$c.told.json"
  told=$(python3 "$here/score.py" --told-args "$out" "$c")
  if [ -n "$told" ]; then
    # shellcheck disable=SC2086
    "$bin" fit "$out/data/$c/nominal.xml" "$out/data/$c/episodes" --format json --quiet $extra $told \
      > "$out/results/$c.told.json" 2> "$out/results/$c.told.stderr"
  fi
done
echo "modellint $(git -C "$repo" rev-parse --short HEAD 2>/dev/null), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
python3 "$here/score.py" "$out" "$@"
