#!/usr/bin/env bash
# What a new user waits for: the README's first command on a fresh clone, timed in its two parts
# (issue 54, item 3). Clones REPO (default: this checkout's repository, at its HEAD) into a
# temporary folder, then times
#   1. the set-up, `python3 -m venv .venv && .venv/bin/pip install -e '.[dev]'`;
#   2. the main job, `.venv/bin/vgs reproduce --profile quick --out runs/quick`, with its
#      stages' wall time from reproduce.json's stage_wall_s;
# and prints both with the revision and the host. Figures only (the host's load counts: run it
# on an otherwise idle machine and say so with the figures). The clone is removed afterwards
# unless KEEP=1.
#
#   bash benchmarks/bench_fresh_clone.sh [REPO]
set -euo pipefail
REPO=${1:-$(git -C "$(dirname "$0")/.." rev-parse --show-toplevel)}
WORK=$(mktemp -d)
[ "${KEEP:-0}" = 1 ] || trap 'rm -rf "$WORK"' EXIT
git clone -q "$REPO" "$WORK/vgs"
cd "$WORK/vgs"
echo "revision $(git rev-parse --short HEAD); host $(python3 -c 'import platform; print(platform.processor() or platform.machine())') $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores"
t0=$(date +%s.%N)
python3 -m venv .venv && .venv/bin/pip install -q -e '.[dev]'
t1=$(date +%s.%N)
.venv/bin/vgs reproduce --profile quick --out runs/quick --no-progress > reproduce.log 2>&1 \
    || { tail -n 20 reproduce.log; exit 1; }
t2=$(date +%s.%N)
python3 - "$t0" "$t1" "$t2" <<'PY'
import json, sys
t0, t1, t2 = (float(x) for x in sys.argv[1:4])
stages = json.load(open("runs/quick/reproduce.json"))["stage_wall_s"]
print(f"set-up (venv, pip install -e '.[dev]'): {t1 - t0:.0f} s")
print(f"vgs reproduce --profile quick: {(t2 - t1) / 60:.1f} min ("
      + ", ".join(f"{k} {v / 60:.1f} min" for k, v in stages.items()) + ")")
print(f"the README's first command in all: {(t2 - t0) / 60:.1f} min")
PY
