"""`python scripts/sim2sim.py ARGS` in a source checkout is `warpgym sim2sim ARGS` (warpgym/cli/sim2sim.py)."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from warpgym.cli.sim2sim import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
