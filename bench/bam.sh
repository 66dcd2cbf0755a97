#!/usr/bin/env bash
# The BAM XL330 figure of README and docs/examples/bam-xl330.md: the real servo logs
# (../shared/data/recordings/bam_xl330), each firmware gain held out in turn, fitted by the
# ordinary `modellint fit` on the other gains. Prints every fold and the mean held-out MAE over
# the 16 logs. ~20 min CPU on 2 cores (tests/bam_fit.rs checks one fold).
set -euo pipefail
cd "$(dirname "$0")/.."
logs=${MODELLINT_SHARED_DATA:-../shared/data}/recordings/bam_xl330
if [ ! -d "$logs" ]; then
  echo "SKIPPED: $logs is absent"
  exit 0
fi
make -s build >/dev/null
time ./target/release/modellint fit fixtures/bam_xl330/rig.xml "$logs" --holdout-by kp
