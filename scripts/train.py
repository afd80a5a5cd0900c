"""`python scripts/train.py ARGS` in a source checkout is `warpgym train ARGS` (warpgym/cli/train.py)."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from warpgym.cli.train import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
