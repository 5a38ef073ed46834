"""Reproduce every experiment of Smith (2002) and write REPORT.md (same as `somarm reproduce`).

python scripts/reproduce.py --out reproduce            # paper trial counts (about 15 minutes)
python scripts/reproduce.py --quick --only throw       # a smoke test of one experiment
"""

from __future__ import annotations

import sys

from somarm.cli import main

if __name__ == "__main__":
    sys.exit(main(["reproduce", *sys.argv[1:]]))
