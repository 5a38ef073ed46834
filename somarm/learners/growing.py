"""Input maps that grow, a row or a column at a time, where their units' quantisation error is largest.

A growing grid (Fritzke 1995, "Growing grid"): a map starts with 2 x 2 units (2 on a line) and every
``grow_every`` learning steps each map gains a row or a column, until it has ``input_shape`` units, so
the units' count is bounded from the start. Each unit adds up the squared distance of the
observations it wins; at a growth the unit e with the largest sum and, of its grid neighbours, the
one f whose weights lie farthest from e's get a new row (f above or below e) or column (f beside
it) between them, falling back to the other direction when the map is full along that one. The new
units' weights and Q rows are the means of the two units they sit between, and every sum restarts
at 0. The map keeps its units in the first ``rows * cols`` places, row-major for its current shape;
grid distances still come from the full map's ``grid_offsets``.
"""

from __future__ import annotations

import numba

__all__ = ["START", "grow"]

#: The units along each grid dimension a growing map starts with.
START = 2


@numba.njit(cache=True, nogil=True)
def _distance(weights, a, b):
    total = 0.0
    for i in range(weights.shape[1]):
        diff = weights[a, i] - weights[b, i]
        total += diff * diff
    return total


@numba.njit(cache=True, nogil=True)
def grow(weights, q, errors, shape, max_rows, max_cols):
    """One growth of one map in place: ``weights (n_units, width)``, ``q (n_units, n_actions)`` and
    ``errors (n_units,)`` of its places, ``shape`` its current ``[rows, cols]``; nothing where it is full."""
    rows, cols = shape[0], shape[1]
    if rows >= max_rows and cols >= max_cols:
        return
    count = rows * cols
    e = 0
    for m in range(1, count):
        if errors[m] > errors[e]:
            e = m
    r, c = e // cols, e - (e // cols) * cols
    best, vertical, after = -1.0, True, True
    for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        rr, cc = r + dr, c + dc
        if 0 <= rr < rows and 0 <= cc < cols:
            d = _distance(weights, e, rr * cols + cc)
            if d > best:
                best, vertical, after = d, dr != 0, dr + dc > 0
    if vertical and rows >= max_rows:
        vertical, after = False, c + 1 < cols
    elif not vertical and cols >= max_cols:
        vertical, after = True, r + 1 < rows
    old_w = weights[:count].copy()
    old_q = q[:count].copy()
    if vertical:  # a new row between row ``at - 1`` and row ``at``
        at = r + 1 if after else r
        new_rows, new_cols = rows + 1, cols
    else:
        at = c + 1 if after else c
        new_rows, new_cols = rows, cols + 1
    for nr in range(new_rows):
        for nc in range(new_cols):
            place = nr * new_cols + nc
            if vertical:
                source, inserted = (nr if nr < at else nr - 1), nr == at
                a, b = (at - 1) * cols + nc, at * cols + nc
                old = source * cols + nc
            else:
                source, inserted = (nc if nc < at else nc - 1), nc == at
                a, b = nr * cols + at - 1, nr * cols + at
                old = nr * cols + source
            if inserted:
                for i in range(weights.shape[1]):
                    weights[place, i] = 0.5 * (old_w[a, i] + old_w[b, i])
                for n in range(q.shape[1]):
                    q[place, n] = 0.5 * (old_q[a, n] + old_q[b, n])
            else:
                weights[place] = old_w[old]
                q[place] = old_q[old]
    for m in range(errors.shape[0]):
        errors[m] = 0.0
    shape[0], shape[1] = new_rows, new_cols
