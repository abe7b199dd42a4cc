"""Parameters of the NP-MRF maximum-likelihood method, their names, aliases and checks."""

from __future__ import annotations

import math
import numbers
from dataclasses import asdict, dataclass, field, replace

from ..core.checks import int_in, one_of
from ..core.views import DEPTH_AXIS, VIEW_AXES, VIEW_SETS  # noqa: F401 (this method's names too)
from ..core.slices import FALLBACK_SPACING, SEAM_GAP, SEAM_SHOWS
from ..errors import InputError
from ..exemplar import window_grid

#: clsolid name -> (kernel code, thesis tag, paper tag). One table, used by the API, the CLI,
#: the docs and both back ends. Heuristics that compare LCPDFs across views (all but
#: the product and the mean) normalise each view over the labels first.
HEURISTICS: dict[str, tuple[int, str, str | None]] = {
    "h2-product": (0, "NP_ML_H2c", "ML_H2b"),
    "h2-min": (1, "NP_ML_H2a", "ML_H2a"),
    "h2-max": (2, "NP_ML_H2b", None),
    "h1-lowest": (3, "NP_ML_H1a", "ML_H1a"),
    "h1-highest": (4, "NP_ML_H1b", None),
    "h1-mean": (5, "NP_ML_H1c", "ML_H1b"),
}

# Both tag sets, case-insensitive. The paper's ML_H2b is the thesis's NP_ML_H2c (the
# product), so the two sets are kept apart by their prefixes and never guessed at.
_ALIASES = {name: name for name in HEURISTICS}
for _name, (_code, _thesis, _paper) in HEURISTICS.items():
    _ALIASES[_thesis.lower()] = _name
    if _paper:
        _ALIASES[_paper.lower()] = _name


