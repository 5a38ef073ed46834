"""Which observed dimensions each input map sees: the ``input_groups`` setting read and checked.

``all`` is the paper's one map over every dimension; ``pairs``, ``triples`` and ``singles`` need no
knowledge of the task; ``chunks:K`` takes consecutive runs in index order; index lists (``0,1;2,3``)
are the user's own. The maps themselves are ``somarm.learners.groups``.
"""

from __future__ import annotations

import itertools

import numpy as np

__all__ = ["GROUPINGS", "check_groups", "dimensions_named", "parse_groups", "group_table"]


#: The named groupings of ``input_groups`` (besides index lists and ``chunks:K``).
GROUPINGS = ("all", "pairs", "triples", "singles")


def check_groups(text: str) -> str:
    """``input_groups`` checked for form, before the observation's size is known.

    Raises:
      ValueError: one line naming the forms allowed.
    """
    allowed = ("input_groups must be all, pairs, triples, singles, chunks:K (K >= 1) or index lists such as "
               f"'0,1;2,3' (0-based, ';' between maps), got {text!r}")
    if not isinstance(text, str):
        raise ValueError(allowed)
    text = text.strip()
    if text in GROUPINGS:
        return text
    if text.startswith("chunks:"):
        size = text.partition(":")[2]
        if not size.isdigit() or int(size) < 1:
            raise ValueError(allowed)
        return text
    try:
        groups = [[int(v) for v in part.split(",")] for part in text.split(";")]
    except ValueError:
        raise ValueError(allowed) from None
    if any(v < 0 for group in groups for v in group):
        raise ValueError(allowed)
    for group in groups:
        if len(set(group)) != len(group):
            raise ValueError(f"input_groups: dimension repeated within the map {','.join(map(str, group))} of {text!r}")
    return text


def dimensions_named(text: str) -> int:
    """The fewest observed dimensions ``input_groups`` can be read against: one past the largest index an
    index list names (0 for the named groupings, which fit any size)."""
    text = check_groups(text)
    if text in GROUPINGS or text.startswith("chunks:"):
        return 0
    return 1 + max(int(v) for part in text.split(";") for v in part.split(","))


def parse_groups(text: str, obs_dim: int) -> list[list[int]]:
    """The observed dimensions each map sees, ``[[0, 1], [2, 3], ...]``, for ``obs_dim`` dimensions.

    ``all``: one map over every dimension; ``pairs``: one per pair ``(i, j)``, i < j, ``triples`` one per
    triple (one map over all of them where there are fewer); ``singles``: one per dimension; ``chunks:K``: consecutive runs of K in index order
    (the last one shorter); index lists as written.

    Raises:
      ValueError: a form ``check_groups`` refuses, or an index outside ``0 .. obs_dim - 1`` (one line).
    """
    text = check_groups(text)
    dims = list(range(obs_dim))
    if text == "all":
        return [dims]
    if text in ("pairs", "triples"):
        return [list(p) for p in itertools.combinations(dims, 2 if text == "pairs" else 3)] or [dims]
    if text == "singles":
        return [[d] for d in dims]
    if text.startswith("chunks:"):
        size = int(text.partition(":")[2])
        return [dims[i:i + size] for i in range(0, obs_dim, size)]
    groups = [[int(v) for v in part.split(",")] for part in text.split(";")]
    bad = sorted({v for group in groups for v in group if v >= obs_dim})
    if bad:
        raise ValueError(f"input_groups={text!r} names dimension(s) {', '.join(map(str, bad))}, but the "
                         f"observation has {obs_dim} (0 .. {obs_dim - 1})")
    return groups


def group_table(groups: list[list[int]]) -> np.ndarray:
    """The groups as a ``(G, width)`` index table, -1 beyond each group's size (the kernels' form)."""
    width = max(len(group) for group in groups)
    table = np.full((len(groups), width), -1, dtype=np.int64)
    for g, group in enumerate(groups):
        table[g, :len(group)] = group
    return table
