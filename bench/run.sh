#!/bin/sh
# All benchmarks, printing figures (no pass/fail): lint + probe timings, then gap replay at the
# seed study's scale (GAP_BENCH_SCALE=0.1 for a tenth). Fit timings (blind fits from the CLI on
# recordings of the independent synth) are bench/fit_speed.sh; the concealed-effect benchmark is
# bench/conceal.sh.
set -e
cd "$(dirname "$0")/.."
cargo build --release --examples
./target/release/examples/lint_bench
./target/release/examples/gap_bench "$@"
./target/release/examples/cache_bench
