"""The presets' choices: why each preset's values are what they are where its table is silent.

They are data, not code: ``preset_choices.md`` beside this module holds one ``## name`` section per
preset, one ``- `` bullet per choice. ``somarm.learners.presets`` reads them into ``Preset.choices``
and the reproduction report quotes them.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["CHOICES_FILE", "read", "parse"]

#: Each preset's choices where its table is silent, one ``## name`` section per preset.
CHOICES_FILE = Path(__file__).with_name("preset_choices.md")


def parse(text: str) -> dict[str, tuple[str, ...]]:
    """Each section's bullets of a choices file: ``## name`` opens a preset's section, ``- `` a
    choice, and a line indented by two spaces continues the choice above it (joined by one space).
    Text before the first section is not read.

    Raises:
      ValueError: a line that is none of these inside a section, or a section named twice.
    """
    sections: dict[str, list[str]] = {}
    items: list[str] | None = None
    for number, line in enumerate(text.splitlines(), 1):
        if line.startswith("## "):
            name = line[3:].strip()
            if name in sections:
                raise ValueError(f"preset choices line {number}: section {name!r} named twice")
            items = sections[name] = []
        elif items is None or not line.strip():
            continue
        elif line.startswith("- "):
            items.append(line[2:].strip())
        elif line.startswith("  ") and items:
            items[-1] += " " + line.strip()
        else:
            raise ValueError(f"preset choices line {number}: {line[:40]!r} is neither a choice ('- ') nor its "
                             "continuation (two spaces)")
    return {name: tuple(items) for name, items in sections.items()}


def read(names: list[str], path: Path = CHOICES_FILE) -> dict[str, tuple[str, ...]]:
    """The choices of every preset in ``names``, from ``path``.

    Raises:
      ValueError: a preset without a section in the file, or a section that names no preset.
    """
    sections = parse(path.read_text(encoding="utf-8"))
    missing, unknown = sorted(set(names) - set(sections)), sorted(set(sections) - set(names))
    if missing or unknown:
        raise ValueError(f"{path.name}: presets without a section {missing}, sections naming no preset {unknown}; "
                         f"allowed sections: {', '.join(names)}")
    return {name: sections[name] for name in names}
