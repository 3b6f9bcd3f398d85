#!/usr/bin/env bash
# Does the grasp act through the centre of mass? (issue 55, item 4; docs/results/com_sweep.)
# The grasp-position sweep over the whole graspable length (15 offsets x 50 scenes) of
#   twin      the uniform peg: the published cell_graspable sweep itself;
#   com20     the same scenes, the centre of mass 20 mm from the middle (an insert, unmarked);
#   com20_ft  com20 under the transport's old rule, the F/T moment picking the hanging end
#             (assembly.longer_end_margin=1: every grasp within the margin);
# then `vgs com-fit` of each shifted sweep against the twin. Each sweep resumes when started
# again; about 25 min each on an idle 2-core host.
# Usage: scripts/com_results.sh [OUT]   (default OUT: runs/com; then copy into docs/results)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-runs/com}
VGS=.venv/bin/vgs
SWEEP=(sweep --offsets-mm=-48,-45,-40,-35,-26.25,-17.5,-8.75,0,8.75,17.5,26.25,35,40,45,48
       --trials 50 --workers 2 --no-progress)
COM=(--set cell.peg.com_shift_mm=20 --set cell.peg.com_marking=hidden)
$VGS "${SWEEP[@]}" --out "$OUT/twin"
$VGS "${SWEEP[@]}" "${COM[@]}" --out "$OUT/com20"
$VGS "${SWEEP[@]}" "${COM[@]}" --set assembly.longer_end_margin=1.0 --out "$OUT/com20_ft"
$VGS com-fit "$OUT/com20" --twin "$OUT/twin" --out "$OUT/fit"
$VGS com-fit "$OUT/com20_ft" --twin "$OUT/twin" --out "$OUT/fit_ft"
