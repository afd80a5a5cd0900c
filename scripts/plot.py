"""`python scripts/plot.py ARGS` in a source checkout is `warpgym plot ARGS` (warpgym/cli/plot.py)."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from warpgym.cli.plot import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
