"""`python scripts/bench.py ARGS` in a source checkout is `warpgym bench ARGS` (warpgym/cli/bench/)."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from warpgym.cli.bench import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
