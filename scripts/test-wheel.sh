#!/usr/bin/env bash
# End-to-end test of the Python package (pyproject.toml): build the wheel the way `pip install .`
# does (PEP 517, build isolation: maturin and mujoco==3.17.0 come from PyPI), install the built
# wheel into a fresh venv (mujoco comes from PyPI as its dependency), and run `modellint` there
# with no environment variable pointing at MuJoCo; then the Python API there: `import modellint`
# and the pytest suite python/tests (pytest and numpy from PyPI; skipped visibly without them).
# Also installs it with `pip install --user` into a private user base, and with uv / pipx when
# they are on PATH.
#
# The wheel build re-uses target/ (same binary as `cargo build --release`, see build.rs), so after
# `make build` it takes well under a minute. Skips visibly (exit 0, "skipping: ...") when python3,
# venv or PyPI are not available. Prints "test-wheel: N passed, M failed"; exit 1 on a failure.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
work="$root/target/wheel-test"
pass=0
fail=0
skip() { echo "test-wheel: skipping: $*" >&2; exit 0; }
ok() { pass=$((pass + 1)); echo "test-wheel: ok: $*"; }
bad() { fail=$((fail + 1)); echo "test-wheel: FAILED: $*" >&2; }
now() { date +%s.%N; }
secs() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }

command -v python3 >/dev/null || skip "python3 not found"
python3 -m venv --help >/dev/null 2>&1 || skip "python3 has no venv module"
python3 -m pip --version >/dev/null 2>&1 || skip "python3 has no pip"
rm -rf "$work"
mkdir -p "$work"
# PyPI reachable? (maturin is the build backend; pip caches the download for the build below.)
python3 -m pip download --quiet --no-deps "maturin>=1.5,<2" -d "$work/probe" >/dev/null 2>&1 \
  || skip "cannot download maturin from PyPI"

# 1. Build the wheel through the PEP 517 backend, exactly as `pip install .` does.
t0=$(now)
if ! python3 -m pip wheel --quiet --no-deps "$root" -w "$work/dist" >"$work/build.log" 2>&1; then
  cat "$work/build.log" >&2
  bad "pip wheel . (build log above)"
  echo "test-wheel: $pass passed, $fail failed"
  exit 1
fi
t1=$(now)
whl="$(ls "$work"/dist/modellint-*.whl)"
size=$(stat -c %s "$whl")
echo "test-wheel: built $(basename "$whl") ($(awk -v s="$size" 'BEGIN { printf "%.2f MB", s / 1e6 }')) in $(secs "$t0" "$t1") s"
ok "wheel built"

# The wheel holds the binary, the Python package with its extension module, and metadata:
# libmujoco must come from the mujoco package.
if python3 - "$whl" <<'PY'
import sys, zipfile
names = zipfile.ZipFile(sys.argv[1]).namelist()
assert any(n.endswith(".data/scripts/modellint") for n in names), names
assert "modellint/__init__.py" in names and "modellint/_native.abi3.so" in names, names
assert not any("libmujoco" in n for n in names), [n for n in names if "libmujoco" in n]
meta = [n for n in names if n.endswith("METADATA")][0]
text = zipfile.ZipFile(sys.argv[1]).read(meta).decode()
assert "Requires-Dist: mujoco==3.17.0" in text, text
PY
then ok "wheel has scripts/modellint and modellint/_native, no libmujoco, Requires-Dist mujoco==3.17.0"; else bad "wheel contents"; fi

# 2. A fresh venv with only the built wheel (and its dependency mujoco from PyPI).
python3 -m venv "$work/venv"
t0=$(now)
if ! "$work/venv/bin/python" -m pip install --quiet "$whl" >"$work/install.log" 2>&1; then
  cat "$work/install.log" >&2
  bad "pip install of the wheel into a fresh venv"
  echo "test-wheel: $pass passed, $fail failed"
  exit 1
fi
t1=$(now)
echo "test-wheel: pip install into a fresh venv took $(secs "$t0" "$t1") s"

# run_clean DIR ARGS...: modellint from DIR/bin with a minimal environment (no LD_LIBRARY_PATH,
# no MUJOCO_* variables, not the project's target/ on PATH), from the project root.
run_clean() {
  local bindir="$1"
  shift
  (cd "$root" && env -i PATH="$bindir:/usr/bin:/bin" HOME="${HOME:-/tmp}" modellint "$@")
}

