"""The tree part of a factorisation plan (:func:`flexmbs.linalg.ordering.peel_tree`, read by
:class:`flexmbs.linalg.bordered.BorderedBandedLU`): plain data, so that the planner and the
factorisation share it without importing each other."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class TreePlan(NamedTuple):
    """Rigid bodies eliminated in tree order before the bordered band
    (:func:`~flexmbs.linalg.ordering.peel_tree`):
    supernode k holds ``unknowns[ptr[k]:ptr[k + 1]]`` (a body's coordinates, its own rows and
    the rows of the joints to its parent), eliminated after its children; it couples
    only to ``parent_set[set_ptr[k]:set_ptr[k + 1]]``, coordinates of its parent body (a later
    supernode, or a body of the rest), none for a root."""

    ptr: np.ndarray          # int64 (S + 1,)
    unknowns: np.ndarray     # int64: global unknowns, supernode by supernode
    set_ptr: np.ndarray      # int64 (S + 1,)
    parent_set: np.ndarray   # int64: global unknowns

    @property
    def size(self) -> int:
        """The number of unknowns eliminated in tree order."""
        return int(self.unknowns.size)

    def cliques(self, rest: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The (row, column) pairs that the elimination adds among the unknowns ``rest`` (a
        bool mask): the parent sets that lie there, each a dense block."""
        rows, cols = [], []
        for k in range(self.ptr.size - 1):
            p = self.parent_set[self.set_ptr[k]:self.set_ptr[k + 1]]
            if p.size and rest[p[0]]:
                rows.append(np.repeat(p, p.size))
                cols.append(np.tile(p, p.size))
        if not rows:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        return np.concatenate(rows), np.concatenate(cols)
