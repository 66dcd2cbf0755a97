#!/usr/bin/env bash
# End-to-end test of the pre-commit hook (.pre-commit-hooks.yaml, `language: python`): a temporary
# git repository uses the `modellint` hook from this repository (a snapshot of the working tree,
# committed in a scratch repository, as `repo: <path>` + `rev: <sha>`); pre-commit installs it
# (pip install of this repository: maturin builds the binary, mujoco==3.17.0 comes from PyPI) and
# runs it:
#   A. a clean model only                      → the hook passes
#   B. the clean model and a ROS package.xml   → the hook passes (needs `modellint a.xml b.xml`,
#      which skips non-model XML; skipped visibly when the installed modellint has no multi-file
#      support yet)
#   B2. package.xml alone (a commit touching only it) → the hook passes (--skip-non-models)
#   C. an underdamped model                    → the hook fails and prints the finding
# The hook's cargo build shares target/ (CARGO_TARGET_DIR) so only the modellint crate compiles.
# Skips visibly (exit 0, "skipping: ...") without python3/venv/git or when pre-commit cannot be
# installed from PyPI. Prints "test-precommit: N passed, M failed"; exit 1 on a failure.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
work="$root/target/precommit-test"
pass=0
fail=0
skip() { echo "test-precommit: skipping: $*" >&2; exit 0; }
ok() { pass=$((pass + 1)); echo "test-precommit: ok: $*"; }
bad() { fail=$((fail + 1)); echo "test-precommit: FAILED: $*" >&2; }

command -v python3 >/dev/null || skip "python3 not found"
command -v git >/dev/null || skip "git not found"
python3 -m venv --help >/dev/null 2>&1 || skip "python3 has no venv module"
rm -rf "$work"
mkdir -p "$work"
python3 -m venv "$work/tools" || skip "cannot create a venv"
"$work/tools/bin/python" -m pip install --quiet "pre-commit>=3" >"$work/tools.log" 2>&1 \
  || skip "cannot install pre-commit from PyPI ($(tail -n 1 "$work/tools.log"))"
precommit="$work/tools/bin/pre-commit"
export PRE_COMMIT_HOME="$work/cache"
gitc() { git -c user.name=modellint-test -c user.email=test@example.invalid -c init.defaultBranch=main -c commit.gpgsign=false "$@"; }

# The hook repository: this working tree (tracked and untracked, not ignored files) as one commit.
hook="$work/hook-repo"
mkdir -p "$hook"
(cd "$root" && git ls-files -z --cached --others --exclude-standard | while IFS= read -r -d '' f; do
  [ -e "$f" ] && printf '%s\0' "$f"
done | xargs -0 cp --parents -t "$hook")
(cd "$hook" && gitc init -q && gitc add -A && gitc commit -q -m snapshot) || { bad "snapshot of the hook repository"; exit 1; }
rev="$(cd "$hook" && git rev-parse HEAD)"

# The lab's repository.
lab="$work/lab"
mkdir -p "$lab/robots"
cd "$lab" && gitc init -q
cat >.pre-commit-config.yaml <<EOF
repos:
  - repo: $hook
    rev: $rev
    hooks:
      - id: modellint
EOF
# ζ = (kv + damping) / (2 √(kp I)): kv 20 + damping 0.1 against kp 100, I ≈ 0.25 kg·m² → ζ ≈ 2.
cat >robots/clean.xml <<'EOF'
<mujoco model="clean">
  <compiler angle="radian"/>
  <option timestep="0.002" integrator="implicitfast"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="thigh" pos="0 0 1">
      <joint name="hip" axis="0 1 0" armature="0.02" damping="0.1" range="-1 1"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.4" size="0.04" mass="4"/>
    </body>
  </worldbody>
  <actuator>
    <position name="hip" joint="hip" kp="100" kv="20" ctrlrange="-0.9 0.9" forcerange="-40 40"/>
  </actuator>
</mujoco>
EOF
gitc add -A

