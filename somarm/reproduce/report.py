"""The report's building blocks (claims, sections) and its Markdown."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Claim", "Section", "merge_seeds", "render", "alt_text", "png_title", "claim_record", "TITLE",
           "BENCHMARKS_TITLE", "SUITE_TITLE"]


@dataclass
class Claim:
    """One claim of the paper, what was measured, and whether it holds under the stated test."""

    claim: str  #: the paper's claim, in a sentence (with its figure)
    measured: str  #: what was measured, with numbers
    holds: bool | None  #: True, False, or None where the measure does not decide
    test: str = ""  #: the stated test (bound, level) the verdict applies
    values: dict[str, float] = field(default_factory=dict)  #: the numbers the test reads, by name
    per_seed: list[tuple[int, Claim]] = field(default_factory=list)  #: (seed, claim) over seeds, if several

    def verdict(self) -> str:
        """"holds", "does not hold", "undecided", or over several seeds "holds in k of N seeds"."""
        if not self.per_seed:
            return _verdict(self.holds)
        held = sum(c.holds is True for _, c in self.per_seed)
        undecided = sum(c.holds is None for _, c in self.per_seed)
        return f"holds in {held} of {len(self.per_seed)} seeds" + (f" ({undecided} undecided)" if undecided else "")

    def spread(self) -> str:
        """Every seed's numbers and their range, one phrase per number (empty for one seed; no range
        where no seed has the number, e.g. a step count that is never reached)."""
        if not self.per_seed:
            return ""
        phrases = []
        for name in self.per_seed[0][1].values:
            numbers = np.array([c.values.get(name, np.nan) for _, c in self.per_seed], dtype=float)
            listed = ", ".join(_number(v) for v in numbers)
            if np.isnan(numbers).all():
                phrases.append(f"{name}: {listed}")
                continue
            phrases.append(f"{name}: {listed} (range {_number(np.nanmin(numbers))} to {_number(np.nanmax(numbers))}, "
                           f"sd {_number(np.nanstd(numbers))})")
        return "; ".join(phrases)


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
    #: Numbers reported at every seed without a test, by name (a count of failed trials, say); after
    #: ``merge_seeds`` each holds the list of every seed's number.
    counts: dict[str, float | list[float]] = field(default_factory=dict)


def _verdict(holds: bool | None) -> str:
    return {True: "holds", False: "does not hold", None: "undecided"}[holds]


def _number(x: float) -> str:
    if not np.isfinite(x):
        return "never" if np.isnan(x) else str(x)
    return f"{x:.3g}" if abs(x) < 1e-3 or abs(x) >= 1e4 else f"{x:.3f}".rstrip("0").rstrip(".")


def merge_seeds(sections: list[Section], seeds: list[int]) -> Section:
    """One section from the same experiment at several seeds: the first seed's figures, notes and
    choices; each claim with every seed's verdict and numbers. A merged claim holds when every
    seed's does, does not when none does and none is undecided, and is undecided otherwise.

    Raises:
      ValueError: the seeds' sections do not list the same claims.
    """
    first = sections[0]
    if any([c.claim for c in s.claims] != [c.claim for c in first.claims] for s in sections):
        raise ValueError(f"{first.name}: the seeds' reports list different claims")
    claims = []
    for i, claim in enumerate(first.claims):
        per_seed = [(seed, s.claims[i]) for seed, s in zip(seeds, sections, strict=True)]
        verdicts = [c.holds for _, c in per_seed]
        holds = True if all(v is True for v in verdicts) else (False if all(v is False for v in verdicts) else None)
        claims.append(Claim(claim.claim, f"seed {seeds[0]}: {claim.measured}", holds, claim.test,
                            dict(claim.values), per_seed))
    counts = {name: [float(s.counts.get(name, np.nan)) for s in sections] for name in first.counts}
    return Section(first.name, first.title, first.figures, claims, first.notes, first.choices, counts=counts)


def _count_lines(counts: dict[str, float | list[float]], seeds: list[int]) -> list[str]:
    """One line per count: its value, or every seed's values and their sum."""
    lines = []
    for name, value in counts.items():
        if isinstance(value, list):
            listed = ", ".join(_number(v) for v in value)
            lines.append(f"- {name}: {listed} at seeds {seeds[0]} to {seeds[-1]}, {_number(float(np.nansum(value)))} "
                         "in all")
        else:
            lines.append(f"- {name}: {_number(float(value))}")
    return lines


