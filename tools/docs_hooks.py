"""MkDocs hooks: pages whose text is generated at build time, so they cannot drift from the code.

- ``docs/cli.md``: every ``somarm`` subcommand's ``--help``, rendered from the parsers in
  ``somarm.cli`` (``bench NAME`` and ``view`` forward to their own parsers and are rendered
  through the same entry point, ``somarm.cli.main``);
- ``docs/changelog.md``: the top-level ``CHANGELOG.md``;
- ``docs/learners.md``: every preset's choices, from ``somarm/learners/preset_choices.md`` (the file the
  report quotes), each preset a level-4 heading.

Each page holds a pair of marker comments; the hook replaces them and what lies between (a note for
readers of the unbuilt page). A page without the markers is left alone.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# Document the checkout the site is built from, even where another copy of somarm is installed.
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))
CLI_MARKER = "somarm-cli-reference"
CHANGELOG_MARKER = "CHANGELOG.md"
CHOICES_MARKER = "preset_choices.md"
#: the width help is wrapped to, so the page does not depend on the terminal that built it
HELP_COLUMNS = 80

__all__ = ["commands", "help_text", "cli_reference", "preset_choices", "on_page_markdown"]


def _subparsers(parser: argparse.ArgumentParser) -> argparse._SubParsersAction:
    (action,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return action


def commands() -> list[list[str]]:
    """Every ``somarm`` command as its argv, in the parser's order: ``[]`` (somarm itself),
    ``["train"]``, ..., and ``["bench", NAME]`` for each benchmark ``bench``'s parser accepts."""
    from somarm import cli

    found: list[list[str]] = [[]]
    for name, sub in _subparsers(cli._parser()).choices.items():
        options = [a for a in sub._actions if a.option_strings and "-h" not in a.option_strings]
        named = [a for a in sub._actions if not a.option_strings and a.choices]
        if named and not options:  # only names what it forwards to (`bench NAME`): one entry per name
            found.extend([name, choice] for choice in named[0].choices)
        else:
            found.append([name])
    return found


def help_text(argv: list[str]) -> str:
    """What ``somarm ARGV --help`` prints, wrapped at ``HELP_COLUMNS``.

    Raises:
      RuntimeError: the command does not print its help and exit with status 0.
    """
    from somarm import cli

    out = io.StringIO()
    saved = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(HELP_COLUMNS)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()) as err:
            try:
                status = cli.main([*argv, "--help"])
            except SystemExit as exc:
                status = exc.code
    finally:
        if saved is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = saved
    if status not in (0, None) or not out.getvalue().strip():
        raise RuntimeError(f"`somarm {' '.join(argv)} --help` ended with {status!r}: {err.getvalue().strip()}")
    return out.getvalue().rstrip() + "\n"


def cli_reference() -> str:
    """The command reference: one section (a level-3 heading) per command, its ``--help`` verbatim."""
    from somarm import cli

    summaries = {a.dest: a.help for a in _subparsers(cli._parser())._choices_actions}
    # a forwarded command (`bench NAME`) describes itself in its own help
    sections = []
    for argv in commands():
        title = " ".join(["somarm", *argv])
        summary = f"{summaries[argv[0]][0].upper()}{summaries[argv[0]][1:]}.\n\n" if len(argv) == 1 else ""
        sections.append(f"### `{title}`\n\n{summary}```text\n{help_text(argv)}```\n")
    return "\n".join(sections)


def _fill(markdown: str, marker: str, text) -> str:
    """``markdown`` with ``<!-- marker -->...<!-- /marker -->`` replaced by ``text()``."""
    pattern = re.compile(rf"<!-- {re.escape(marker)} -->.*?<!-- /{re.escape(marker)} -->\n?", re.S)
    return pattern.sub(lambda _: text(), markdown) if pattern.search(markdown) else markdown


def preset_choices() -> str:
    """The presets' choices from their first section on, each preset a level-4 heading."""
    text = (ROOT / "somarm" / "learners" / "preset_choices.md").read_text()
    return re.sub(r"^## (\S+)$", r"#### `\1`", text[text.index("\n## ") + 1:], flags=re.M) + "\n"


def on_page_markdown(markdown: str, page, config, files) -> str:
    """MkDocs hook: fill the marked parts of ``cli.md``, ``changelog.md`` and ``learners.md``."""
    markdown = _fill(markdown, CLI_MARKER, cli_reference)
    markdown = _fill(markdown, CHOICES_MARKER, preset_choices)
    return _fill(markdown, CHANGELOG_MARKER, lambda: (ROOT / "CHANGELOG.md").read_text())
