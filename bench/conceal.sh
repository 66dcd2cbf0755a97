#!/bin/sh
# Concealed-effect benchmark: hidden effects → synthetic recordings → blind `modellint fit` → score.
# Usage: bench/conceal.sh [--quick] [--filter TERM[,TERM...]]  (cases whose label has every TERM,
#        e.g. --filter 'arm3,real 12b')   (markdown table on stdout, progress on stderr)
set -e
cd "$(dirname "$0")/.."
cargo build --release --example conceal_bench
exec ./target/release/examples/conceal_bench "$@"
