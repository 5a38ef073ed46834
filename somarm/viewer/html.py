"""A self-contained HTML file of a scene and its animation: opens with no server, can be shared.

This is meshcat's static export (the page its server builds for ``get_scene``), built here
from recorded commands so that no server has to run: meshcat's viewer script inlined,
followed by every command as msgpack bytes handed to ``viewer.handle_command_bytearray``.
"""

from __future__ import annotations

import base64
import json
import os
from pathlib import Path

import meshcat
import umsgpack

from somarm.io import atomic_write_text

__all__ = ["static_html", "write_html"]

_PAGE = """<!DOCTYPE html>
<html>
<head><meta charset="utf-8"><title>{title}</title>
<style>body {{margin: 0;}} #meshcat-pane {{width: 100vw; height: 100vh; overflow: hidden;}}</style>
</head>
<body>
<div id="meshcat-pane"></div>
<script>{viewer_js}</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var commands = {commands};
for (const encoded of commands) {{
  const bytes = Uint8Array.from(atob(encoded), c => c.charCodeAt(0));
  viewer.handle_command_bytearray(bytes);
}}
</script>
</body>
</html>
"""


def _viewer_js() -> str:
    path = Path(meshcat.viewer_assets_path()) / "dist" / "main.min.js"
    # "</script" inside the inlined script would end the tag early; "<\\/script" means the same in JS.
    return path.read_text(encoding="utf-8").replace("</script", "<\\/script")


def static_html(commands: list[dict], *, title: str = "somarm") -> str:
    """The page as a string.

    Args:
      commands: lowered meshcat commands in replay order (e.g. ``Recorder().commands()``).
      title: the page title.
    """
    encoded = [base64.b64encode(umsgpack.packb(command)).decode("ascii") for command in commands]
    return _PAGE.format(title=title, viewer_js=_viewer_js(), commands=json.dumps(encoded))


def write_html(path: str | os.PathLike, commands: list[dict], *, title: str = "somarm") -> Path:
    """Write ``static_html(commands)`` to ``path`` atomically.

    Raises:
      ValueError: the folder of ``path`` does not exist.
    """
    return atomic_write_text(path, static_html(commands, title=title))
