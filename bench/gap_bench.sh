#!/bin/sh
# Replay throughput at the seed study's scale (see examples/gap_bench.rs).
# Usage: bench/gap_bench.sh [MODEL]   (GAP_BENCH_SCALE=0.1 for a tenth)
set -e
cd "$(dirname "$0")/.."
cargo build --release --example gap_bench
exec ./target/release/examples/gap_bench "$@"
