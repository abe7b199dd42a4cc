"""The orthogonal views every method constrains, and how they sit in a ``(Z, Y, X)`` block.

Axes are 0 = z, 1 = y, 2 = x. Front and right share y, the stacking axis of laminar
textures (Urs thesis, §6.3.1); top is the (z, x) plane.
"""

from __future__ import annotations

from typing import Any

#: View name -> (volume axis of the exemplar rows, volume axis of the exemplar columns).
VIEW_AXES: dict[str, tuple[int, int]] = {"front": (1, 2), "right": (1, 0), "top": (0, 2)}
#: View name -> the volume axis its slices are stacked along (front: z, right: x, top: y).
DEPTH_AXIS: dict[str, int] = {"front": 0, "right": 2, "top": 1}
#: Number of constrained views -> the views.
VIEW_SETS: dict[int, tuple[str, ...]] = {2: ("front", "right"), 3: ("front", "right", "top")}
#: The views, in the order every method lists them.
VIEW_ORDER: tuple[str, ...] = VIEW_SETS[3]


def view_set(views: Any) -> tuple[str, ...] | None:
    """The views a ``views`` value names, in :data:`VIEW_ORDER`; None if it names none.

    ``views`` is 2 (front and right), 3 (all three), or two or three distinct view names: a
    sequence, or one string joined by ``+`` or ``,`` (``"front+top"``)."""
    if isinstance(views, int) and not isinstance(views, bool):
        return VIEW_SETS.get(views)
    if isinstance(views, str):
        views = views.replace(",", "+").split("+")
    try:
        names = [str(v).strip() for v in views]
    except TypeError:
        return None
    if not 2 <= len(names) <= 3 or len(set(names)) != len(names) or not set(names) <= set(VIEW_ORDER):
        return None
    return tuple(v for v in VIEW_ORDER if v in names)


def views_value(names: tuple[str, ...]) -> int | str:
    """The ``views`` value that records *names*: 2 or 3 for front + right and all three (the
    values every record before view pairs holds), else the names joined by ``+``."""
    for count, views in VIEW_SETS.items():
        if tuple(names) == views:
            return count
    return "+".join(names)
