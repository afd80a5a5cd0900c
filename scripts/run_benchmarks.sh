#!/usr/bin/env bash
# Produce every number in docs/benchmarks.md on one GPU machine. Usage: scripts/run_benchmarks.sh OUT_DIR
# Writes logs, JSON and run directories under OUT_DIR; takes about 20 minutes on an H100.
set -uo pipefail
out=${1:?usage: scripts/run_benchmarks.sh OUT_DIR}
mkdir -p "$out"
export PYTHONUNBUFFERED=1
graph_flag=""
step() { echo "== $(date +%T) $*" | tee -a "$out/progress.log"; }

step "GPU checks (CUDA graph update vs eager, env vs torch reference)"
if ! python3 -m pytest -q tests/test_cuda.py > "$out/test_cuda.log" 2>&1; then
  step "GPU checks FAILED: training below runs the PPO update without a CUDA graph"
  graph_flag="--no-cuda-graph"
fi

step "throughput: raw Newton vs Sim vs full env step"
python3 scripts/bench.py --robots ant humanoid --num-envs 1024 4096 16384 --steps 100 --repeats 5 \
  --out "$out/bench.json" > "$out/bench.log" 2>&1

for task in Ant Humanoid; do
  step "profile: $task 4096 envs, 40 iterations"
  python3 scripts/train.py --task "$task" --num-envs 4096 --max-iterations 40 --profile --no-eval --no-plots \
    $graph_flag --run-dir "$out/profile_$task" > "$out/profile_$task.log" 2>&1
done

for n in 4096 1024 16384 32768; do
  step "train: Ant $n envs, 90 s"
  python3 scripts/train.py --task Ant --num-envs "$n" --time-limit 90 --eval-gap 10 $graph_flag \
    --run-dir "$out/ant_$n" > "$out/ant_$n.log" 2>&1
done

step "train: Humanoid 4096 envs, 300 s"
python3 scripts/train.py --task Humanoid --num-envs 4096 --time-limit 300 --eval-gap 20 $graph_flag \
  --run-dir "$out/humanoid_4096" > "$out/humanoid_4096.log" 2>&1

python3 scripts/plot.py "$out/ant_1024" "$out/ant_4096" "$out/ant_16384" "$out/ant_32768" \
  --labels "1024 envs" "4096 envs" "16384 envs" "32768 envs" --title "Ant: PPO, one GPU" \
  --out "$out/fig_ant" > /dev/null 2>&1
step "done"
touch "$out/DONE"
