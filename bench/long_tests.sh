#!/bin/sh
# Every test `make test` skips for its length (`#[ignore = "long ..."]` / "12-joint legs ..."):
# the Asimov-legs and arm3 Stribeck cases of tests/conceal.rs and the blind trunk battery and the
# episode rotation of tests/independent_free.rs — tens of minutes on two cores. Pass/fail at the
# end, each conceal case's figures on stderr. Usage: bench/long_tests.sh [NAME-FILTER]
set -e
cd "$(dirname "$0")/.."
make -s build >/dev/null
exec cargo test --release --locked -- --ignored --nocapture --test-threads 1 ${1:+"$1"}
