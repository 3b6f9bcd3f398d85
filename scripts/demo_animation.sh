#!/usr/bin/env bash
# The README's animations and their captions' numbers, made on the current cell (issue 42):
#   docs/figures/demo.gif         the centre heuristic, seed 3 (the README's `vgs demo --seed 3`)
#   docs/figures/demo_policy.gif  a published trained network (paper-light, position action,
#                                 seed 0) on the same seed, its Q heat map beside the episode
# and docs/figures/demo.png, the demo figure. Prints one caption line per animation: write
# those numbers into the README's captions. About 1 min on a 2-core host; rendering needs
# OpenGL (EGL without a display).
# Usage: scripts/demo_animation.sh [POLICY]   (default: docs/results/paper_light_s0/vgs)
set -euo pipefail
cd "$(dirname "$0")/.."
VGS=${VGS:-.venv/bin/vgs}
POLICY=${1:-docs/results/paper_light_s0/vgs}
VIDEO=(--video-size 400x300 --video-speed 6 --video-fps 10)
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
CAPTION=$(cat <<'PY'
import json, sys
r = json.load(sys.stdin)
done = (f"assembled in {r['assembly_time_s']:.2f} s simulated" if r["assembly_success"]
        else f"not assembled ({r['failure_reason']})")
print(f"{sys.argv[1]}: seed {r['seed']}, {done}, {r['adjustments']} adjustments, grasp "
      f"offset {r['grasp_offset_mm']:+.1f} mm")
PY
)
caption() { .venv/bin/python -c "$CAPTION" "$1"; }  # the episode record (--json) as one line
$VGS demo --seed 3 --out "$TMP/centre" --video docs/figures/demo.gif "${VIDEO[@]}" --force --json \
    | caption "docs/figures/demo.gif (centre heuristic)"
cp "$TMP/centre/demo.png" docs/figures/demo.png
$VGS demo --seed 3 --policy "$POLICY" --out "$TMP/policy" --video docs/figures/demo_policy.gif \
    "${VIDEO[@]}" --force --json | caption "docs/figures/demo_policy.gif ($POLICY)"
