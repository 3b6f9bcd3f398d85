#!/usr/bin/env bash
# The cell's published measurements (docs/results/cell_stiction, docs/results/paper_center_stiction),
# exactly as run for docs/assembly.md. About 20 min for the sweeps and 50 min for the 3 x 1000
# centre grasps on an idle 2-core host. Each command resumes where it stopped when started again.
# Usage: scripts/cell_results.sh [OUT]   (default OUT: runs/cell; then copy into docs/results)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-runs/cell}
VGS=.venv/bin/vgs
$VGS sweep --offsets 9 --trials 50 --workers 2 --out "$OUT/sweep" --no-progress
$VGS sweep --offsets-mm 0 --trials 200 --workers 2 --out "$OUT/com200" --no-progress
# The whole graspable length (docs/results/cell_graspable; about 25 min on an idle host).
$VGS sweep --offsets-mm=-48,-45,-40,-35,-26.25,-17.5,-8.75,0,8.75,17.5,26.25,35,40,45,48 \
    --trials 50 --workers 2 --out "$OUT/graspable" --no-progress
$VGS sweep --offsets 9 --trials 50 --workers 2 --mass-range 0.15 --length-range 0.15 \
    --out "$OUT/sweep_mass_length" --no-progress
for condition in nominal mass length; do
    $VGS evaluate --profile paper --policy center --condition "$condition" --workers 2 \
        --out "$OUT/paper_center/eval/center/$condition" --no-progress
done
$VGS report "$OUT/paper_center" \
    --title "Centre heuristic at the paper's scale (vgs evaluate --profile paper --policy center)"
echo "tables: benchmarks/sweep_tables.py at ac53c96 (git show ac53c96:benchmarks/sweep_tables.py)" \
    "on $OUT/sweep (com200, sweep_mass_length)"
