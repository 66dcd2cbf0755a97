#!/usr/bin/env bash
# Blind-fit speed, end to end from the CLI (issue 12's targets on 2 cores): recordings made by
# `modellint synth` (its own MuJoCo loop, 100 Hz controller, async ~88 Hz recorder, noise, 12-bit
# encoder, drops), then `modellint fit MODEL EPISODES` with every effect allowed, as a user runs
# it. Prints wall and CPU seconds per case, what was fitted, and the medians against the targets:
#   single-joint case ≤ 10 s median, 3-joint arm ≤ 30 s, 12-joint robot (4 × 6 s episodes) ≤ 90 s.
# With ../shared/data the seven independent arm2 datasets are timed too.
# Figures only (no pass/fail): the machine is shared; quote ratios from one run.
#   bench/fit_speed.sh            # all groups
#   bench/fit_speed.sh --quick    # single-joint and arm2 only
set -euo pipefail
cd "$(dirname "$0")/.."
make -s build >/dev/null
bin=./target/release/modellint
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
quick=0
[ "${1:-}" = "--quick" ] && quick=1

TIMEFORMAT='%R %U %S'
declare -A times
row() { # group name model episodes-dir
  local group=$1 name=$2 model=$3 eps=$4 t wall cpu fitted
  t=$({ time "$bin" fit "$model" "$eps" --quiet --format json >"$work/out.json" 2>/dev/null || true; } 2>&1)
  read -r wall u s <<<"$t"
  cpu=$(python3 -c "print(f'{$u + $s:.1f}')")
  fitted=$(python3 - "$work/out.json" <<'EOF'
import json, sys
try:
    d = json.load(open(sys.argv[1]))
except Exception:
    print("(fit failed)"); sys.exit()
m = d.get("missing_physics", [])
print("; ".join(f"{x['effect']}@{'+'.join(x['joints'])}" for x in m) or "(nothing)")
EOF
)
  printf '%-8s %-34s %8s %8s  %s\n' "$group" "$name" "$wall" "$cpu" "$fitted"
  times[$group]="${times[$group]:-} $wall"
}
n_case=0
synth() { # model effects extra... → sets $eps to the episodes directory
  local model=$1 eff=$2; shift 2
  n_case=$((n_case + 1))
  "$bin" synth "$model" --effects "$eff" --out "$work/c$n_case" --quiet "$@" >/dev/null
  eps="$work/c$n_case/episodes"
}

printf '%-8s %-34s %8s %8s  %s\n' group case "wall s" "cpu s" fitted
pend=fixtures/synth/pendulum_servo.xml
for c in "none" "viscous_damping=0.03" "action_delay=0.015" "armature=0.003" "coulomb_friction=0.03" "gain_error=0.7,1.3"; do
  synth "$pend" "$c" --amplitude 0.8 --seed 5
  row single "pendulum $c" "$pend" "$eps"
done
arm2=../shared/data/recordings/independent_arm2
if [ -d "$arm2" ]; then
  for d in "$arm2"/arm2.*/; do
    n=$(basename "$d")
    row arm2 "$n" "$d/nominal.xml" "$d/episodes"
  done
else
  echo "arm2     (skipping: $arm2 is absent)"
fi
if [ $quick = 0 ]; then
  arm3=fixtures/gap/arm3.xml
  for c in "none" "viscous_damping@elbow_pitch=0.4" "action_delay=0.025"; do
    synth "$arm3" "$c" --amplitude 0.5 --seed 7
    row arm3 "arm3 $c" "$arm3" "$eps"
  done
  asi=models/asimov.xml
  for c in "none" "viscous_damping@*_knee=3.0"; do
    synth "$asi" "$c" --episodes 4 --duration 6 --suspend 0.5 --amplitude 0.15 --heldout 1 --seed 7
    row legs12 "asimov (4 x 6 s) $c" "$asi" "$eps"
  done
fi
echo
for g in single arm2 arm3 legs12; do
  [ -n "${times[$g]:-}" ] || continue
  med=$(python3 -c "import statistics,sys; print(f'{statistics.median(map(float, sys.argv[1:])):.1f}')" ${times[$g]})
  case $g in single) tgt="≤ 10 s";; arm3) tgt="≤ 30 s";; legs12) tgt="≤ 90 s";; *) tgt="(2 joints)";; esac
  printf 'median wall %-7s %6s s   target %s\n' "$g" "$med" "$tgt"
done
echo "load average at the end: $(cut -d' ' -f1-3 /proc/loadavg) (2 cores; wall times stretch with load)"
