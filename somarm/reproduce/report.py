"""The report's building blocks (claims, sections) and its Markdown."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Claim", "Section", "render"]


@dataclass
class Claim:
    """One claim of the paper, what was measured, and whether it holds under the stated test."""

    claim: str  #: the paper's claim, in a sentence (with its figure)
    measured: str  #: what was measured, with numbers
    holds: bool | None  #: True, False, or None where the measure does not decide
    test: str = ""  #: the stated test (bound, level) the verdict applies


@dataclass
class Section:
    """One experiment: figures, claims, notes, and the project's own choices it used."""

    name: str
    title: str
    figures: list[Path] = field(default_factory=list)
    claims: list[Claim] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    choices: list[str] = field(default_factory=list)
    wall_time_s: float = 0.0


def _verdict(holds: bool | None) -> str:
    return {True: "holds", False: "does not hold", None: "undecided"}[holds]


def render(sections: list[Section], *, header: list[str], out_dir: Path) -> str:
    """The whole REPORT.md: header, the claims table, then one part per experiment."""
    lines = [
        "# somarm: reproduction of Smith (2002)",
        "",
        *header,
        "",
        "## Claims",
        "",
        "| experiment | claim | measured | test | verdict |",
        "|---|---|---|---|---|",
    ]
    for section in sections:
        for c in section.claims:
            cells = [section.name, c.claim, c.measured, c.test, f"**{_verdict(c.holds)}**"]
            lines.append("| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |")
    for section in sections:
        lines += [
            "",
            f"## {section.title}",
            "",
            f"Experiment `{section.name}`, {section.wall_time_s:.1f} s.",
            "",
        ]
        for c in section.claims:
            lines.append(
                f"- **{_verdict(c.holds)}**: {c.claim} Measured: {c.measured}"
                + (f" Test: {c.test}" if c.test else "")
            )
        if section.notes:
            lines.append("")
            lines += [f"{note}" for note in section.notes]
        if section.choices:
            lines += ["", "This project's choices (the paper gives no value):", ""]
            lines += [f"- {choice}" for choice in section.choices]
        for fig in section.figures:
            rel = Path(fig).relative_to(out_dir) if Path(fig).is_absolute() else Path(fig)
            lines += ["", f"![{rel.stem}]({rel.as_posix()})"]
    return "\n".join(lines) + "\n"
