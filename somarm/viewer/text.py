"""What the page says: the text overlay's commands (task, numbers, a colour key, labels in the scene).

The viewer's pages (``html.py``) show a panel over the 3D view. Python sets its text with one
command of our own, ``somarm_text``, sent like any meshcat command (live, or recorded into an
offline page); the page's script (``page.js``) takes it and hands every other command to meshcat.
A command changes only the fields it gives:

- ``title``: the first line (the task and what is shown);
- ``lines``: lines below it that stay (learner, trial, run step, ...);
- ``timeline``: lines that follow the animation: ``{"fps": f, "frames": [[k, lines], ...]}``
  shows ``lines`` from animation frame ``k`` on (the frame is read from the playing clip, so the
  text stays with the scene when the clip loops or is scrubbed);
- ``caption``: lines shown now (live pages, goal after goal);
- ``key``: the colour key, ``[[css colour, meaning], ...]``;
- ``labels``: text pinned to scene nodes, ``[[meshcat path, text], ...]`` (distance ticks, a scale);
- ``status``: a line in bold at the top (``training``, ``training finished ...``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["TEXT_COMMAND", "Timeline", "css", "number", "text_command"]

TEXT_COMMAND = "somarm_text"
_FIELDS = ("title", "lines", "timeline", "caption", "key", "labels", "status")


def css(color: int) -> str:
    """``#rrggbb`` of a ``0xRRGGBB`` colour."""
    return f"#{int(color) & 0xFFFFFF:06x}"


def number(value: float, digits: int = 3) -> str:
    """A short, fixed form for the overlay: ``0.0123``, ``-1.25``, ``nan``."""
    value = float(value)
    if not np.isfinite(value):
        return str(value)
    if value != 0 and abs(value) < 10 ** -digits:
        return f"{value:.1e}"
    return f"{value:.{digits}f}" if abs(value) < 100 else f"{value:.1f}"


def text_command(**fields) -> dict:
    """A ``somarm_text`` command setting the given fields (see the module docstring).

    Raises:
      ValueError: an unknown field (the fields are listed).
    """
    unknown = sorted(set(fields) - set(_FIELDS))
    if unknown:
        raise ValueError(f"unknown overlay field(s) {', '.join(unknown)}; fields: {', '.join(_FIELDS)}")
    command = {"type": TEXT_COMMAND, "path": ""}
    for name, value in fields.items():
        if name in ("lines", "caption") and value is not None:
            value = [str(line) for line in value]
        elif name in ("key", "labels") and value is not None:
            value = [[str(a), str(b)] for a, b in value]
        command[name] = value
    return command


class Timeline:
    """Lines that change with an animation's frames: ``add(n_frames, lines)`` in playing order."""

    def __init__(self, fps: float) -> None:
        self.fps = float(fps)
        self.frames: list[list] = []
        self.n_frames = 0

    def add(self, n_frames: int, lines: list[str]) -> None:
        """Show ``lines`` for the next ``n_frames`` frames."""
        lines = [str(line) for line in lines]
        if not self.frames or self.frames[-1][1] != lines:
            self.frames.append([self.n_frames, lines])
        self.n_frames += int(n_frames)

    def command(self) -> dict:
        """The ``somarm_text`` command holding this timeline."""
        return text_command(timeline={"fps": self.fps, "frames": self.frames})

    def at(self, frame: int) -> list[str]:
        """The lines shown at animation frame ``frame`` (what the page does, for tests)."""
        shown: list[str] = []
        for start, lines in self.frames:
            if start > frame:
                break
            shown = lines
        return shown
