"""Fixed-neighbourhood search methods (thesis_spec §1): Wei-Levoy (``wl``) and Kopf et al.
(``kopf``) extended to 2D->3D, on the exact nearest-neighbourhood matcher
(:mod:`clsolid.search.match`); Chen-Wang is issue 11's next step."""
