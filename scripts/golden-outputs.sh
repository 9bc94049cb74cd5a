#!/usr/bin/env bash
# Golden outputs: runs one `flinch` binary over every output a user sees (issue 24's "no behaviour
# change" check) and writes them under OUTDIR, so that two binaries (before and after a refactor)
# can be compared with `diff -r`:
#
#   scripts/golden-outputs.sh OLD_BIN /tmp/golden/before
#   scripts/golden-outputs.sh NEW_BIN /tmp/golden/after
#   diff -r /tmp/golden/before /tmp/golden/after     # must print nothing
#
# What it runs (from the repository root, on its scenes/ and docs/):
#   - `scenes list`, and `scenes show` of every shipped scene;
#   - every impact scene's `run --json` and `run --csv` (every shipped scene but avoid_*), and the
#     text summary; `run --measured` of the README's synthetic measurement; `run --plot` (SVG);
#   - `hil --json --csv` on the README's impact scenes, with the README's scan cycle and phase, with
#     the glitch filter, two channels, auto reset and injected faults;
#   - `check` (text and --json) and `design` (text, --json, --body-region) of several scenes;
#   - the README's sweep CSVs (and their SVG plots);
#   - `validate --out` (docs/validation.md and the pictures' SVGs), and `validate --check`;
#   - `bench` over a reduced but representative set of scenes (see BENCH_SCENES: a bi-stable, a
#     hydraulic, a rigid, a free-object, a soft-object and a body-region scene, --repeats 1; the full
#     default set takes minutes and covers the same code), its runs.csv, summary.csv, fixed_point.csv
#     and the table on standard output;
#   - `avoid --json` of every avoid scene, `avoid --csv` of two, `avoid --mcu --json` of two;
#   - `sample --json`, `--csv` and text of the README's study, its chunks and `--merge`;
#   - `robot` of both URDF scenes and a `--sweep-joint --csv`;
#   - `report --out` (the HTML page) of the README's case.
#
# Every command's standard output, standard error and exit status are kept (FILE.out, FILE.err,
# FILE.rc): a message is an output too.
#
# Filtered, because they are not deterministic (each filter is below, named NONDET):
#   1. bench's timings: the columns wall_median_s and x_real_time of runs.csv, total_wall_s,
#      x_real_time_overall and x_real_time_worst_scene of summary.csv, the "x real" and "worst sc."
#      columns of the table on standard output are replaced by "T"; pareto.svg (its axis is the wall
#      time) is not kept.
#   2. The absolute path of the scratch directory and of the repository in messages ("wrote ...")
#      are replaced by $SCRATCH and $REPO.
#   3. The wall time in the progress messages on standard error of `sweep` and `sample` ("30
#      points in 0.06 s (2 threads)", "200 samples in 1.02 s (2 threads, 196 samples/s)"): the
#      seconds become "T" and the rate "R".
#   4. The binary's own name in clap's usage lines: the binary is run through a symlink named
#      `flinch`, so nothing to filter.
#   5. PNG files are not kept (plotters' bitmap encoder is deterministic, but the SVG of the same
#      plot carries the same data and diffs readably); SVGs are kept byte for byte.
# Nothing else is filtered: two runs of the same binary give identical trees (checked by running
# this script twice with one binary and diffing).
set -euo pipefail

