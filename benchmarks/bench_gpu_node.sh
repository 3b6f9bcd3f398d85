#!/usr/bin/env bash
# What one GPU node buys the `paper` protocol (issue 18, item 3): measured on a lent machine with
# one GPU and 16 cores (the project's device tool; never needed by the tests), where
# benchmarks/bench_train.py can only assume a learner on one CPU core.
#
#   bash benchmarks/bench_gpu_node.sh OUTDIR
#
# Needs python3 with a CUDA build of torch; vgs's other dependencies are found on the path or
# installed from wheels in .whl/ (mujoco, mujoco-core, gymnasium, farama-notifications, glfw for
# the machine's Python). Prints and writes into OUTDIR:
#   1. network_cuda.json: a greedy decision (R = 16, 224 px) and a training step of DenseNet-121
#      and the light backbone on the GPU, float32 and bfloat16 (bench_network.py);
#   2. the simulation's throughput with 1 and 16 worker processes on centre-grasp test
#      episodes of the paper cell (bench_eval.throughput), and the scaling efficiency;
#   3. train_densenet.csv: a real `vgs train --profile paper` (DenseNet-121) on this node with 16
#      parallel episodes, the network on the GPU: $EPISODES episodes (default 64), 16 random
#      then greedy; the sum of
#      wall_s over the greedy ones is the node's wall time per training episode.
# Figures only; the host is printed with them.
set -uo pipefail
OUT=${1:?usage: bash benchmarks/bench_gpu_node.sh OUTDIR}
cd "$(dirname "$0")/.."
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1
if compgen -G ".whl/*.whl" > /dev/null; then
    python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
        --target /tmp/site .whl/*.whl || exit 1
    export PYTHONPATH=/tmp/site:$PWD/src
else
    export PYTHONPATH=$PWD/src
fi
nvidia-smi -L; nproc; lscpu | grep -m1 "Model name"
python3 -c "import torch, mujoco; print('torch', torch.__version__, 'mujoco', mujoco.__version__,
'cuda', torch.cuda.is_available())" || exit 1

PARTS=${PARTS:-123}  # which parts to run (PARTS=23 skips the network)
EPISODES=${EPISODES:-64}  # training episodes of part 3 (16 of them random)
if [[ $PARTS == *1* ]]; then
echo "== 1. the network on the GPU"
timeout 120 python3 benchmarks/bench_network.py --device cuda --backbones densenet121 light \
    --rotate input --precision float32 bfloat16 --repeats 5 --warmup 2 \
    --json "$OUT/network_cuda.json"
fi

if [[ $PARTS == *2* ]]; then
echo "== 2. the simulation on 1 and 16 worker processes"
cat > /tmp/node_sim.py <<'EOF'
import sys
sys.path.insert(0, "benchmarks")
from bench_eval import throughput

if __name__ == "__main__":  # the pool's workers are spawned and import this file
    w1, s1 = throughput(4, 1, "local")
    w16, s16 = throughput(64, 16, "local")
    print(f"1 worker: {4 / w1:.3f} episodes/s ({s1 / 4:.2f} s per episode); "
          f"16 workers: {64 / w16:.3f} episodes/s ({s16 / 64:.2f} s per episode); "
          f"scaling efficiency {(64 / w16) / (16 * 4 / w1):.2f} (start-up of the pool included)")
EOF
timeout 90 python3 /tmp/node_sim.py
fi

[[ $PARTS == *3* ]] || exit 0
echo "== 3. vgs train --profile paper (DenseNet-121) with 16 parallel episodes, network on the GPU"
rm -rf /tmp/train_gpu
start=$(date +%s.%N)
timeout 300 python3 -m vgs.cli train --mode vgs --profile paper --device cuda \
    --set train.episodes=$EPISODES --set agent.random_episodes=16 --set train.checkpoint_every=16 \
    --set train.parallel_episodes=16 --out /tmp/train_gpu --no-progress
end=$(date +%s.%N)
cp /tmp/train_gpu/episodes.csv "$OUT/train_densenet.csv" 2>/dev/null
python3 - "$OUT/train_densenet.csv" "$start" "$end" <<'EOF'
import sys
import pandas as pd
t = pd.read_csv(sys.argv[1])
explored = t.explored.astype(bool)
print(f"{len(t)} episodes in {float(sys.argv[3]) - float(sys.argv[2]):.0f} s of wall time "
      f"(start-up included); sum of wall_s: random {t.wall_s[explored].sum():.1f} s over "
      f"{explored.sum()}, greedy {t.wall_s[~explored].sum():.1f} s over {(~explored).sum()} "
      f"({t.wall_s[~explored].mean():.2f} s per greedy episode); greedy grasps held "
      f"{t.grasp_success[~explored].mean():.2f}, assembled {t.assembly_success[~explored].mean():.2f}")
EOF
