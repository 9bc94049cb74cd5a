#!/usr/bin/env bash
# Incremental rebuild time after a trivial edit to one plant element (issue 24, docs/architecture.md):
#
#   scripts/rebuild-times.sh PLANT_FILE [RUNS]
#
# e.g. scripts/rebuild-times.sh host-harness/crates/plant/src/decoupler/bistable.rs
# (before the split: host-harness/src/plant/decoupler/bistable.rs). For each of
# `cargo build --release --bin flinch` and `cargo test --workspace --no-run`: one untimed build to
# warm the target directory, then RUNS (default 3) times: append a comment line to PLANT_FILE (a
# change rustc must re-read, not only a touched timestamp), build, and time it; the file is
# restored at the end. Prints each time with the machine's 1-minute load average (`uptime`)
# before it, and the median. Builds run under `nice -n 10` as every build on this shared machine.
set -euo pipefail
FILE=$1
RUNS=${2:-3}
cd "$(dirname "$0")/.."
cp "$FILE" "$FILE.rebuild-times.bak"
trap 'mv "$FILE.rebuild-times.bak" "$FILE"' EXIT

measure() {
    local what=$1
    shift
    nice -n 10 "$@" >/dev/null 2>&1 # warm
    local times=()
    for i in $(seq "$RUNS"); do
        echo "// rebuild-times $i $(date +%s%N)" >>"$FILE"
        local load
        load=$(uptime | sed -E 's/.*load average: ([0-9.]+),.*/\1/')
        local t0 t1
        t0=$(date +%s.%N)
        nice -n 10 "$@" >/dev/null 2>&1
        t1=$(date +%s.%N)
        local dt
        dt=$(echo "$t1 - $t0" | bc)
        times+=("$dt")
        printf '%s run %d: %.1f s (load %s)\n' "$what" "$i" "$dt" "$load"
    done
    printf '%s median of %d: %.1f s\n' "$what" "$RUNS" "$(printf '%s\n' "${times[@]}" | sort -n | sed -n "$(((RUNS + 1) / 2))p")"
}

measure "cargo build --release --bin flinch" cargo build --release --bin flinch
measure "cargo test --workspace --no-run" cargo test --workspace --no-run
