"""Where an exemplar's windows lie: the geometry every method and the memory checks share."""

from __future__ import annotations


def window_grid(shape: tuple[int, ...], neighborhood: int) -> tuple[int, int]:
    """``(rows, columns)`` of the sites of an exemplar of *shape* whose ``neighborhood``-square
    window lies wholly inside it (none wraps round); their count is the product."""
    return max(0, shape[0] - neighborhood + 1), max(0, shape[1] - neighborhood + 1)