if [ $# -ne 2 ]; then
    echo "usage: $0 FLINCH_BINARY OUTDIR" >&2
    exit 2
fi
BIN=$(realpath "$1")
OUT=$2
REPO=$(cd "$(dirname "$0")/.." && pwd)
rm -rf "$OUT"
mkdir -p "$OUT"
OUT=$(realpath "$OUT")
SCRATCH=$(mktemp -d /tmp/flinch-golden.XXXXXX)
trap 'rm -rf "$SCRATCH"' EXIT
mkdir -p "$SCRATCH/bin"
ln -s "$BIN" "$SCRATCH/bin/flinch"
ln -s "$REPO/scenes" "$SCRATCH/scenes"
ln -s "$REPO/docs" "$SCRATCH/docs"
cd "$SCRATCH"
export PATH="$SCRATCH/bin:$PATH"

# NONDET 2: absolute paths in messages.
scrub() { sed -e "s#$SCRATCH#\$SCRATCH#g" -e "s#$REPO#\$REPO#g" "$@"; }
# NONDET 3: wall time in progress messages.
untime() { sed -E -e 's/ in [0-9.]+ s \(([0-9]+ threads?)/ in T s (\1/' -e 's/[0-9.]+ samples\/s/R samples\/s/' "$@"; }

# g NAME CMD...: runs CMD in the scratch directory, keeps its stdout, stderr and exit status.
g() {
    local name=$1
    shift
    mkdir -p "$(dirname "$OUT/$name")"
    set +e
    "$@" >"$OUT/$name.out" 2>"$OUT/$name.err.raw"
    echo $? >"$OUT/$name.rc"
    set -e
    scrub "$OUT/$name.err.raw" | untime >"$OUT/$name.err"
    rm "$OUT/$name.err.raw"
    scrub -i "$OUT/$name.out"
    echo "$name: exit $(cat "$OUT/$name.rc")" >&2
}

# keep FILE DEST: moves a file a command wrote into the output tree.
keep() {
    mkdir -p "$(dirname "$OUT/$2")"
    if [ -e "$1" ]; then mv "$1" "$OUT/$2"; else echo "missing" >"$OUT/$2.missing"; fi
}

# --- scenes ---------------------------------------------------------------------------------
g scenes/list flinch scenes list
SCENES=$(flinch scenes list | awk '{print $1}')
for s in $SCENES; do
    g "scenes/show/${s//\//__}" flinch scenes show "$s"
done

# --- run ------------------------------------------------------------------------------------
for s in $SCENES; do
    case $s in avoid_*) continue ;; esac
    n=${s//\//__}
    g "run/$n.text" flinch run "$s"
    g "run/$n.json" flinch run "$s" --json
    g "run/$n.csv" flinch run "$s" --csv "run.csv"
    keep run.csv "run/$n.csv.file"
done
g run/measured flinch run tables5-7_bistable --measured docs/measured/tables5-7_bistable_synthetic.csv
g run/plot_bistable flinch run tables5-7_bistable --plot run.svg
keep run.svg run/plot_bistable.svg
g run/plot_hydraulic flinch run table14_hydraulic_surface --plot hydraulic.svg
keep hydraulic.svg run/plot_hydraulic.svg
g run/stdin_csv sh -c 'flinch scenes show tables5-7_bistable | flinch run - --csv -'

# --- hil ------------------------------------------------------------------------------------
hil_case() {
    local name=$1
    shift
    g "hil/$name" flinch hil "$@" --json --csv hil.csv
    keep hil.csv "hil/$name.csv.file"
    g "hil/$name.text" flinch hil "$@"
}
hil_case bistable_readme tables5-7_bistable --scan-cycle 0.016 --phase 0.3
hil_case bistable_default tables5-7_bistable
hil_case hydraulic table14_hydraulic_surface --scan-cycle 0.016 --phase 0.3
hil_case bistable_v025 tables5-7_bistable_v025 --scan-cycle 0.016 --filter consecutive:3 --tick 1e-4
hil_case bistable_two_channels tables5-7_bistable --scan-cycle 0.016 --channels 2 --reset-policy auto:0.05
hil_case fault_welded tables5-7_bistable --scan-cycle 0.016 --fault welded-output@0.1
hil_case fault_stuck tables5-7_bistable --scan-cycle 0.016 --fault stuck-rest@0.2,reset@0.3
hil_case body_hand body_hand --scan-cycle 0.016
g hil/plot flinch hil tables5-7_bistable --scan-cycle 0.016 --phase 0.3 --plot hil.svg
keep hil.svg hil/plot.svg

# --- check and design -----------------------------------------------------------------------
for s in tables5-7_bistable tables5-7_bistable_v025 tables5-7_bistable_stopping_table table14_hydraulic_surface table12_hydraulic_object tables5-7_rigid body_hand; do
    g "check/$s" flinch check "$s"
    g "check/$s.json" flinch check "$s" --json
done
for s in tables5-7_bistable tables5-7_bistable_v025 tables5-7_bistable_stopping_table table14_hydraulic_surface; do
    g "design/$s" flinch design "$s"
    g "design/$s.json" flinch design "$s" --json
done
g design/bistable_dt70 flinch design tables5-7_bistable --dead-time 0.07 --plot design.svg
keep design.svg design/bistable_dt70.svg
g design/body_hand flinch design body_hand --body-region hand
g design/body_hand_free flinch design body_hand_free --body-region hand
g design/body_hand_all.json flinch design body_hand --body-region all --json

# --- sweep (README) -------------------------------------------------------------------------
g sweep/speed flinch sweep scenes/tables5-7_bistable.toml --vary motion.speed=0.01:0.3:30 --plot speed.svg --csv speed.csv
keep speed.csv sweep/speed.csv
keep speed.svg sweep/speed.svg
g sweep/modes flinch sweep scenes/figures/ch3_bistable_sweep.toml --vary motion.speed=0.05:0.3:11 --vary motion.dead_time=0:0.1:11 --metric peak_robot_force --log-color --plot modes.svg --csv modes.csv
keep modes.csv sweep/modes.csv
keep modes.svg sweep/modes.svg
g sweep/robot_elbow flinch sweep robot_two_link --vary robot.joints.elbow=0.6:2.4:10 --csv -

# --- validate -------------------------------------------------------------------------------
mkdir -p validate_out
g validate/run flinch validate --out validate_out --scenes scenes
mv validate_out "$OUT/validate/docs"
g validate/check flinch validate --check --scenes scenes

# --- bench (reduced) ------------------------------------------------------------------------
BENCH_SCENES="tables5-7_bistable table14_hydraulic_surface tables5-7_rigid table1_free_tool table8_bistable body_hand"
# shellcheck disable=SC2086
g bench/table flinch bench $BENCH_SCENES --repeats 1 --out bench_out
# NONDET 1: timings.
python3 - "$SCRATCH/bench_out" "$OUT/bench" <<'EOF'
import csv, os, sys
src, dst = sys.argv[1], sys.argv[2]
os.makedirs(dst, exist_ok=True)
timed = {"wall_median_s", "x_real_time", "total_wall_s", "x_real_time_overall", "x_real_time_worst_scene"}
for name in ["runs.csv", "summary.csv", "fixed_point.csv"]:
    with open(os.path.join(src, name), newline="") as f:
        rows = list(csv.reader(f))
    cols = [i for i, h in enumerate(rows[0]) if h in timed]
    with open(os.path.join(dst, name), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(rows[0])
        for r in rows[1:]:
            w.writerow(["T" if i in cols else v for i, v in enumerate(r)])
EOF
# The table: its last two columns ("x real", "worst sc.") are timings.
awk 'length($0) == 119 && !/^configuration/ { print substr($0, 1, 97) "  T  T"; next } { print }' \
    "$OUT/bench/table.out" >"$OUT/bench/table.out.t"
mv "$OUT/bench/table.out.t" "$OUT/bench/table.out"

# --- avoid ----------------------------------------------------------------------------------
for s in $SCENES; do
    case $s in avoid_*) ;; *) continue ;; esac
    g "avoid/$s.json" flinch avoid "$s" --json