check_install() { # LABEL BINDIR SITEPKG_GLOB
  local label="$1" bindir="$2"
  local out code
  out="$(run_clean "$bindir" models/asimov.xml --color never 2>&1)"
  code=$?
  if [ "$code" = 1 ] && grep -q "underdamped-pd-gains" <<<"$out" && grep -q "error(s)" <<<"$out"; then
    ok "$label: modellint models/asimov.xml exits 1 with the underdamped-pd-gains finding"
  else
    bad "$label: modellint models/asimov.xml exited $code; output: $(tail -n 5 <<<"$out")"
  fi
  # Which libmujoco did the dynamic loader open? It must be the one inside the installed package.
  local lib
  lib="$(cd "$root" && env -i PATH="$bindir:/usr/bin:/bin" LD_DEBUG=libs modellint --version 2>&1 \
    | sed -n 's/.*calling init: \(.*libmujoco\.so\.3\.17\.0\).*/\1/p' | head -n 1)"
  case "$lib" in
    */site-packages/mujoco/libmujoco.so.3.17.0 | */dist-packages/mujoco/libmujoco.so.3.17.0)
      ok "$label: libmujoco loaded from the installed mujoco package ($lib)" ;;
    *) bad "$label: libmujoco loaded from '${lib:-nowhere}', not from the mujoco package" ;;
  esac
}

check_install "venv" "$work/venv/bin"
# Bad input still gives exit 2 with a file:line message from the installed binary.
printf '<mujoco>\n  <worldbody>\n' >"$work/broken.xml"
out="$(run_clean "$work/venv/bin" "$work/broken.xml" 2>&1)"
code=$?
if [ "$code" = 2 ] && grep -q "broken.xml:" <<<"$out"; then ok "venv: malformed model exits 2 with file:line"; else bad "venv: malformed model exited $code: $out"; fi

# The "Lint" step of the GitHub Actions workflow in docs/ci.md, run as GitHub runs it
# (bash -eo pipefail, GITHUB_OUTPUT), with the installed modellint: findings → the step passes and
# records exit-code=1 with a non-empty SARIF; a broken model → the step itself fails with 2.
step="$(awk '/- name: Lint$/ { f = 1 } f && /run: \|/ { r = 1; next } r && /^      - / { exit } r { sub(/^          /, ""); print }' "$root/docs/ci.md")"
if [ -z "$step" ]; then
  bad "docs/ci.md: no 'Lint' step found"
else
  for case in findings broken; do
    d="$work/ci-$case"
    mkdir -p "$d/robots"
    if [ "$case" = findings ]; then
      cp "$root/models/asimov.xml" "$d/robots/my_robot.xml"
      cp "$root/models/asimov.toml" "$d/robots/my_robot.toml"
    else
      cp "$work/broken.xml" "$d/robots/my_robot.xml"
      cp "$root/models/asimov.toml" "$d/robots/my_robot.toml"
    fi
    (cd "$d" && env -i PATH="$work/venv/bin:/usr/bin:/bin" HOME="${HOME:-/tmp}" GITHUB_OUTPUT="$d/out" \
      bash --noprofile --norc -eo pipefail -c "$step" >/dev/null 2>"$d/stderr")
    code=$?
    recorded="$(sed -n 's/^exit-code=//p' "$d/out" 2>/dev/null)"
    if [ "$case" = findings ]; then
      if [ "$code" = 0 ] && [ "$recorded" = 1 ] && python3 -c '
import json, sys
runs = json.load(open(sys.argv[1]))["runs"]
assert runs[0]["results"], "no results"' "$d/modellint.sarif"; then
        ok "docs/ci.md Lint step: findings → step passes, exit-code=1 recorded, SARIF has results"
      else
        bad "docs/ci.md Lint step on findings: step exit $code, recorded '$recorded'"
      fi
    else
      if [ "$code" = 2 ] && [ "$recorded" = 2 ]; then
        ok "docs/ci.md Lint step: broken model → the step fails with exit 2 (no SARIF upload)"
      else
        bad "docs/ci.md Lint step on a broken model: step exit $code, recorded '$recorded'"
      fi
    fi
  done
fi