UPSAMPLING = ("1/8", "8/8")
#: Where the +in slices go. "aligned": the same depths and tiling in every view (so the start,
#: and after ICM's first sweep the whole block, is its own x<->z mirror image); "staggered":
#: each view's slices between the other's, each showing the exemplar at its own seeded shift.
SLICE_LAYOUTS = ("aligned", "staggered")
INHERITED = ("resynthesize", "fixed")
# +in slices about every 6 voxels of each constrained view's depth axis (a count given in
# insert_slices overrides it). Four slices a view at 48^3 (one every 12) left 6 of the 15
# gallery exemplars above 0.1 mirror correlation, one every 8 left 3, one every 6 none:
# each slice anchors content that no x<->z-symmetric state shares (docs/choices.md).
DEFAULT_INSERT_SPACING = FALLBACK_SPACING
# Categorical exemplars (those the pruned sum takes): one every 5. Over seeds 1-6 on the ten
# categorical gallery exemplars it met the mirror target in 55 of 60 runs against 48, C2 in
# 48 against 44, the rest alike; on grey ones (brick, hrtem) it gained nothing and cut their
# structure a little (autocorrelation misses 4 -> 6 of 12 runs), so they keep 6 (docs/choices.md).
CATEGORICAL_INSERT_SPACING = 5.0
#: How the exemplar of each coarser scale is made. "binomial" low-passes with [1 2 1]/4 before
#: keeping the even pixels (a Gaussian pyramid, thesis ch. 3); "decimate" keeps them unfiltered
#: (thesis §2.5). One-pixel lines, like brick's mortar, vanish at random under plain decimation.
PYRAMIDS = ("binomial", "decimate")
# Silverman's h (factor 1, the thesis) is ~0.9 sigma in 81 dimensions, so ICM merges
# neighbouring grey levels (mode-seeking). 0.2 x Silverman at every scale keeps them: on
# brick over 6 seeds, histogram score 0.06 against 0.40 (README, Quality).
DEFAULT_BANDWIDTH_FACTOR = 0.2
# Gaussian fall-off of the neighbourhood terms, sigma in pixels of each scale (0: every term
# counts alike, the thesis). On grey exemplars sigma = 3 in an 11 x 11 window lets the nearest
# neighbours weigh most: over six seeds hrtem's patch score met 0.3 on 5 seeds against 1 (worst
# 0.47 -> 0.30) and gravel's worst autocorrelation fell 0.20 -> 0.11, brick's rose 0.30 -> 0.33
# (4 of 6 seeds within 0.3 either way); on categorical ones it moved nothing to the better
# (fibres' autocorrelation 0.13 -> 0.32, copies up), so they keep 0 (docs/choices.md).
GREY_FALLOFF = 3.0
# The window terms on the axis two constrained views share (shared_weight=None: by the
# exemplar). The voxels straight above and below a voxel lie in both views' windows, so
# with every term alike they count twice, and features grow taller than wide (the stretch,
# clsolid.metrics.stretch: 1.2-2.3 on the categorical gallery). Left out on categorical
# exemplars with two views: over seeds 1-6 the stretch falls to 1.1-1.5, copies and
# connectedness rise, the rest alike; grey ones keep them (hrtem's fringes and brick's
# courses lose their spacing without: autocorrelation 0.53-0.86 and 0.33-0.44; docs/choices.md).
CATEGORICAL_SHARED_WEIGHT = 0.0
#: Which terms shared_weight < 1 weighs (clsolid.ml.model.term_weights). "line": the shared
#: axis's own terms (the voxels straight above and below) weigh W, the rest 1; "direction":
#: every term 1 - (1 - W) cos^2 of its angle to that axis, so that a term just off the axis,
#: which says nearly what the axis's own say, weighs nearly as little. On the ten categorical
#: gallery exemplars (seeds 1-6, W = 0) "direction" brought the stretch within 1.25x in 46 of 60
#: runs against 29 with the issue targets alike, at a cost to thin networks' connectedness
#: (cracks' C2 met on 1 of 6 seeds against 5); at 128^2 (seeds 1-4) autocorrelation 32 of 36
#: runs against 29, stretch 19 of 40 against 13 (docs/choices.md).
SHARED_PROFILES = ("direction", "line")
# The coarser scale's 3 x 3 parent terms (parent_weight=None: by the exemplar). On categorical
# exemplars each weighs 4 against 1 for a window term, at the scales whose coarser exemplar has
# at least PARENT_MIN_SIDE pixels on its shorter side: at 128^2 -> 64^3 (ten categorical gallery
# exemplars, seeds 1-4) autocorrelation met in 30 of 36 runs against 22, C2 in 26 against 18,
# copies 25 of 40 against 21, the mirror 32 against 33; from a 32^2 or 16^2 coarser scale (the
# 64^2 gallery) they cost (autocorrelation 11 of 16 against 15), and grey exemplars lost at
# 128^2 (autocorrelation 1 of 10 runs against 4), so those keep 0 (docs/choices.md).
CATEGORICAL_PARENT_WEIGHT = 4.0
PARENT_MIN_SIDE = 64

#: How a visited voxel takes its new label (thesis_spec §2.3). "icm" takes the argmax (the
#: thesis); "gibbs" draws it from the combined, normalised LCPDF, with ICM's per-voxel
#: temperatures and stop rule; "annealing" is TIP14 Fig. 1: a uniform random proposal
#: accepted by a Metropolis-like test at a global temperature t_in that falls every sweep.
RELAXATIONS = ("icm", "gibbs", "annealing")

