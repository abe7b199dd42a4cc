"""Fixed-neighbourhood search methods (Urs thesis, ch. 3): Wei-Levoy (``wl``), Kopf et al.
(``kopf``) and Chen-Wang (``chen-wang``) extended to 2D->3D, on the exact
nearest-neighbourhood matcher (:mod:`clsolid.search.match`) or its k-coherence candidates
(:mod:`clsolid.search.coherence`)."""
