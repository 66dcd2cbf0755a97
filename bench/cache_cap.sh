#!/bin/sh
# Lint cache under its cap: size of one entry, warm re-lint time of an unchanged mesh-heavy
# model (answered from the entry, no compile), then the cache size after 10 edits of it (each
# edit is a new entry; the cap evicts the least recently used). Prints figures, no pass/fail.
# MODELS defaults to the Booster T1 and Unitree H1 scenes in ../shared (mesh-heavy); CAP_MB to
# the default cap (300); ARGS to the pre-commit hook's options.
set -e
cd "$(dirname "$0")/.."
MODELS=${MODELS:-"../shared/data/models/booster_t1/scene.xml ../shared/data/models/unitree_h1/scene.xml"}
CAP_MB=${CAP_MB:-300}
ARGS=${ARGS:-"--no-probe --output-format concise"}
cargo build --release --locked -q
BIN=$PWD/target/release/modellint
export MODELLINT_CACHE_MAX_MB=$CAP_MB
ms() { echo $(($(date +%s%N) / 1000000)); }
for MODEL in $MODELS; do
  if [ ! -f "$MODEL" ]; then echo "skipping: $MODEL is absent"; continue; fi
  CACHE=$(mktemp -d)
  WORK=$(mktemp -d)
  cp -r "$(dirname "$MODEL")"/. "$WORK"/
  chmod -R u+w "$WORK"
  M="$WORK/$(basename "$MODEL")"
  echo "== $MODEL ($ARGS)"
  t0=$(ms); "$BIN" "$M" $ARGS --cache-dir "$CACHE" >/dev/null 2>&1 || true; t1=$(ms)
  echo "cold lint (compile, then store): $((t1 - t0)) ms"
  echo "one entry: $(du -b "$CACHE"/*.lint | awk '{s+=$1} END {print s}') bytes"
  best=999999
  for i in 1 2 3 4 5; do
    t0=$(ms); "$BIN" "$M" $ARGS --cache-dir "$CACHE" >/dev/null 2>&1 || true; t1=$(ms)
    d=$((t1 - t0)); [ "$d" -lt "$best" ] && best=$d
  done
  echo "warm re-lint of the unchanged model (best of 5): ${best} ms"
  # Edits of the included robot file and of one mesh (a binary STL's free 80-byte header, so
  # the mesh stays valid): each a new key (no stale hit).
  ROBOT=$(ls "$WORK"/*.xml | grep -v "/$(basename "$MODEL")\$" | head -1)
  MESH=$(ls "$WORK"/assets/* 2>/dev/null | head -1)
  for i in 1 2 3 4 5 6 7 8 9 10; do
    if [ $((i % 2)) = 0 ] && [ -n "$MESH" ]; then printf 'edit %s' "$i" | dd of="$MESH" conv=notrunc status=none; else printf '\n<!-- edit %s -->\n' "$i" >> "${ROBOT:-$M}"; fi
    "$BIN" "$M" $ARGS --cache-dir "$CACHE" >/dev/null 2>&1 || true
  done
  echo "after 10 edits (robot file, mesh): $(ls "$CACHE"/*.lint | wc -l) entries, $(du -sb "$CACHE" | cut -f1) bytes (cap ${CAP_MB} MB)"
  rm -rf "$CACHE" "$WORK"
done
