"""`python scripts/train_with.py ARGS` in a source checkout is `warpgym train-with ARGS` (warpgym/cli/train_with.py)."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from warpgym.cli.train_with import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