def claim_record(c: Claim) -> dict:
    """A claim as claims.json holds it (with ``per_seed`` and ``holds_in`` over several seeds)."""
    record = {"claim": c.claim, "measured": c.measured, "test": c.test, "holds": c.holds,
              "values": {k: _json_number(v) for k, v in c.values.items()}}
    if c.per_seed:
        record["holds_in"] = sum(x.holds is True for _, x in c.per_seed)
        record["seeds"] = len(c.per_seed)
        record["per_seed"] = [{"seed": seed, "holds": x.holds, "measured": x.measured,
                               "values": {k: _json_number(v) for k, v in x.values.items()}}
                              for seed, x in c.per_seed]
        record["spread"] = {name: {"min": _json_number(np.nanmin(v)), "max": _json_number(np.nanmax(v)),
                                   "sd": _json_number(np.nanstd(v))}
                            for name in c.values
                            for v in [np.array([x.values.get(name, np.nan) for _, x in c.per_seed], dtype=float)]}
    return record


def _json_number(x) -> float | None:
    """JSON has no NaN or infinity: those are written as null."""
    x = float(x)
    return x if np.isfinite(x) else None


#: The report's title, and the titles of a report of Gymnasium's benchmarks alone and of the suite's.
TITLE = "somarm: reproduction of Smith (2002)"
BENCHMARKS_TITLE = "somarm: SOM-Q on Gymnasium's benchmarks beside TD3 and SAC"
SUITE_TITLE = "somarm: SOM-Q on the DeepMind Control Suite beside TD3 and SAC"


def render(sections: list[Section], *, header: list[str], out_dir: Path, seeds: list[int] | None = None,
           title: str = TITLE) -> str:
    """The whole REPORT.md: the title, header, the claims table, then one part per experiment.

    ``out_dir`` is the folder REPORT.md is written to: every figure lies under it and is linked
    relative to it (``figures/x.png``), never by a path that names the folder. ``seeds``: the seeds a
    merged section's counts were measured at.
    """
    lines = [
        f"# {title}",
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
            measured = c.measured + (f" Over seeds: {c.spread()}." if c.spread() else "")
            cells = [section.name, c.claim, measured, c.test, f"**{c.verdict()}**"]
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
                f"- **{c.verdict()}**: {c.claim} Measured: {c.measured}"
                + (f" Over seeds: {c.spread()}." if c.spread() else "")
                + (f" Test: {c.test}" if c.test else "")
            )
        if section.notes:
            lines.append("")
            lines += [f"{note}" for note in section.notes]
        if section.counts:
            lines += ["", "Counted (no test):", ""]
            lines += _count_lines(section.counts, seeds or [0])
        if section.choices:
            lines += ["", "This project's choices (the paper gives no value):", ""]
            lines += [f"- {choice}" for choice in section.choices]
        for fig in section.figures:
            # Relative to REPORT.md's own folder, so that the links hold wherever the folder is read
            # from, and after a forced run's files move from the staging folder into ``out``.
            rel = Path(fig).absolute().relative_to(Path(out_dir).absolute())
            lines += ["", f"![{alt_text(Path(fig), section.title)}]({rel.as_posix()})"]
    return "\n".join(lines) + "\n"


def alt_text(figure: Path, section_title: str) -> str:
    """What a figure shows, for its image link: the title the PNG carries (``plots.save`` writes the
    figure's title into it), else the part's title with the figure's name; one line, no brackets."""
    title = png_title(figure)
    text = title if title else f"{section_title}, figure {figure.stem}"
    return " ".join(text.replace("[", "(").replace("]", ")").split())


def png_title(path: Path) -> str | None:
    """The ``Title`` text chunk of a PNG file (``tEXt`` or ``iTXt``, before the image data), or None
    where it has none or cannot be read."""
    import struct
    import zlib

    try:
        with open(path, "rb") as file:
            if file.read(8) != b"\x89PNG\r\n\x1a\n":
                return None
            while header := file.read(8):
                length, kind = struct.unpack(">I4s", header)
                if kind == b"IDAT" or length > 1 << 20:  # the text chunks a title would be in come first
                    return None
                data = file.read(length)
                file.read(4)  # the chunk's CRC
                keyword, _, rest = data.partition(b"\0")
                if keyword != b"Title":
                    continue
                if kind == b"tEXt":
                    return rest.decode("latin-1")
                if kind == b"iTXt":  # compression flag and method, language, translated keyword, text
                    compressed, text = rest[0], rest[2:].split(b"\0", 2)[-1]
                    return (zlib.decompress(text) if compressed else text).decode("utf-8")
    except (OSError, ValueError, IndexError, struct.error, zlib.error):
        return None
    return None
