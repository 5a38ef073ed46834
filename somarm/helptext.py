"""Help text for a terminal: the docstrings' markup (``literal`` and `code`) printed without its backticks.

The command line's descriptions and option help come from docstrings and dataclass fields written
for the documentation site, where backticks mark code. ``somarm COMMAND --help`` shows them as plain
text: ``PlainHelpFormatter`` drops the backticks (``somarm view TASK`` reads as somarm view TASK),
and ``RawPlainHelpFormatter`` does the same and keeps the description's own line breaks.
"""

from __future__ import annotations

import argparse
import re

__all__ = ["plain", "PlainHelpFormatter", "RawPlainHelpFormatter"]

_QUOTED = re.compile(r"``(.+?)``|`([^`\n]+?)`")


def plain(text: str) -> str:
    """``text`` without markup: ````x```` and ```x``` become ``x``; other text is kept."""
    return _QUOTED.sub(lambda m: m.group(1) or m.group(2), text)


class PlainHelpFormatter(argparse.HelpFormatter):
    """argparse's formatter, with descriptions, epilogs and option help as plain text (``plain``)."""

    def _format_text(self, text: str) -> str:
        return super()._format_text(plain(text))

    def _expand_help(self, action: argparse.Action) -> str:
        return plain(super()._expand_help(action))


class RawPlainHelpFormatter(argparse.RawDescriptionHelpFormatter):
    """``argparse.RawDescriptionHelpFormatter`` (line breaks kept), with plain text as ``PlainHelpFormatter``."""

    def _format_text(self, text: str) -> str:
        return super()._format_text(plain(text))

    def _expand_help(self, action: argparse.Action) -> str:
        return plain(super()._expand_help(action))
