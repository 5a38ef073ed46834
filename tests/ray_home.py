"""The home folder the Ray tests give Ray, one for the whole test process.

Ray writes its auth token under ``$HOME/.ray`` when a local cluster starts, and keeps the token it
read for the rest of the process: a second cluster started in the same process under another
``HOME`` writes a new token that the process no longer reads, and never comes up. So every test that
starts Ray sets ``HOME`` to this one folder (a temporary one, removed when the process ends), never
to the real home.
"""

from __future__ import annotations

import atexit
import functools
import shutil
import tempfile
from pathlib import Path


@functools.cache
def ray_home() -> Path:
    """The temporary home folder of this test process's Ray clusters."""
    home = Path(tempfile.mkdtemp(prefix="somarm-ray-home-"))
    atexit.register(shutil.rmtree, home, ignore_errors=True)
    return home
