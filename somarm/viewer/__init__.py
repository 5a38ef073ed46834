"""The meshcat browser viewer: MuJoCo scenes streamed to a local page, or exported as HTML.

Nothing here is imported by ``somarm`` or by headless training: meshcat loads only when a
viewer is asked for (``somarm view``, ``somarm train --view``, ``somarm.viewer.live``).
"""

__all__: list[str] = []
