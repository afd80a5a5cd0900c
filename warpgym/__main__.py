"""``python -m warpgym COMMAND ...``: the same as the ``warpgym`` command."""

import sys

from warpgym.cli import main

sys.exit(main())
