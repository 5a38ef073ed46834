"""``python -m somarm``: the ``somarm`` command, for an environment whose scripts are not on the PATH."""

import sys

from somarm.cli import main

sys.exit(main())
