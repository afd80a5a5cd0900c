"""`python scripts/eval.py ARGS` in a source checkout is `warpgym eval ARGS` (warpgym/cli/eval/)."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from warpgym.cli.eval import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
