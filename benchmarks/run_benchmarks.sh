#!/usr/bin/env bash
# Produce the numbers in docs/benchmarks.md on one GPU machine. Usage: benchmarks/run_benchmarks.sh OUT_DIR
# Writes logs, JSON and run directories under OUT_DIR. All runs share one Warp kernel cache that starts
# empty, so the first run measures a fresh machine's cold start.
#   QUICK=1  the runs behind issue 5's targets (~10 min on an H100): cold start, libmathdx on/off,
#            GPU checks, Ant and Humanoid at 4096 envs
#   default  also the env-step table at 1024-16384 envs, profiles and the Ant scaling runs (~30 min)
#   COLD=0   skip the cold start and the --no-mathdx env step, and keep Warp's own kernel cache
#            (warm after any earlier run; benchmarks/speed/cold_start.py measures cold starts in full)
set -uo pipefail
out=${1:?usage: benchmarks/run_benchmarks.sh OUT_DIR}
mkdir -p "$out"
export PYTHONUNBUFFERED=1
quick=${QUICK:-0}
cold_run=${COLD:-1}
flags=""
step() { echo "== $(date +%T) $*" | tee -a "$out/progress.log"; }
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv > "$out/machine.txt" 2>&1
python3 -c "import torch, warp, newton, mujoco_warp; print(torch.__version__, warp.__version__, newton.__version__, mujoco_warp.__version__)" >> "$out/machine.txt" 2>&1
if [ "$cold_run" = 1 ]; then
cold=$(mktemp -d)
export WARP_CACHE_PATH=$cold

step "cold start: Ant 4096 envs, 75 s, empty kernel cache, --no-mathdx (module compile times logged)"
WARPGYM_WARP_INFO=1 python3 scripts/train.py --task Ant --num-envs 4096 --time-limit 75 --eval-gap 10 --no-mathdx \
  --run-dir "$out/ant_4096_cold" > "$out/ant_4096_cold.log" 2>&1

step "env step: Ant 4096 without, then with libmathdx (the second compiles its kernels first)"
python3 scripts/bench.py --robots ant --num-envs 4096 --steps 100 --repeats 5 --no-mathdx \
  --out "$out/bench_no_mathdx.json" > "$out/bench_no_mathdx.log" 2>&1
fi
if [ "$quick" = 1 ]; then sizes="4096"; else sizes="1024 4096 16384"; fi
python3 scripts/bench.py --robots ant humanoid --num-envs $sizes --steps 100 --repeats 5 \
  --out "$out/bench.json" > "$out/bench.log" 2>&1

step "GPU checks (captured rollout and update vs eager, env vs torch reference)"
python3 -m pytest -q tests/test_cuda.py > "$out/test_cuda.log" 2>&1
if grep -q "FAILED.*captured_rollout" "$out/test_cuda.log"; then
  step "captured rollout check FAILED: training below collects eagerly"; flags="$flags --no-rollout-graph"
fi
if grep -q "FAILED.*captured_update" "$out/test_cuda.log"; then
  step "captured update check FAILED: training below runs without CUDA graphs"; flags="$flags --no-cuda-graph"
fi

step "train: Ant 4096 envs, 90 s"
python3 scripts/train.py --task Ant --num-envs 4096 --time-limit 90 --eval-gap 10 $flags \
  --run-dir "$out/ant_4096" > "$out/ant_4096.log" 2>&1

if [ "$quick" = 1 ]; then hum_s=120; else hum_s=300; fi
step "train: Humanoid 4096 envs, $hum_s s"
python3 scripts/train.py --task Humanoid --num-envs 4096 --time-limit $hum_s --eval-gap 20 $flags \
  --run-dir "$out/humanoid_4096" > "$out/humanoid_4096.log" 2>&1

step "train: Ant 4096 envs, 90 s, rollouts launched step by step (what the rollout graph buys)"
python3 scripts/train.py --task Ant --num-envs 4096 --time-limit 90 --eval-gap 10 --no-rollout-graph $flags \
  --run-dir "$out/ant_4096_no_rollout_graph" > "$out/ant_4096_no_rollout_graph.log" 2>&1

if [ "$quick" != 1 ]; then
  for task in Ant Humanoid; do
    step "profile: $task 4096 envs, 40 iterations, rollouts launched step by step so each phase can be timed"
    python3 scripts/train.py --task "$task" --num-envs 4096 --max-iterations 40 --profile --no-eval --no-plots \
      --no-rollout-graph $flags --run-dir "$out/profile_$task" > "$out/profile_$task.log" 2>&1
  done
  for n in 1024 16384 32768; do
    step "train: Ant $n envs, 90 s"
    python3 scripts/train.py --task Ant --num-envs "$n" --time-limit 90 --eval-gap 10 $flags \
      --run-dir "$out/ant_$n" > "$out/ant_$n.log" 2>&1
  done
  python3 scripts/plot.py "$out/ant_1024" "$out/ant_4096" "$out/ant_16384" "$out/ant_32768" \
    --labels "1024 envs" "4096 envs" "16384 envs" "32768 envs" --title "Ant: PPO, one GPU" \
    --out "$out/fig_ant" > /dev/null 2>&1
fi
[ "$cold_run" = 1 ] && rm -rf "$cold"
step "done"
touch "$out/DONE"