# The hook's build: share this checkout's target/ and MuJoCo so only the modellint crate compiles.
# Cargo names the crate's build unit by its path relative to the workspace, so the hook's clone
# and this checkout share one unit: the clone's build replaces target/release/modellint and the
# unit's fingerprint then points at the clone's sources. Afterwards the checkout's binary is put
# back and the clone deleted, so the next `cargo build` here sees missing sources and rebuilds.
export CARGO_TARGET_DIR="$root/target"
cleanup() {
  rm -rf "$PRE_COMMIT_HOME" "$hook"
  if [ -f "$work/modellint.checkout" ]; then
    cp -p "$work/modellint.checkout" "$root/target/release/modellint.restore" \
      && mv -f "$root/target/release/modellint.restore" "$root/target/release/modellint"
  fi
}
[ -f "$root/target/release/modellint" ] && cp -p "$root/target/release/modellint" "$work/modellint.checkout"
trap cleanup EXIT
[ -f "$root/.mujoco/lib/libmujoco.so" ] && export MUJOCO_DYNAMIC_LINK_DIR="$root/.mujoco/lib"

# A. Clean model: installs the hook environment (pip install of the hook repository), then passes.
t0=$(date +%s)
out="$("$precommit" run --all-files --color never 2>&1)"
code=$?
t1=$(date +%s)
if [ "$code" = 0 ] && grep -q "modellint (robot model lint, static pass).*Passed" <<<"$out"; then
  ok "A: clean model passes (hook installed and run in $((t1 - t0)) s)"
else
  bad "A: clean model: pre-commit exited $code: $out"
fi
installed="$(ls -d "$PRE_COMMIT_HOME"/repo*/py_env-*/bin/modellint 2>/dev/null | head -n 1)"

# B. A ROS package manifest beside it must not be linted as a model.
cat >robots/package.xml <<'EOF'
<?xml version="1.0"?>
<package format="3">
  <name>clean_robot_description</name>
  <version>0.1.0</version>
  <description>Clean robot.</description>
  <maintainer email="lab@example.invalid">lab</maintainer>
  <license>BSD-3-Clause</license>
</package>
EOF
gitc add -A
multi="$([ -n "$installed" ] && "$installed" robots/clean.xml robots/clean.xml --no-probe 2>&1)"
if grep -q "cannot be used with" <<<"$multi"; then
  echo "test-precommit: skipping B: the installed modellint lints one model per call (multi-file support not merged yet)" >&2
else
  out="$("$precommit" run --all-files --color never 2>&1)"
  code=$?
  if [ "$code" = 0 ]; then ok "B: clean model + package.xml passes"; else bad "B: clean model + package.xml: pre-commit exited $code: $out"; fi
fi
# B2. A commit that touches only the package manifest: the hook gets that one file and passes.
if [ -n "$installed" ] && "$installed" --help 2>&1 | grep -q -- "--skip-non-models"; then
  out="$("$precommit" run --files robots/package.xml --color never 2>&1)"
  code=$?
  if [ "$code" = 0 ]; then ok "B2: a commit of package.xml alone passes"; else bad "B2: package.xml alone: pre-commit exited $code: $out"; fi
else
  echo "test-precommit: skipping B2: the installed modellint has no --skip-non-models" >&2
fi
git rm -q --cached robots/package.xml && rm robots/package.xml

# C. An underdamped model: kv 1 against kp 100 → ζ ≈ 0.1, the hook must fail with the finding.
sed -e 's/model="clean"/model="bad"/' -e 's/kv="20"/kv="1"/' -e 's/damping="0.1"/damping="0"/' robots/clean.xml >robots/bad.xml
git rm -q --cached robots/clean.xml && rm robots/clean.xml
gitc add -A
out="$("$precommit" run --all-files --color never 2>&1)"
code=$?
if [ "$code" = 1 ] && grep -q "modellint (robot model lint, static pass).*Failed" <<<"$out" \
  && grep -q "underdamped-pd-gains" <<<"$out" && grep -q "robots/bad.xml" <<<"$out"; then
  ok "C: underdamped model fails the hook with the underdamped-pd-gains finding"
else
  bad "C: underdamped model: pre-commit exited $code: $out"
fi

echo "test-precommit: $pass passed, $fail failed"
[ "$fail" = 0 ]
