#!/bin/sh
# All benchmarks, printing figures (no pass/fail): lint + probe timings, fit timings, then gap
# replay at the seed study's scale (GAP_BENCH_SCALE=0.1 for a tenth). The concealed-effect
# benchmark is separate: bench/conceal.sh.
set -e
cd "$(dirname "$0")/.."
cargo build --release --examples
./target/release/examples/lint_bench
./target/release/examples/fit_bench
./target/release/examples/gap_bench "$@"
./target/release/examples/cache_bench
