#!/bin/sh
# Compiled-model cache under its cap: warm re-lint time of an unchanged mesh-heavy model, then
# the cache size after 10 edits of it (each edit is a new cache entry; the cap evicts the least
# recently used). Prints figures, no pass/fail. MODEL defaults to the Booster T1 scene in
# ../shared (mesh-heavy); CAP_MB to the default cap (300).
set -e
cd "$(dirname "$0")/.."
MODEL=${MODEL:-../shared/data/models/booster_t1/scene.xml}
CAP_MB=${CAP_MB:-300}
if [ ! -f "$MODEL" ]; then echo "skipping: $MODEL is absent"; exit 0; fi
cargo build --release --locked -q
BIN=$PWD/target/release/modellint
CACHE=$(mktemp -d)
WORK=$(mktemp -d)
trap 'rm -rf "$CACHE" "$WORK"' EXIT
cp -r "$(dirname "$MODEL")"/. "$WORK"/
M="$WORK/$(basename "$MODEL")"
export MODELLINT_CACHE_MAX_MB=$CAP_MB
ms() { echo $(($(date +%s%N) / 1000000)); }
"$BIN" "$M" --no-probe --cache-dir "$CACHE" >/dev/null 2>&1 || true
best=999999
for i in 1 2 3 4 5; do
  t0=$(ms); "$BIN" "$M" --no-probe --cache-dir "$CACHE" >/dev/null 2>&1 || true; t1=$(ms)
  d=$((t1 - t0)); [ "$d" -lt "$best" ] && best=$d
done
echo "warm re-lint of an unchanged model (best of 5): ${best} ms"
echo "one entry: $(du -k "$CACHE"/*.mjb | awk '{s+=$1} END {print s}') kB"
for i in 1 2 3 4 5 6 7 8 9 10; do
  printf '\n<!-- edit %s -->\n' "$i" >> "$M"
  "$BIN" "$M" --no-probe --cache-dir "$CACHE" >/dev/null 2>&1 || true
done
echo "after 10 edits: $(ls "$CACHE"/*.mjb | wc -l) entries, $(du -sk "$CACHE" | cut -f1) kB (cap ${CAP_MB} MB)"
