"""The harnesses behind docs/benchmarks.md, grouped by what they measure: speed/, learning/, multi_gpu/,
physics/, reliability/. Run each from the repository root as a module, e.g.
``python -m benchmarks.speed.suite_speed --help``; ``harness`` and ``targets`` are what they share."""
