#!/usr/bin/env bash
# The test command of the README and of CI: installs system packages, checks formatting and
# clippy, runs every test on lavapipe, then renders every sky in skies/ headless (the CI smoke set)
# and runs `skytune bench` briefly.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh

# Software Vulkan everywhere in tests: identical pixels on every machine.
export SKYTUNE_ADAPTER=cpu
# Mesa's WSI complains without one; nothing here uses Wayland.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
export RUST_BACKTRACE=1
# A clean clone gains nothing from incremental caches; they would take gigabytes of CI's disk.
if [ "${CI:-}" = "true" ]; then export CARGO_INCREMENTAL=0; fi

echo "lint: cargo fmt --check, cargo clippy -D warnings"
cargo fmt --check
cargo clippy --locked --all-targets -- -D warnings

cargo build --locked --bins
cargo test --locked -- --test-threads=2

echo "smoke: rendering every sky in skies/ on lavapipe"
out="$(mktemp -d)"
count=0
for sky in skies/*/sky.toml skies/*/continent.toml; do
    [ -e "$sky" ] || continue
    name="$(basename "$(dirname "$sky")")-$(basename "$sky" .toml)"
    ./target/debug/skytune check "$sky" >/dev/null
    for hw in "12 0" "18.5 0.3" "23 0" "15 1"; do
        set -- $hw
        ./target/debug/skytune render "$sky" --hour "$1" --weather "$2" --size 320x180 --out "$out/$name-$1-$2.png" >/dev/null
    done
    count=$((count + 1))
done
[ "$count" -gt 0 ] || { echo "smoke: no skies found in skies/" >&2; exit 1; }
./target/debug/skytune render --size 320x180 --out "$out/builtin.png" >/dev/null
echo "smoke: $count sky files rendered at 4 (hour, weather) pairs each, plus the built-in sky"

echo "models: the quick speed-against-accuracy benchmark and a stability sweep (docs/models.md, docs/stability.md)"
./target/debug/skytune bench models --quick --frames 3 --out "$out/models" >/dev/null
grep -q "model GPU ms, sun moving / still" "$out/models/models.md" && grep -q "^## Accuracy by regime" "$out/models/models.md" \
    || { echo "models: models.md lacks the model-only cost columns or the per-regime table" >&2; exit 1; }
./target/debug/skytune sweep --count 2000 --out "$out/stability.md" >/dev/null

echo "soak: 1000 frames of random changes, sky reloads (good and broken) and shader rebuilds"
./target/debug/skytune soak --frames 1000 --size 96x54 --warm-up-frames 500 --max-rss-growth-percent 10 --report "$out/reliability.md" >/dev/null

echo "smoke: skytune bench frame --quick (every sky against the fill-rate floor)"
./target/debug/skytune bench frame --quick --out "$out/performance.md" > "$out/frame.txt"
tail -1 "$out/frame.txt"
grep -q '^fill_limit_ratio worst=[0-9.]* median=[0-9.]*$' "$out/frame.txt"

echo "smoke: skytune bench (a few frames; the report goes to a temporary file)"
./target/debug/skytune bench --frames 3 --size 160x90 --out "$out/benchmarks.md" >/dev/null
if grep -q "NaN" "$out/benchmarks.md"; then
    echo "smoke: the benchmark report has missing timings:" >&2
    cat "$out/benchmarks.md" >&2
    exit 1
fi
echo "smoke: bench ok"
