"""Fixed-neighbourhood search methods (Wei-Levoy, Kopf et al., Chen-Wang extended to 2D->3D,
thesis_spec §1). So far: the exact nearest-neighbourhood matcher they are built on
(:mod:`clsolid.search.match`); the methods themselves are issue 11's next steps."""
