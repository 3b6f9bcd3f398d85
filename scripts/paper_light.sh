#!/usr/bin/env bash
# The paper's protocol with the light backbone for one training seed (issue 18; the `paper-light`
# profile, docs/training.md): the baseline's training first (about 1 h here: grasps without
# assembly), then VGS's, then 1000 tests per policy and condition, the report, and its
# publication under docs/results/paper_light_s<SEED>. Every step resumes from the run folder when
# started again, also after the folder was moved to another machine (docs/training.md, "Runs
# that move between machines"). A run that cannot finish on this machine moves through git:
# stop it, `scripts/carry.sh pack runs/paper_light_s<SEED> docs/results/unfinished/
# paper_light_s<SEED>.tar.xz`, commit that file (or its pieces, .part00 ...); on the next
# machine this script unpacks it and goes on, and deletes it once the run is published (commit
# the deletion).
# The paper's position action is the profile's default; ACTION=rotation runs the rotation action
# space of visual-pushing-grasping, into runs/paper_light_rotation_s<SEED>.
# PEG=com runs the protocol on pegs whose centre of mass lies 20 mm from the middle, the heavy
# end painted (issue 55, the `com` condition of docs/evaluation.md; the heavy end wherever the
# peg's random yaw turns it): trained on such pegs, tested on `com` beside the centre heuristic
# (the middle of the perceived peg) and the centre-of-mass oracle (`com-oracle`: ground truth,
# analysis only), into runs/com_light_s<SEED>; PEG=com-hidden the unmarked control, into
# runs/com_hidden_light_s<SEED>.
# Usage: [ACTION=position|rotation] [PEG=uniform|com|com-hidden] scripts/paper_light.sh SEED
set -euo pipefail
cd "$(dirname "$0")/.."
SEED=${1:?usage: scripts/paper_light.sh SEED}
ACTION=${ACTION:-position}
NAME=paper_light_s$SEED
[ "$ACTION" = position ] || NAME=paper_light_${ACTION}_s$SEED
VGS=.venv/bin/vgs
SET=(--profile paper-light --set "network.action=$ACTION" --set "reproduce.train_seeds=($SEED,)")
TITLE="VGS reproduction report (paper-light, $ACTION action, seed $SEED)"
PEG=${PEG:-uniform}
case "$PEG" in
    uniform) ;;
    com|com-hidden)
        [ "$ACTION" = position ] || { echo "PEG=$PEG runs the position action only" >&2; exit 2; }
        MARKING=visible; [ "$PEG" = com ] || MARKING=hidden
        NAME=${PEG//-/_}_light_s$SEED
        SET+=(--set cell.peg.com_shift_mm=20 --set "cell.peg.com_marking=$MARKING"
              --set "reproduce.conditions=(\"$PEG\",)"
              --set 'reproduce.reference_policies=("center","com-oracle")')
        TITLE="VGS on pegs whose centre of mass is 20 mm off the middle ($PEG, paper-light, seed $SEED)" ;;
    *) echo "PEG must be uniform, com or com-hidden, got $PEG" >&2; exit 2 ;;
esac
OUT=runs/$NAME
CARRY=docs/results/unfinished/$NAME.tar.xz
if [ ! -e "$OUT" ] && { [ -f "$CARRY" ] || [ -f "$CARRY.part00" ]; }; then
    scripts/carry.sh unpack "$CARRY" "$OUT"
fi
# The baseline alone first: it is short, and a finished run needs no checkpoint to move.
$VGS train --mode baseline "${SET[@]}" --seed "$SEED" --out "$OUT/train/baseline_s$SEED" \
    --no-progress
$VGS reproduce "${SET[@]}" --out "$OUT" --no-progress
$VGS report "$OUT" --title "$TITLE" --publish "docs/results/$NAME"
rm -f "$CARRY" "$CARRY".part[0-9][0-9]