done
g avoid/operator_hand.text flinch avoid avoid_operator_hand --csv avoid.csv --plot avoid.svg
keep avoid.csv avoid/operator_hand.csv
keep avoid.svg avoid/operator_hand.svg
g avoid/thesis_reach.text flinch avoid avoid_thesis_reach --thesis --csv -
g avoid/operator_hand_mcu.json flinch avoid avoid_operator_hand --mcu --json
g avoid/forearm_across_30_mcu.json flinch avoid avoid_forearm_across_30 --mcu --json

# --- sample (README) ------------------------------------------------------------------------
VARY=(--vary motion.dead_time=uniform:0.016:0.032 --vary motion.speed=normal:0.25:0.01 --vary decoupler.spring_rate=normal:200:10 --vary decoupler.height=normal:0.03:0.0005)
g sample/text flinch sample tables5-7_bistable_v025 --samples 200 "${VARY[@]}"
g sample/json flinch sample tables5-7_bistable_v025 --samples 200 --json --csv sample.csv "${VARY[@]}"
keep sample.csv sample/rows.csv
g sample/chunk1 flinch sample tables5-7_bistable_v025 --samples 200 --chunk 1/2 --json "${VARY[@]}"
g sample/chunk2 flinch sample tables5-7_bistable_v025 --samples 200 --chunk 2/2 --json "${VARY[@]}"
cp "$OUT/sample/chunk1.out" chunk1.json
cp "$OUT/sample/chunk2.out" chunk2.json
g sample/merge flinch sample --merge chunk1.json chunk2.json
g sample/body flinch sample body_hand --samples 50 --seed 7 --vary motion.speed=uniform:0.1:0.4 --json --csv body.csv
keep body.csv sample/body.csv

# --- robot ----------------------------------------------------------------------------------
g robot/two_link flinch robot robot_two_link
g robot/viper flinch robot robot_viper_standin
g robot/elbow flinch robot robot_two_link --sweep-joint elbow --points 19 --csv elbow.csv --plot elbow.svg
keep elbow.csv robot/elbow.csv
keep elbow.svg robot/elbow.svg

# --- report ---------------------------------------------------------------------------------
g report/stopping_table flinch report tables5-7_bistable_stopping_table --out report.html --sweep motion.speed=0.1:0.3:5 --sweep tool.mass=0.5:1.0:3
keep report.html report/stopping_table.html

# --- bad input (messages are outputs) -------------------------------------------------------
printf '[motion]\nspeed = -1\n' >bad.toml
g errors/bad_scene flinch run bad.toml
g errors/unknown_scene flinch run no_such_scene

# Every kept file: the same bytes for the same binary (NONDET 2 on files the commands wrote).
find "$OUT" -type f \( -name '*.csv' -o -name '*.svg' -o -name '*.md' -o -name '*.html' -o -name '*.file' \) -print0 |
    xargs -0 sed -i -e "s#$SCRATCH#\$SCRATCH#g" -e "s#$REPO#\$REPO#g"
echo "golden outputs of $BIN in $OUT: $(find "$OUT" -type f | wc -l) files" >&2