# The Python API in the fresh venv, with no environment variable: the issue's one-liner, then
# the pytest suite (python/tests: the API against this venv's `modellint` command's JSON; pytest,
# numpy and tqdm from PyPI).
out="$(cd "$root" && env -i PATH="$work/venv/bin:/usr/bin:/bin" HOME="${HOME:-/tmp}" python -c \
  "import modellint; print(modellint.lint('models/asimov.xml'))" 2>&1)"
if grep -q "models/asimov.xml:.*error \[underdamped-pd-gains\]" <<<"$out"; then
  ok "venv: python -c 'import modellint; print(modellint.lint(\"models/asimov.xml\"))' lists the findings"
else
  bad "venv: modellint.lint('models/asimov.xml'): $(tail -n 5 <<<"$out")"
fi
lib="$(cd "$root" && env -i PATH="$work/venv/bin:/usr/bin:/bin" LD_DEBUG=libs python -c "import modellint" 2>&1 \
  | sed -n 's/.*calling init: \(.*libmujoco\.so\.3\.17\.0\).*/\1/p' | head -n 1)"
[ -n "$lib" ] && lib="$(readlink -f "$lib")" # site-packages/modellint/../mujoco/…
case "$lib" in
  */site-packages/mujoco/libmujoco.so.3.17.0) ok "venv: import modellint loads libmujoco from the mujoco package ($lib)" ;;
  *) bad "venv: import modellint loaded libmujoco from '${lib:-nowhere}', not from the mujoco package" ;;
esac
if "$work/venv/bin/python" -m pip install --quiet pytest numpy tqdm >"$work/pytest-install.log" 2>&1; then
  t0=$(now)
  (cd "$root" && env -i PATH="$work/venv/bin:/usr/bin:/bin" HOME="${HOME:-/tmp}" \
    PYTHONDONTWRITEBYTECODE=1 python -m pytest -p no:cacheprovider -q python/tests) >"$work/pytest.log" 2>&1
  code=$?
  t1=$(now)
  tail -n 15 "$work/pytest.log"
  if [ "$code" = 0 ]; then
    ok "pytest python/tests: $(tail -n 1 "$work/pytest.log" | tr -d '=') ($(secs "$t0" "$t1") s)"
  else
    bad "pytest python/tests exited $code (log above; full log $work/pytest.log)"
  fi
else
  echo "test-wheel: skipping: pytest python/tests: cannot install pytest, numpy and tqdm from PyPI ($(tail -n 1 "$work/pytest-install.log"))" >&2
fi

# 3. pip install --user (scripts in <userbase>/bin, packages in <userbase>/lib/python3.N/site-packages).
if PYTHONUSERBASE="$work/userbase" python3 -m pip install --quiet --user --break-system-packages \
  "$whl" >"$work/user.log" 2>&1; then
  check_install "pip --user" "$work/userbase/bin"
else
  echo "test-wheel: skipping: pip install --user refused here ($(tail -n 1 "$work/user.log"))" >&2
fi

# 4. uv tool / pipx: the ones on PATH, else installed from PyPI into a scratch venv.
if ! command -v uv >/dev/null || ! command -v pipx >/dev/null; then
  python3 -m venv "$work/tools" && "$work/tools/bin/python" -m pip install --quiet uv pipx >"$work/tools.log" 2>&1 \
    && PATH="$PATH:$work/tools/bin"
fi
if command -v uv >/dev/null; then
  if UV_TOOL_DIR="$work/uv-tools" UV_TOOL_BIN_DIR="$work/uv-bin" uv tool install --quiet "$whl" >"$work/uv.log" 2>&1; then
    check_install "uv tool" "$work/uv-bin"
  else
    bad "uv tool install: $(tail -n 3 "$work/uv.log")"
  fi
else
  echo "test-wheel: skipping: uv not on PATH (uv tool install not tested)" >&2
fi
if command -v pipx >/dev/null; then
  if PIPX_HOME="$work/pipx-home" PIPX_BIN_DIR="$work/pipx-bin" pipx install --quiet "$whl" >"$work/pipx.log" 2>&1; then
    check_install "pipx" "$work/pipx-bin"
  else
    bad "pipx install: $(tail -n 3 "$work/pipx.log")"
  fi
else
  echo "test-wheel: skipping: pipx not on PATH (pipx install not tested)" >&2
fi

echo "test-wheel: $pass passed, $fail failed"
[ "$fail" = 0 ]