#: How the Parzen sum is taken (issue 12). "exact" sums over every exemplar site (the thesis);
#: "pruned" over k-coherence candidates plus a sample of the other sites (clsolid.ml.pruned);
#: "auto" prunes categorical exemplars (their own values kept, at most AUTO_PRUNED_LEVELS of
#: them: the gallery's scores equal, or better, 3x faster) and large grey ones, with projected
#: candidates (below), and sums smaller grey ones exactly (there the pruned sum misses the
#: nearest windows: hrtem's and grass's structure is lost).
LIKELIHOODS = ("auto", "exact", "pruned")
AUTO_PRUNED_LEVELS = 8
# Grey exemplars with at least this many sites at the finest scale (about 110^2 pixels at
# 11 x 11): "auto" prunes them too, with projected candidates (prune_projected=None resolves to
# AUTO_PROJECTED_AXES). On the five grey gallery exemplars at 128^2 (into 48^3, seeds 1-2) that
# scored as the exact sum (grass's patch 0.42/0.41 against 0.50/0.45) in about 40 % of its
# time, and better with the settings below (searched in the first sweep only, the sources'
# own windows, 32 sampled sites: grass autocorrelation 0.38/0.41 against the exact 2.24/2.11);
# the plain pruned sum lost grass (0.62/0.54) and gravel's autocorrelation (1.06 against
# 0.68). At 64^2 the projected sum missed hrtem's fringes (in the first sweep only too), so
# smaller grey exemplars keep the exact sum (docs/performance.md).
AUTO_PROJECTED_SITES = 10_000
AUTO_PROJECTED_AXES = 24
# Similar windows taken per source (prune_similar=None): where projected candidates supply
# the near windows, the sources' own windows alone (1), which on the 128^2 grey gallery scored
# better than 8, 4 or 2 (grass autocorrelation 0.31/0.33 against 1.27/1.21 with 8;
# docs/performance.md) and need no table of similar windows (an O(sites^2) search); on the
# categorical gallery (no projected candidates) 4 scored no better than 8.
DEFAULT_SIMILAR = 8
PROJECTED_SIMILAR = 1
# Sites sampled for the rest of the sum (prune_sample=None): half as many with projected
# candidates, which scored alike on the 128^2 grey gallery (seeds 1-4) in 82 % of the time.
DEFAULT_SAMPLE = 64
PROJECTED_SAMPLE = 32
# What a record with projected candidates ran with where it predates an option: every site
# searched (before the site lists), in every sweep (before prune_projected_sweeps).
_PROJECTED_AS_IT_RAN = {"prune_projected_probe": 0, "prune_projected_sweeps": 0}

#: How two neighbourhoods (and a label and a centre value) differ. "squared" sums squared
#: grey-level differences (the thesis); "mismatch" counts the neighbours whose labels differ,
#: each weighted (1 - t)^2, so that phases are names, not numbers: with squared differences a
#: 3-phase material matches a 1-2 pair closer than a 1-3 pair, and its volume changes when its
#: phases' grey values are permuted; "weighted" costs a mismatch between phases a and b
#: 1/(2 f_a) + 1/(2 f_b) (f: the exemplar's fractions; the chi-square distance), so that a rare
#: phase's shapes count as much as the matrix's. On two labels all three are the same
#: distance. "auto" takes "weighted" on categorical exemplars (as for the likelihood: their own
#: values, at most AUTO_PRUNED_LEVELS of them; "mismatch", the same, on two) and "squared" on
#: grey ones (docs/choices.md).
DISTANCES = ("auto", "squared", "mismatch", "weighted")


def canonical_heuristic(name: str) -> str:
    """Return the clsolid name of a heuristic given any of its names or tags."""
    if not isinstance(name, str) or name.lower() not in _ALIASES:
        valid = ", ".join(f"{n} ({t}/{p or '-'})" for n, (_, t, p) in HEURISTICS.items())
        raise InputError(f"heuristic={name!r} is not known; use one of: {valid}")
    return _ALIASES[name.lower()]


def _real(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)


