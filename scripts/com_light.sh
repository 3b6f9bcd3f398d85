#!/usr/bin/env bash
# The paper-light protocol on a peg whose centre of mass lies 20 mm from its middle, the heavy
# end painted (issue 55; the `com` condition, docs/evaluation.md): the baseline's and VGS's
# training on such pegs (`cell.peg.com_shift_mm=20`, the heavy end wherever the peg's random
# yaw turns it), then 1000 test scenes of `com` for each, for the centre heuristic (the middle
# of the perceived peg) and for the centre-of-mass oracle (`com-oracle`: the true centre of
# mass, ground truth, analysis only), the report, and its publication under
# docs/results/com_light_s<SEED>. CONDITION=com-hidden runs the unmarked peg into
# runs/com_hidden_light_s<SEED> (the control). Every step resumes from the run folder; a run
# that cannot finish here moves through git as scripts/paper_light.sh says (carry.sh).
# Usage: [CONDITION=com|com-hidden] scripts/com_light.sh SEED
set -euo pipefail
cd "$(dirname "$0")/.."
SEED=${1:?usage: scripts/com_light.sh SEED}
CONDITION=${CONDITION:-com}
case "$CONDITION" in
    com) MARKING=visible; NAME=com_light_s$SEED ;;
    com-hidden) MARKING=hidden; NAME=com_hidden_light_s$SEED ;;
    *) echo "CONDITION must be com or com-hidden, got $CONDITION" >&2; exit 2 ;;
esac
OUT=runs/$NAME
CARRY=docs/results/unfinished/$NAME.tar.xz
VGS=.venv/bin/vgs
SET=(--profile paper-light --set cell.peg.com_shift_mm=20 --set "cell.peg.com_marking=$MARKING"
     --set "reproduce.conditions=(\"$CONDITION\",)"
     --set 'reproduce.reference_policies=("center","com-oracle")'
     --set "reproduce.train_seeds=($SEED,)")
if [ ! -e "$OUT" ] && [ -f "$CARRY" ]; then
    scripts/carry.sh unpack "$CARRY" "$OUT"
fi
$VGS train --mode baseline "${SET[@]}" --seed "$SEED" --out "$OUT/train/baseline_s$SEED" \
    --no-progress
$VGS reproduce "${SET[@]}" --out "$OUT" --no-progress
$VGS report "$OUT" --title "VGS on a peg whose centre of mass is 20 mm off its middle ($CONDITION, paper-light, seed $SEED)" \
    --publish "docs/results/$NAME"
rm -f "$CARRY"
