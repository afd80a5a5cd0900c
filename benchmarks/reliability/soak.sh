#!/usr/bin/env bash
# Do MuJoCo Warp's constraint and contact buffers hold over long default training runs?
# Usage: benchmarks/reliability/soak.sh OUT_DIR [SECONDS] [TASK ...]    (default: 300 s, Ant Humanoid)
# Writes OUT_DIR/soak.jsonl: per task, the run's peak constraint rows per world against njmax,
# peak contacts against naconmax, the fault totals (overflowed world-substeps must be 0) and the
# steady samples/s; and for the Ant, env-steps/s with Newton's old estimate (njmax 64) and the
# default, from one bench.py run.
set -uo pipefail
out=${1:?usage: benchmarks/reliability/soak.sh OUT_DIR [SECONDS] [TASK ...]}
seconds=${2:-300}
shift $(( $# > 1 ? 2 : 1 ))
tasks=${*:-Ant Humanoid}
mkdir -p "$out"
export PYTHONUNBUFFERED=1
for task in $tasks; do
  if [ "$task" = Ant ]; then
    python3 scripts/bench.py --robots ant --num-envs 4096 --steps 100 --repeats 5 --njmax 64 128 \
      --out "$out/bench_njmax.json" > "$out/bench_njmax.log" 2>&1
    python3 -c "import json; print(json.dumps({'bench_njmax': json.load(open('$out/bench_njmax.json'))['results']}))" >> "$out/soak.jsonl"
  fi
  python3 scripts/train.py --task "$task" --num-envs 4096 --time-limit "$seconds" --eval-gap 30 --no-plots \
    --run-dir "$out/$task" > "$out/$task.log" 2>&1
  python3 -c "import json; s = json.load(open('$out/$task/summary.json')); print(json.dumps({'task': '$task', **{k: s.get(k) for k in ('device', 'iterations', 'solver_load', 'faults', 'steady_samples_per_s_median', 'final', 'best_eval')}}))" >> "$out/soak.jsonl"
  tar -C "$out" --exclude=checkpoint.pt --exclude=tensorboard -czf "$out/run_$task.tar.gz" "$task" && rm -rf "${out:?}/$task"
done
tail -n 5 "$out/soak.jsonl"
