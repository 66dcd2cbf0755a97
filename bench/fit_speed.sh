#!/usr/bin/env bash
# Blind-fit speed, end to end from the CLI, on 2 cores: recordings made by `modellint synth` (its
# own MuJoCo loop, 100 Hz controller, async ~88 Hz recorder, noise, 12-bit encoder, drops), then
# `modellint fit MODEL EPISODES` with every effect allowed, as a user runs it, and the same data
# fitted *told* (`fit --told EFFECT@JOINTS` with the true effects and joints: no search, what
# mujoco.sysid does when given the parameters). Prints per case the blind wall and CPU seconds,
# the told wall seconds, their ratio (target <= 3), the same ratio in recording seconds
# replayed (JSON search.simulated_s: the load-independent cost), the rollouts of the blind
# search and its recording seconds replayed (sim s), what was fitted, and the medians against
# the targets: single-joint <= 5 s, three-joint arm <= 10 s, 12-joint legs (4 x 6 s) <= 90 s,
# the same with 4 x 25 s of 200 Hz logs <= 3 min, the 23-joint Booster T1 (4 x 10 s) <= 5 min.
# With ../shared/data the seven independent arm2 datasets and T1.
# Figures only (no pass/fail): the machine is shared; quote ratios from one run.
#   bench/fit_speed.sh            # all groups
#   bench/fit_speed.sh --quick    # single-joint and arm2 only
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -n "${MODELLINT:-}" ]; then bin=$MODELLINT; else make -s build >/dev/null; bin=./target/release/modellint; fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
quick=0
[ "${1:-}" = "--quick" ] && quick=1

TIMEFORMAT='%R %U %S'
declare -A times
ratios=""
sratios=""
told_of() { # episodes-dir -> --told arguments from the dataset's truth.json (none for a control)
  python3 - "$1/../truth.json" <<'PYEOF'
import json, sys
try:
    d = json.load(open(sys.argv[1]))
except Exception:
    sys.exit()
eff = d.get("effects", [])
groups = {}
if eff and isinstance(eff[0], dict):            # modellint synth: one entry per (effect, joint)
    for e in eff:
        key = (e["effect"], json.dumps(e.get("params", {}), sort_keys=True))
        groups.setdefault(key, []).append(e["joint"])
else:                                           # independent arm2: effects x joints
    for e in eff:
        if e != "none":
            groups[(e, "")] = list(d.get("joints", []))
print(" ".join(f"--told {k[0]}@{'+'.join(v)}" for k, v in groups.items()))
PYEOF
}
row() { # group name model episodes-dir
  local group=$1 name=$2 model=$3 eps=$4 t wall cpu fitted told twall ratio rollouts sim tsim sratio
  t=$({ time "$bin" fit "$model" "$eps" --quiet --format json >"$work/out.json" 2>/dev/null || true; } 2>&1)
  read -r wall u s <<<"$t"
  cpu=$(python3 -c "print(f'{$u + $s:.1f}')")
  read -r rollouts sim fitted < <(python3 - "$work/out.json" <<'PYEOF'
import json, sys
try:
    d = json.load(open(sys.argv[1]))
except Exception:
    print("- - (fit failed)"); sys.exit()
m = d.get("missing_physics", [])
s = d.get("search", {})
sim = s.get("simulated_s")
print(s.get("rollouts", "-"), "-" if sim is None else f"{sim:.0f}",
      "; ".join(f"{x['effect']}@{'+'.join(x['joints'])}" for x in m) or "(nothing)")
PYEOF
)
  told=$(told_of "$eps")
  twall="-"; ratio="-"; sratio="-"
  if [ -n "$told" ]; then
    t=$({ time "$bin" fit "$model" "$eps" $told --quiet --format json >"$work/told.json" 2>/dev/null || true; } 2>&1)
    read -r twall u s <<<"$t"
    ratio=$(python3 -c "print(f'{$wall / $twall:.1f}')")
    ratios="$ratios $ratio"
    tsim=$(python3 -c "import json; print(json.load(open('$work/told.json'))['search']['simulated_s'])" 2>/dev/null || echo -)
    if [ "$tsim" != "-" ] && [ "$sim" != "-" ]; then
      sratio=$(python3 -c "print(f'{$sim / $tsim:.1f}')")
      sratios="$sratios $sratio"
    fi
  fi
  printf '%-8s %-34s %8s %8s %8s %6s %6s %9s %9s  %s\n' "$group" "$name" "$wall" "$cpu" "$twall" "$ratio" "$sratio" "$rollouts" "$sim" "$fitted"
  times[$group]="${times[$group]:-} $wall"
}
n_case=0
synth() { # model effects extra... → sets $eps to the episodes directory
  local model=$1 eff=$2; shift 2
  n_case=$((n_case + 1))
  "$bin" synth "$model" --effects "$eff" --out "$work/c$n_case" --quiet "$@" >/dev/null
  eps="$work/c$n_case/episodes"
}

printf '%-8s %-34s %8s %8s %8s %6s %6s %9s %9s  %s\n' group case "wall s" "cpu s" "told s" ratio "sim r" rollouts "sim s" fitted
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
  # Long logs: 4 x 25 s at 200 Hz. (The amplitude is smaller than above: at 0.15 for 25 s the
  # feet touch each other, the replay's error is then discontinuous in the knee damping, and
  # even a told fit stops at 2.1 for 3.0 — see docs/fitting.md, Known limits.)
  synth "$asi" "viscous_damping@*_knee=3.0" --episodes 4 --duration 25 --suspend 0.5 \
    --amplitude 0.08 --heldout 1 --seed 7 --sample-hz 200 --control-hz 200
  row legs25 "asimov (4 x 25 s, 200 Hz) knee damping" "$asi" "$eps"
  t1=../shared/data/models/booster_t1/t1.xml
  if [ -f "$t1" ]; then
    synth "$t1" "viscous_damping@*Knee*=2.0" --episodes 4 --duration 10 --suspend 0.5 \
      --amplitude 0.15 --heldout 1 --seed 7
    row t1 "booster t1 23 joints (4 x 10 s) knee damping" "$t1" "$eps"
  else
    echo "t1       (skipping: $t1 is absent)"
  fi
fi
echo
for g in single arm2 arm3 legs12 legs25 t1; do
  [ -n "${times[$g]:-}" ] || continue
  med=$(python3 -c "import statistics,sys; print(f'{statistics.median(map(float, sys.argv[1:])):.1f}')" ${times[$g]})
  case $g in single) tgt="≤ 5 s";; arm3) tgt="≤ 10 s";; legs12) tgt="≤ 90 s";; legs25) tgt="≤ 180 s";; t1) tgt="≤ 300 s";; *) tgt="(2 joints)";; esac
  printf 'median wall %-7s %6s s   target %s\n' "$g" "$med" "$tgt"
done
[ -n "$ratios" ] && python3 -c "import statistics,sys; r=list(map(float, sys.argv[1:])); print(f'blind / told wall time: median {statistics.median(r):.1f}, max {max(r):.1f} over {len(r)} cases   target <= 3')" $ratios
echo "load average at the end: $(cut -d' ' -f1-3 /proc/loadavg) (2 cores; wall times stretch with load)"
[ -n "$sratios" ] && python3 -c "import statistics,sys; r=list(map(float, sys.argv[1:])); print(f'blind / told recording seconds replayed: median {statistics.median(r):.1f}, max {max(r):.1f} over {len(r)} cases')" $sratios
