#!/bin/sh
# The long concealed-effect cases of tests/conceal.rs (12-joint Asimov legs, minutes each on two
# cores, three arm3 Stribeck cases and the arm3 backlash + position offset pair), which `make test` skips (#[ignore]): each case's figures on stderr, pass/fail at the
# end. Usage: bench/conceal_long.sh [NAME-FILTER]
set -e
cd "$(dirname "$0")/.."
make -s build >/dev/null
exec cargo test --release --locked --test conceal -- --ignored --nocapture --test-threads 1 ${1:+"$1"}
