"""somarm: self-organising-map reinforcement learning for continuous actions (Smith, 2002).

Importing the package is light: matplotlib and meshcat load only in the modules that
plot and view, and MuJoCo only in the tasks.
"""

import os as _os

# Nothing here renders (the viewer is meshcat), but dm_control looks for an OpenGL context on import
# and, on a machine with no display, warns that GLFW found no DISPLAY. With no display and no
# choice made by the user, say there is no OpenGL; a user's own MUJOCO_GL is left alone.
if "MUJOCO_GL" not in _os.environ and not (_os.environ.get("DISPLAY") or _os.environ.get("WAYLAND_DISPLAY")):
    _os.environ["MUJOCO_GL"] = "disable"

__version__ = "0.1.0"  # the one place the version is written: pyproject.toml reads it from here
__all__ = ["__version__", "SOMQ"]


def __getattr__(name: str):
    # ``from somarm import SOMQ`` (the SB3-style model) loads the run machinery only when asked for.
    if name == "SOMQ":
        from somarm.agent import SOMQ

        return SOMQ
    raise AttributeError(f"module 'somarm' has no attribute {name!r}")
