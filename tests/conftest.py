"""Test-wide setup: no OpenGL (dm_control otherwise looks for a display and warns); the viewer is meshcat."""

import os

os.environ.setdefault("MUJOCO_GL", "disable")
