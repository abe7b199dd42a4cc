"""Fixed-neighbourhood search methods (Urs thesis, ch. 3): Wei-Levoy (``wl``), Kopf et al.
(``kopf``) and Chen-Wang (``chen-wang``) extended to 2D->3D, on the exact
nearest-neighbourhood matcher (:mod:`clsolid.search.match`) or its k-coherence candidates
(:mod:`clsolid.search.coherence`)."""

from ..core.hostmemory import Footprint
from ..core.probe import register_smoke_test

#: The host memory of a search run: the block, its matches and sources per view, the level
#: tables, the most that ``chen-wang`` takes (docs/design.md#host-memory).
FOOTPRINT = Footprint(120)

register_smoke_test("clsolid.search.smoke:smoke_test")