@dataclass(frozen=True)
class MLParams:
    """Every parameter of the ML method (thesis_spec §2), validated on construction.

    See :func:`clsolid.synthesize` for the meaning of each field.
    """

    neighborhood: int = 11
    scales: int = 3
    pyramid: str = "binomial"
    views: int = 2
    levels: int | None = 32
    heuristic: str = "h2-product"
    xi: float = -3.0
    stop_fraction: float = 0.95
    max_sweeps: int = 30
    upsampling: str | None = None
    inherited: str = "resynthesize"
    insert_slices: int | None = None
    insert_spacing: float | None = None  # None: by the exemplar (for_exemplar), else DEFAULT_INSERT_SPACING
    slice_layout: str = "staggered"
    insert_piece: int = 0  # 0: each +in slice one exemplar window; N: N x N pieces (docs/choices.md)
    seam_gap: int | None = None  # pixels left out by a +in slice's wrap seam; None: by the exemplar (for_exemplar)
    initial_temperature: float = 1.0
    bandwidth_factor: float | tuple[float, ...] | None = None
    bandwidth: tuple[float, ...] | None = field(default=None)
    falloff: float | None = None  # None: by the exemplar (for_exemplar); 0: uniform terms (the thesis)
    parent_weight: float | None = None  # each parent term's weight; None: by the exemplar; 0: none (the thesis)
    parent_min_side: int = PARENT_MIN_SIDE  # parent terms where the coarser exemplar is at least this wide
    # each window term on a line through the voxel that another constrained view's window holds too (and,
    # by shared_profile, the terms near it); None: by the exemplar (for_exemplar); 1: as any term (the
    # thesis; a checkpoint older than it, as it ran)
    shared_weight: float | None = None
    shared_profile: str = "direction"  # which terms it weighs (SHARED_PROFILES; a record older than it: "line")
    # (a checkpoint older than the fall-off has no such key: None reaches build_scale, which takes 0, as it ran)
    relaxation: str = "gibbs"
    anneal_start: float = 1.0
    anneal_cooling: float = 0.8
    sweeps: int | None = None
    balance: float = 1.0
    likelihood: str = "auto"
    distance: str = "auto"
    prune_similar: int | None = None  # None: n_similar decides (for_exemplar records it)
    prune_sample: int | None = None  # None: n_sample decides (for_exemplar records it)
    prune_min_weight: float = 0.0
    # axes of the projected candidate search (0: off; None: by the exemplar, for_exemplar;
    # clsolid.ml.pruned.ProjectedWindows)
    prune_projected: int | None = None
    prune_projected_k: int = 32  # its candidates a voxel and view (docs/performance.md: 64 cost 1.6x, scored alike)
    prune_projected_probe: int = 8  # site lists it reads (0: every site; clsolid.ml.pruned.site_lists)
    # the first sweeps of each scale that search them (0: every sweep; docs/performance.md)
    prune_projected_sweeps: int = 1
    # 0: each sweep visits the sets over the whole block; N: region by region, cubes of N voxels,
    # every set of one before the next (a tiled run's disk and transfers; tissue scores worse: README, Using it)
    region: int = 0

    def __post_init__(self):
        k = int_in("neighborhood", self.neighborhood, 3, 31)
        if k % 2 == 0:
            raise InputError(f"neighborhood={k} must be odd (a full square k x k centred on the voxel)")
        int_in("scales", self.scales, 1, 8)
        one_of("pyramid", self.pyramid, PYRAMIDS)
        if self.views not in VIEW_SETS:
            raise InputError(f"views={self.views!r} must be 2 (front + right) or 3 (front + right + top)")
        if self.levels is not None:
            int_in("levels", self.levels, 2, 65536)
        object.__setattr__(self, "heuristic", canonical_heuristic(self.heuristic))
        if not (isinstance(self.xi, numbers.Real) and math.isfinite(self.xi) and self.xi < 0):
            raise InputError(f"xi={self.xi!r} must be a finite negative number (thesis default -3)")
        if not (isinstance(self.stop_fraction, numbers.Real) and 0 < self.stop_fraction <= 1):
            raise InputError(f"stop_fraction={self.stop_fraction!r} must be in (0, 1] (1 = until zero)")
        int_in("max_sweeps", self.max_sweeps, 1)
        one_of("inherited", self.inherited, INHERITED)
        if self.insert_slices is not None:
            int_in("insert_slices", self.insert_slices, 0)
        if self.insert_spacing is not None and not (_real(self.insert_spacing) and self.insert_spacing >= 1):
            raise InputError(f"insert_spacing={self.insert_spacing!r} must be a number >= 1 (voxels between "
                             "a view's +in slices); insert_slices=0 gives no slices")
        one_of("slice_layout", self.slice_layout, SLICE_LAYOUTS)
        if int_in("insert_piece", self.insert_piece, 0) % 2 ** (self.scales - 1):
            raise InputError(f"insert_piece={self.insert_piece!r} must be 0 (whole exemplar windows) or a "
                             f"multiple of 2^(scales-1) = {2 ** (self.scales - 1)}, so that every scale "
                             "has the same pieces")
        if self.seam_gap is not None:
            int_in("seam_gap", self.seam_gap, 0)
        int_in("region", self.region, 0)
        t0 = self.initial_temperature
        if not (isinstance(t0, numbers.Real) and 0 < t0 <= 1):
            raise InputError(f"initial_temperature={t0!r} must be in (0, 1] (1 = no confidence, the thesis)")
        if self.bandwidth is not None and self.bandwidth_factor is not None:
            raise InputError("give bandwidth or bandwidth_factor, not both")
        if self.bandwidth is not None:
            object.__setattr__(self, "bandwidth", self._per_scale("bandwidth", self.bandwidth))
        elif self.bandwidth_factor is not None:
            object.__setattr__(self, "bandwidth_factor", self._per_scale("bandwidth_factor", self.bandwidth_factor))
        else:
            object.__setattr__(self, "bandwidth_factor", (DEFAULT_BANDWIDTH_FACTOR,) * self.scales)
        if self.falloff is not None and not (_real(self.falloff) and self.falloff >= 0):
            raise InputError(f"falloff={self.falloff!r} must be a number >= 0 (the sigma, in pixels, of the "
                             "Gaussian weight of each neighbourhood term; 0 = every term alike, the thesis)")
        if self.parent_weight is not None and not (_real(self.parent_weight) and self.parent_weight >= 0):
            raise InputError(f"parent_weight={self.parent_weight!r} must be a number >= 0 (the weight of each "
                             "of the coarser scale's 3 x 3 parent terms in a neighbourhood; 0 = none, the thesis)")
        int_in("parent_min_side", self.parent_min_side, 0)
        if self.shared_weight is not None and not (_real(self.shared_weight) and 0 <= self.shared_weight <= 1):
            raise InputError(f"shared_weight={self.shared_weight!r} must be a number in [0, 1] (the weight of the "
                             "window terms on the axis the constrained views share; 0 = left out, 1 = the thesis)")
        one_of("shared_profile", self.shared_profile, SHARED_PROFILES)
        one_of("relaxation", self.relaxation, RELAXATIONS)
        if self.upsampling is None:  # 1/8 for ICM (thesis §5.3.3), 8/8 for annealing (TIP14)
            object.__setattr__(self, "upsampling", "8/8" if self.relaxation == "annealing" else "1/8")
        one_of("upsampling", self.upsampling, UPSAMPLING)
        if not (_real(self.anneal_start) and self.anneal_start > 0):
            raise InputError(f"anneal_start={self.anneal_start!r} must be a positive number "
                             "(the initial t_in; 1 = Metropolis on the LCPDF)")
        if not (_real(self.anneal_cooling) and 0 < self.anneal_cooling < 1):
            raise InputError(f"anneal_cooling={self.anneal_cooling!r} must be in (0, 1) "
                             "(t_in is multiplied by it after every sweep)")
        if self.sweeps is not None:
            int_in("sweeps", self.sweeps, 1)
        if not (_real(self.balance) and 0 <= self.balance <= 1):
            raise InputError(f"balance={self.balance!r} must be a number in [0, 1] "
                             "(0 = off, 1 = the exemplar's label fractions exactly)")
        one_of("likelihood", self.likelihood, LIKELIHOODS)
        one_of("distance", self.distance, DISTANCES)
        if self.prune_similar is not None:
            int_in("prune_similar", self.prune_similar, 1, 16)
        if self.prune_sample is not None:
            int_in("prune_sample", self.prune_sample, 0, 4096)
        if self.prune_projected is not None:
            int_in("prune_projected", self.prune_projected, 0, 64)
        int_in("prune_projected_k", self.prune_projected_k, 1, 256)
        int_in("prune_projected_probe", self.prune_projected_probe, 0, 1024)
        int_in("prune_projected_sweeps", self.prune_projected_sweeps, 0, 1 << 20)
        if not (_real(self.prune_min_weight) and 0 <= self.prune_min_weight <= 1):
            raise InputError(f"prune_min_weight={self.prune_min_weight!r} must be a number in [0, 1] (the "
                             "mean (1 - t)^2 of a neighbourhood below which the pruned mode sums exactly)")

    def _per_scale(self, name: str, value) -> tuple[float, ...]:
        """One positive number for every scale, or one per scale (finest first)."""
        values = (value,) * self.scales if isinstance(value, numbers.Real) else value
        try:
            values = tuple(values)
        except TypeError:
            values = ()
        if len(values) != self.scales or not all(
            isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v) and v > 0 for v in values
        ):
            raise InputError(f"{name}={value!r} must be a positive number or one per scale "
                             f"({self.scales} values, finest first)")
        return tuple(float(v) for v in values)

    def for_exemplar(self, n_levels: int, categorical: bool, seam_ratio: float = 0.0,
                     shape: tuple[int, int] | None = None) -> "MLParams":
        """These parameters with ``likelihood="auto"``, ``distance="auto"``,
        ``insert_spacing=None``, ``falloff=None``, ``seam_gap=None``, ``parent_weight=None``,
        ``shared_weight=None``, ``prune_projected=None``,
        ``prune_similar=None`` and ``prune_sample=None`` resolved for an exemplar of *n_levels*
        levels, *categorical* if they are its own values (not a quantisation of grey ones),
        whose :func:`~clsolid.core.slices.seam_ratio` is *seam_ratio*, of *shape* (rows,
        columns; None: small)."""
        phases = categorical and n_levels <= AUTO_PRUNED_LEVELS
        k = self.neighborhood
        large = shape is not None and math.prod(window_grid(shape, k)) >= AUTO_PROJECTED_SITES
        likelihood = self.likelihood
        if likelihood == "auto":
            likelihood = "pruned" if phases or large else "exact"
        projected = self.prune_projected
        if projected is None:
            projected = AUTO_PROJECTED_AXES if likelihood == "pruned" and large and not phases else 0
        # On two phases the weights are one constant: the plain count is the same distance.
        counted = "weighted" if n_levels > 2 else "mismatch"
        distance = (counted if phases else "squared") if self.distance == "auto" else self.distance
        spacing = self.insert_spacing
        if spacing is None:
            spacing = CATEGORICAL_INSERT_SPACING if phases else DEFAULT_INSERT_SPACING
        falloff = self.falloff
        if falloff is None:
            falloff = 0.0 if phases else GREY_FALLOFF
        gap = self.seam_gap
        if gap is None:
            gap = SEAM_GAP if seam_ratio > SEAM_SHOWS else 0
        parents = self.parent_weight
        if parents is None:
            parents = CATEGORICAL_PARENT_WEIGHT if phases else 0.0
        shared = self.shared_weight
        if shared is None:  # measured with two views only
            shared = CATEGORICAL_SHARED_WEIGHT if phases and self.views == 2 else 1.0
        resolved = replace(self, likelihood=likelihood, distance=distance, insert_spacing=spacing,
                           falloff=float(falloff), seam_gap=gap, prune_projected=projected,
                           parent_weight=float(parents), shared_weight=float(shared))
        return replace(resolved, prune_similar=resolved.n_similar, prune_sample=resolved.n_sample)

    def _by_projection(self, value: int | None, projected: int, default: int) -> int:
        """*value*, or where it is None *projected* with projected candidates, else *default*."""
        if value is not None:
            return value
        return projected if self.prune_projected else default

    @property
    def n_similar(self) -> int:
        """The similar windows the pruned sum takes per source (``prune_similar``; None:
        :data:`PROJECTED_SIMILAR` with projected candidates, else :data:`DEFAULT_SIMILAR`)."""
        return self._by_projection(self.prune_similar, PROJECTED_SIMILAR, DEFAULT_SIMILAR)

    @property
    def n_sample(self) -> int:
        """The sites the pruned sum samples for the rest (``prune_sample``; None:
        :data:`PROJECTED_SAMPLE` with projected candidates, else :data:`DEFAULT_SAMPLE`)."""
        return self._by_projection(self.prune_sample, PROJECTED_SAMPLE, DEFAULT_SAMPLE)

    @property
    def view_names(self) -> tuple[str, ...]:
        return VIEW_SETS[self.views]

    @property
    def heuristic_code(self) -> int:
        return HEURISTICS[self.heuristic][0]

    @classmethod
    def from_dict(cls, d: dict) -> "MLParams":
        """The parameters recorded by :meth:`to_dict` (e.g. ``SynthesisResult.params``, a checkpoint's);
        other keys are ignored. Keys a record predates take the value it ran with, not today's default."""
        kept = {k: d[k] for k in cls.__dataclass_fields__ if k in d}
        kept.setdefault("parent_weight", 0.0)  # before parent terms there were none
        if "shared_weight" in kept:  # weighed the shared line alone before the profiles
            kept.setdefault("shared_profile", "line")
        if kept.get("prune_projected"):
            kept = {**_PROJECTED_AS_IT_RAN, **kept}
        return cls(**kept)

    @property
    def relaxation_code(self) -> int:
        """0 icm, 1 gibbs, 2 annealing (the kernel's numbering)."""
        return RELAXATIONS.index(self.relaxation)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["bandwidth"] = list(self.bandwidth) if self.bandwidth else None
        return d
