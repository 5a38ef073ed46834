"""The viewer's pages: meshcat's viewer with somarm's text overlay, live from a server or self-contained.

The live page is what our server (``_bridge.py``) serves at ``/static/``: meshcat's viewer script,
the overlay (``page.js``), a websocket to the server. The offline page is meshcat's static export
(the page its server builds for ``get_scene``), built here from recorded commands so that no
server has to run: both scripts inlined, then every command as msgpack bytes handed to
``viewer.handle_command_bytearray``. Either page's title is the task.
"""

from __future__ import annotations

import base64
import html
import json
import os
from pathlib import Path

import meshcat
import umsgpack

from somarm.io import atomic_write_text

__all__ = ["FAVICON_SVG", "live_page", "static_html", "write_html"]

#: The tab's icon: a two-link arm reaching for a goal ring (served as /favicon.ico and inlined offline).
FAVICON_SVG = (
    '<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 32 32">'
    '<rect width="32" height="32" rx="6" fill="#26324a"/>'
    '<circle cx="24" cy="9" r="5" fill="none" stroke="#3fbf5f" stroke-width="2.5"/>'
    '<path d="M8 27 L13 14 L23 10" fill="none" stroke="#e0a060" stroke-width="3" stroke-linecap="round"/>'
    '<circle cx="8" cy="27" r="3" fill="#c8ccd4"/><circle cx="23" cy="10" r="2.2" fill="#ffd21f"/></svg>'
)

_STYLE = """
body {margin: 0; font-family: system-ui, -apple-system, "Segoe UI", Roboto, sans-serif;}
#meshcat-pane {width: 100vw; height: 100vh; overflow: hidden;}
.somarm-panel {position: fixed; left: 10px; top: 10px; max-width: min(430px, 60vw); padding: 8px 11px;
  background: rgba(255, 255, 255, 0.88); color: #1d2330; border-radius: 6px; font-size: 13px;
  line-height: 1.35; box-shadow: 0 1px 4px rgba(0, 0, 0, 0.18); pointer-events: none; z-index: 10;}
.somarm-status {font-weight: 600; color: #a04000; margin-bottom: 2px;}
.somarm-title {font-weight: 600; font-size: 14px;}
.somarm-lines {color: #4a5263;}
.somarm-caption {margin-top: 3px; font-variant-numeric: tabular-nums;}
.somarm-key {margin-top: 5px; display: flex; flex-wrap: wrap; gap: 2px 10px; font-size: 12px; color: #4a5263;}
.somarm-key-item {white-space: nowrap;}
.somarm-swatch {display: inline-block; width: 10px; height: 10px; border-radius: 2px; margin-right: 4px;
  vertical-align: -1px; border: 1px solid rgba(0, 0, 0, 0.25);}
.somarm-label {position: fixed; transform: translate(-50%, 4px); font-size: 11px; color: #2a3140;
  text-shadow: 0 0 3px #fff, 0 0 3px #fff; pointer-events: none; white-space: nowrap; z-index: 5;}
"""

_PAGE = """<!DOCTYPE html>
<html>
<head><meta charset="utf-8"><title>{title}</title>
<link rel="icon" href="{icon}">
<style>{style}</style>
</head>
<body>
<div id="meshcat-pane"></div>
{viewer_script}
<script>{overlay_js}</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
SomarmOverlay.install(viewer);
{start}
</script>
</body>
</html>
"""

_REPLAY = """var commands = {commands};
for (const encoded of commands) {{
  const bytes = Uint8Array.from(atob(encoded), c => c.charCodeAt(0));
  viewer.handle_command_bytearray(bytes);
}}"""

_CONNECT = """try {
  viewer.connect();
  SomarmOverlay.watch(viewer.connection);
} catch (e) {
  console.info("Not connected to the viewer's server: ", e);
}"""


def _viewer_js() -> str:
    path = Path(meshcat.viewer_assets_path()) / "dist" / "main.min.js"
    # "</script" inside the inlined script would end the tag early; "<\\/script" means the same in JS.
    return path.read_text(encoding="utf-8").replace("</script", "<\\/script")


def _overlay_js() -> str:
    return (Path(__file__).with_name("page.js")).read_text(encoding="utf-8").replace("</script", "<\\/script")


def _icon_uri() -> str:
    return "data:image/svg+xml;base64," + base64.b64encode(FAVICON_SVG.encode()).decode("ascii")


def live_page(title: str) -> str:
    """The page our server serves: meshcat's script from the server, the overlay, a websocket."""
    return _PAGE.format(title=html.escape(title), icon="/favicon.ico", style=_STYLE,
                        viewer_script='<script src="main.min.js"></script>', overlay_js=_overlay_js(),
                        start=_CONNECT)


def static_html(commands: list[dict], *, title: str = "somarm") -> str:
    """The offline page as a string.

    Args:
      commands: lowered meshcat (and ``somarm_text``) commands in replay order (e.g. ``Recorder().commands()``).
      title: the page title.
    """
    encoded = [base64.b64encode(umsgpack.packb(command)).decode("ascii") for command in commands]
    return _PAGE.format(title=html.escape(title), icon=_icon_uri(), style=_STYLE,
                        viewer_script=f"<script>{_viewer_js()}</script>", overlay_js=_overlay_js(),
                        start=_REPLAY.format(commands=json.dumps(encoded)))


def write_html(path: str | os.PathLike, commands: list[dict], *, title: str = "somarm") -> Path:
    """Write ``static_html(commands)`` to ``path`` atomically.

    Raises:
      ValueError: the folder of ``path`` does not exist.
    """
    return atomic_write_text(path, static_html(commands, title=title))
