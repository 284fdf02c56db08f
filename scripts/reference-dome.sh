#!/usr/bin/env bash
# Recomputes the benchmark's reference dome (assets/reference_dome.csv) shard by shard, so that
# no step runs longer than about 10 minutes on two cores and an interruption loses one shard at
# most: each shard is written to assets/reference-dome-shards/ (atomically) as it finishes, a
# complete shard of the same settings is skipped on the next run, and the merge at the end writes
# the dataset byte for byte as one `skytune bench models` would. With --commit, each shard is
# committed as soon as it is done (the way the committed dataset was made: docs/batch.md).
#
#   bash scripts/reference-dome.sh [--commit] [SHARDS]      (SHARDS: 4 by default)
set -euo pipefail
cd "$(dirname "$0")/.."
commit=0
if [ "${1:-}" = "--commit" ]; then commit=1; shift; fi
n="${1:-4}"
dir=assets/reference-dome-shards
mkdir -p "$dir"
cargo build --release --locked --bins
for k in $(seq 1 "$n"); do
    out="$dir/dome-$k-of-$n.csv"
    start=$(date +%s)
    ./target/release/skytune bench models --shard "$k/$n" --out "$out"
    echo "reference-dome: shard $k/$n in $(( $(date +%s) - start )) s"
    if [ "$commit" = 1 ]; then
        git add "$out"
        git diff --cached --quiet -- "$out" || git commit -q -m "Reference dome: shard $k/$n" -- "$out"
    fi
done
./target/release/skytune merge --out assets/reference_dome.csv "$dir"/dome-*-of-"$n".csv
echo "reference-dome: wrote assets/reference_dome.csv; the shards in $dir may go"
