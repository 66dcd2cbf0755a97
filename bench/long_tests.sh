#!/bin/sh
# Every test `make test` skips for its length (`#[ignore = "long ..."]` / "12-joint legs ..."):
# the Asimov-legs, arm3 Stribeck and arm3 backlash + position offset cases of tests/conceal.rs,
# the blind trunk battery and the episode rotation of tests/independent_free.rs, the Stribeck and
# load-dependent friction recoveries of tests/fit.rs and the kp-400 fold of tests/bam_fit.rs —
# tens of minutes on two cores. Pass/fail at the
# end, each conceal case's figures on stderr. Usage: bench/long_tests.sh [NAME-FILTER]
set -e
cd "$(dirname "$0")/.."
make -s build >/dev/null
exec cargo test --release --locked -- --ignored --nocapture --test-threads 1 ${1:+"$1"}
