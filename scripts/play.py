"""`python scripts/play.py ARGS` in a source checkout is `warpgym play ARGS` (warpgym/cli/play.py)."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from warpgym.cli.play import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
