#!/bin/sh
# Concealed-effect benchmark: hidden effects → synthetic recordings → blind `modellint fit` → score.
# Usage: bench/conceal.sh [--quick] [--filter SUBSTRING]   (markdown table on stdout, progress on stderr)
set -e
cd "$(dirname "$0")/.."
cargo build --release --example conceal_bench
exec ./target/release/examples/conceal_bench "$@"
