"""The orthogonal views every method constrains, and how they sit in a ``(Z, Y, X)`` block.

Axes are 0 = z, 1 = y, 2 = x. Front and right share y, the stacking axis of laminar
textures (Urs thesis, §6.3.1); top is the (z, x) plane.
"""

#: View name -> (volume axis of the exemplar rows, volume axis of the exemplar columns).
VIEW_AXES: dict[str, tuple[int, int]] = {"front": (1, 2), "right": (1, 0), "top": (0, 2)}
#: View name -> the volume axis its slices are stacked along (front: z, right: x, top: y).
DEPTH_AXIS: dict[str, int] = {"front": 0, "right": 2, "top": 1}
#: Number of constrained views -> the views.
VIEW_SETS: dict[int, tuple[str, ...]] = {2: ("front", "right"), 3: ("front", "right", "top")}
