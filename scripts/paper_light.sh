#!/usr/bin/env bash
# The paper's protocol with the light backbone for one training seed (issue 18; the `paper-light`
# profile, docs/training.md): the baseline's training first (about 1 h here: grasps without
# assembly), then VGS's, then 1000 tests per policy and condition, the report, and its
# publication under docs/results/paper_light_s<SEED>. Every step resumes from the run folder when
# started again, also after the folder was moved to another machine (docs/training.md, "Runs
# that move between machines"). A run that cannot finish on this machine moves through git:
# stop it, `scripts/carry.sh pack runs/paper_light_s<SEED> docs/results/unfinished/
# paper_light_s<SEED>.tar.xz`, commit that file; on the next machine this script unpacks it
# and goes on, and deletes it once the run is published (commit the deletion).
# The paper's position action is the profile's default; ACTION=rotation runs the rotation action
# space of visual-pushing-grasping (the published docs/results/paper_light_rotation_s0..s2),
# into runs/paper_light_rotation_s<SEED>.
# Usage: [ACTION=position|rotation] scripts/paper_light.sh SEED
set -euo pipefail
cd "$(dirname "$0")/.."
SEED=${1:?usage: scripts/paper_light.sh SEED}
ACTION=${ACTION:-position}
NAME=paper_light_s$SEED
[ "$ACTION" = position ] || NAME=paper_light_${ACTION}_s$SEED
OUT=runs/$NAME
CARRY=docs/results/unfinished/$NAME.tar.xz
VGS=.venv/bin/vgs
SET=(--profile paper-light --set "network.action=$ACTION" --set "reproduce.train_seeds=($SEED,)")
if [ ! -e "$OUT" ] && [ -f "$CARRY" ]; then
    scripts/carry.sh unpack "$CARRY" "$OUT"
fi
# The baseline alone first: it is short, and a finished run needs no checkpoint to move.
$VGS train --mode baseline "${SET[@]}" --seed "$SEED" --out "$OUT/train/baseline_s$SEED" \
    --no-progress
$VGS reproduce "${SET[@]}" --out "$OUT" --no-progress
$VGS report "$OUT" --title "VGS reproduction report (paper-light, $ACTION action, seed $SEED)" \
    --publish "docs/results/$NAME"
rm -f "$CARRY"
