"""The seeding passes' search on principal components (``seed_components``).

The coherence search's exhaustive first pass (``exact_passes``) costs more than all the
passes among the candidates after it. Here it compares each voxel's neighbourhood with every
exemplar site on the P leading principal components of the level's (weighted) sites only:
the site nearest there is the voxel's match, and its distance is then taken on every term,
as the exact search's is. A few components hold most of the variance of a texture's
neighbourhoods, so the site found is the exact one or one nearly as near, and the matcher's
time goes with the terms it sums: P instead of every term (docs/design.md#principal-components). Squared differences only (phase codes are names, not coordinates).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .match import CLMatcher, best_match_reference, candidate_distances_reference


class Projection:
    """The sites of a level's table, and queries, on the leading principal components of
    the sites' rows weighted by *weights* (each term times the square root of its weight).

    Parameters
    ----------
    table : ndarray, ``(n_sites, dim)``
        The sites' rows (as the matcher compares them).
    weights : ndarray, ``(dim,)``
        The distance's per-term weights (0 leaves a term out).
    components : int
        How many components (at most ``dim``).
    """

    def __init__(self, table: np.ndarray, weights: np.ndarray, components: int) -> None:
        self.table = np.asarray(table, np.float64)
        self.weights = np.asarray(weights, np.float64)
        self.scale = np.sqrt(self.weights)
        rows = self.table * self.scale
        self.mean = rows.mean(axis=0)
        _, _, vt = np.linalg.svd(rows - self.mean, full_matrices=False)
        self.basis = vt[: min(components, vt.shape[0])]  # (P, dim)
        self.sites = (rows - self.mean) @ self.basis.T  # (n_sites, P)
        self._device: tuple | None = None

    @property
    def components(self) -> int:
        return self.basis.shape[0]

    def project(self, queries: np.ndarray) -> np.ndarray:
        """Queries ``(m, dim)`` on the components, ``(m, P)``."""
        return (np.asarray(queries, np.float64) * self.scale - self.mean) @ self.basis.T

    def distances(self, queries: np.ndarray, sites: np.ndarray) -> np.ndarray:
        """The weighted squared distance, on every term, of each query to its site (float32)."""
        return candidate_distances_reference(queries, self.table, sites[:, None], self.weights)[:, 0].astype(np.float32)

    def best_reference(self, queries: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The float64 reference: each query's site nearest on the components (the lowest
        index on a tie) and its distance on every term. Returns ``(site (m,), distance (m,))``."""
        site, _ = best_match_reference(self.project(queries), self.sites)
        return site, self.distances(queries, site)

    def on_device(self, matcher: CLMatcher) -> tuple[CLMatcher, Any, Any]:
        """On *matcher*'s device (made once): a matcher of the projected sites (as many
        queries a launch as *matcher*) and the buffers of :meth:`folded`'s basis and offset."""
        import pyopencl as cl

        if self._device is None:
            flags = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
            self._device = (CLMatcher(matcher.device, self.sites.astype(np.float32), max_batch=matcher.max_batch),
                            *(cl.Buffer(matcher.device.context, flags, hostbuf=a) for a in self.folded()))
        return self._device

    def folded(self) -> tuple[np.ndarray, np.ndarray]:
        """``(B (P, dim), c (P,))`` float32 such that a query's projection is ``B q - c``
        (the weights' square roots folded into the basis, the mean into the offset), as the
        device's ``project_queries`` computes it."""
        b = self.basis * self.scale
        return np.ascontiguousarray(b, np.float32), np.ascontiguousarray(self.basis @ self.mean, np.float32)
