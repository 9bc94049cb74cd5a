#!/usr/bin/env bash
# Incremental rebuild time after a trivial edit to one plant element (issue 24, docs/architecture.md),
# in one or more source trees, interleaved so that every tree sees the same machine load:
#
#   scripts/rebuild-times.sh [-n RUNS] TREE:PLANT_FILE [TREE:PLANT_FILE ...]
#
# e.g. (main's layout in /tmp/before, this one here):
#   scripts/rebuild-times.sh /tmp/before:host-harness/src/plant/decoupler/bistable.rs \
#                            .:host-harness/crates/plant/src/decoupler/bistable.rs
#
# For each of `cargo build --release --bin flinch` and `cargo test --workspace --no-run`: one untimed
# build per tree to warm its target directory, then RUNS (default 3) rounds, each tree in turn:
# append a comment line to its PLANT_FILE (a change rustc must re-read, not only a timestamp), build,
# time it. Every file is restored at the end. Prints each time with the 1-minute load average
# (`uptime`) before it, and each tree's median. Builds run under `nice -n 10`, as every build on
# this shared machine.
set -euo pipefail
RUNS=3
if [ "${1:-}" = "-n" ]; then
    RUNS=$2
    shift 2
fi
[ $# -ge 1 ] || { echo "usage: $0 [-n RUNS] TREE:PLANT_FILE..." >&2; exit 2; }
SPECS=("$@")
for s in "${SPECS[@]}"; do
    f="${s%%:*}/${s#*:}"
    cp "$f" "$f.rebuild-times.bak"
done
restore() {
    for s in "${SPECS[@]}"; do
        f="${s%%:*}/${s#*:}"
        [ -e "$f.rebuild-times.bak" ] && mv "$f.rebuild-times.bak" "$f"
    done
}
trap restore EXIT

measure() {
    local what=$1
    shift
    declare -A times
    for s in "${SPECS[@]}"; do
        (cd "${s%%:*}" && nice -n 10 "$@" >/dev/null 2>&1) # warm
    done
    for i in $(seq "$RUNS"); do
        for s in "${SPECS[@]}"; do
            local tree=${s%%:*} file=${s#*:}
            echo "// rebuild-times $i $(date +%s%N)" >>"$tree/$file"
            local load t0 t1 dt
            load=$(uptime | sed -E 's/.*load average: ([0-9.]+),.*/\1/')
            t0=$(date +%s.%N)
            (cd "$tree" && nice -n 10 "$@" >/dev/null 2>&1)
            t1=$(date +%s.%N)
            dt=$(echo "$t1 - $t0" | bc)
            times[$tree]="${times[$tree]:-} $dt"
            printf '%s in %s, run %d: %.1f s (load %s)\n' "$what" "$tree" "$i" "$dt" "$load"
        done
    done
    for s in "${SPECS[@]}"; do
        local tree=${s%%:*}
        # shellcheck disable=SC2086
        printf '%s in %s: median of %d %.1f s\n' "$what" "$tree" "$RUNS" "$(printf '%s\n' ${times[$tree]} | sort -n | sed -n "$(((RUNS + 1) / 2))p")"
    done
}

measure "cargo build --release --bin flinch" cargo build --release --bin flinch
measure "cargo test --workspace --no-run" cargo test --workspace --no-run
