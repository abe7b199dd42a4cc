"""Parameters of the NP-MRF maximum-likelihood method: each declared once, with its check and help."""

from __future__ import annotations

import math
import numbers
from dataclasses import asdict, dataclass, replace
from typing import Any

from ..core.geometry import window_grid
from ..core.options import (
    Check,
    Choice,
    Int,
    Real,
    Reals,
    despeckle_option,
    documented,
    levels_option,
    neighborhood_option,
    option,
    scales_option,
    validate,
    views_option,
)
from ..core.slices import FALLBACK_SPACING, SEAM_GAP, SEAM_SHOWS
from ..core.views import VIEW_AXES, VIEW_SETS, view_set  # noqa: F401 (VIEW_AXES: this method's name for them too)
from ..errors import InputError
from ..phases import is_categorical

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

#: Coarse-to-fine copy: one voxel of each 2x2x2 block (the thesis's ICM) or all eight (TIP 2014's annealing).
UPSAMPLING = ("1/8", "8/8")
#: Where the +in slices go. "aligned": the same depths and tiling in every view (so the start,
#: and after ICM's first sweep the whole block, is its own x<->z mirror image); "staggered":
#: each view's slices between the other's, each showing the exemplar at its own seeded shift.
SLICE_LAYOUTS = ("aligned", "staggered")
INHERITED = ("resynthesize", "fixed")
#: +in slices about every this many voxels of a view's depth; each slice anchors content that
#: no mirror-symmetric state shares (docs/design.md#inserted-slices).
DEFAULT_INSERT_SPACING = FALLBACK_SPACING
#: Denser slices on categorical exemplars, which keep less of the mirror in check otherwise;
#: grey ones lose structure with them (docs/design.md#inserted-slices).
CATEGORICAL_INSERT_SPACING = 5.0
#: How the exemplar of each coarser scale is made. "binomial" low-passes with [1 2 1]/4 before
#: keeping the even pixels (a Gaussian pyramid, thesis ch. 3); "decimate" keeps them unfiltered
#: (thesis §2.5). One-pixel lines, like brick's mortar, vanish at random under plain decimation.
PYRAMIDS = ("binomial", "decimate")
#: Silverman's bandwidth times this: at Silverman's own, ICM merges neighbouring grey levels
#: (mode-seeking; docs/design.md#bandwidth).
DEFAULT_BANDWIDTH_FACTOR = 0.2
#: Gaussian fall-off sigma (pixels) of the window terms on grey exemplars: the nearest
#: neighbours weigh most; categorical ones keep every term alike (docs/design.md#falloff).
GREY_FALLOFF = 3.0
#: The weight of the window terms along the axis two constrained views share, on categorical
#: exemplars with two views: counted in both views' windows, they make features taller than
#: wide; grey ones keep them, or fringes and courses lose their spacing (docs/design.md#shared-axis).
CATEGORICAL_SHARED_WEIGHT = 0.0
#: Which terms shared_weight < 1 weighs (clsolid.ml.model.term_weights). "line": the shared
#: axis's own terms (the voxels straight above and below) weigh W, the rest 1; "direction":
#: every term 1 - (1 - W) cos^2 of its angle to that axis, so that a term just off the axis,
#: which says nearly what the axis's own say, weighs nearly as little (docs/design.md#shared-axis).
SHARED_PROFILES = ("direction", "line")
#: Each coarser-scale 3 x 3 parent term's weight on categorical exemplars, at the scales whose
#: coarser exemplar is at least PARENT_MIN_SIDE wide: it keeps features wider than the window;
#: from smaller coarser scales, and on grey exemplars, it costs (docs/design.md#parent-terms).
CATEGORICAL_PARENT_WEIGHT = 4.0
PARENT_MIN_SIDE = 64

#: How a visited voxel takes its new label (thesis §2.3). "icm" takes the argmax (the
#: thesis); "gibbs" draws it from the combined, normalised LCPDF, with ICM's per-voxel
#: temperatures and stop rule; "annealing" is TIP 2014 Fig. 1: a uniform random proposal
#: accepted by a Metropolis-like test at a global temperature t_in that falls every sweep.
RELAXATIONS = ("icm", "gibbs", "annealing")

#: How the Parzen sum is taken. "exact" sums over every exemplar site (the thesis);
#: "pruned" over k-coherence candidates plus a sample of the other sites (clsolid.ml.pruned);
#: "auto" prunes categorical exemplars and large grey ones (with projected candidates) and sums
#: smaller grey ones exactly, where the pruned sum misses the nearest windows (docs/design.md#pruned-likelihood).
LIKELIHOODS = ("auto", "exact", "pruned")
#: Grey exemplars with at least this many sites at the finest scale (about 110^2 pixels at
#: 11 x 11): "auto" prunes them too, with projected candidates on AUTO_PROJECTED_AXES axes.
AUTO_PROJECTED_SITES = 10_000
AUTO_PROJECTED_AXES = 24
#: Similar windows taken per source: where projected candidates supply the near windows, the
#: sources' own windows alone (no table of similar windows, an O(sites^2) search).
DEFAULT_SIMILAR = 8
PROJECTED_SIMILAR = 1
#: Sites sampled for the rest of the sum; projected candidates need half as many.
DEFAULT_SAMPLE = 64
PROJECTED_SAMPLE = 32
# What a record with projected candidates ran with where it predates an option: every site
# searched (before the site lists), in every sweep (before prune_projected_sweeps).
_PROJECTED_AS_IT_RAN = {"prune_projected_probe": 0, "prune_projected_sweeps": 0}

#: How two neighbourhoods (and a label and a centre value) differ. "squared" sums squared
#: grey-level differences (the thesis); "mismatch" counts the neighbours whose labels differ,
#: each weighted (1 - t)^2, so that phases are names, not numbers; "weighted" costs a mismatch
#: between phases a and b 1/(2 f_a) + 1/(2 f_b) (f: the exemplar's fractions; the chi-square
#: distance), so that a rare phase's shapes count as much as the matrix's. On two labels all
#: three are the same distance. "auto": "weighted" on categorical exemplars ("mismatch", the
#: same, on two), "squared" on grey ones (docs/design.md#categorical-exemplars).
DISTANCES = ("auto", "squared", "mismatch", "weighted")

def canonical_heuristic(name: str) -> str:
    """Return the clsolid name of a heuristic given any of its names or tags."""
    if not isinstance(name, str) or name.lower() not in _ALIASES:
        valid = ", ".join(f"{n} ({t}/{p or '-'})" for n, (_, t, p) in HEURISTICS.items())
        raise InputError(f"heuristic={name!r} is not known; use one of: {valid}")
    return _ALIASES[name.lower()]


class _Heuristic(Check):
    """A heuristic's clsolid name or either tag (case-insensitive)."""

    def describe(self) -> str:
        return f"one of {', '.join(HEURISTICS)} or a thesis/paper tag"

    def __call__(self, name: str, value: Any) -> str:
        return canonical_heuristic(value)


_ML, _TUNE = "ml", "ml-tuning"


@documented
@dataclass(frozen=True)
class MLParams:
    """Every parameter of the NP-MRF maximum-likelihood method, validated on construction.

    Each field is declared once (:func:`clsolid.core.options.option`), with its check, its
    one-line help and its command-line group; ``clsolid synth --help-all`` and the option
    reference in the docs list them all. Fields whose default is None are decided by the
    exemplar (:meth:`for_exemplar`); the result's ``params`` record what was taken.

    The published form of the method (Urs et al., TIP 2014; Urs thesis ch. 5) is
    ``views=2, relaxation="icm", polish_sweeps=0, balance=0, slice_layout="aligned", insert_slices=4,
    distance="squared", falloff=0, seam_gap=0, parent_weight=0, shared_weight=1,
    bandwidth_factor=1, pyramid="decimate"`` (the likelihood presets of :mod:`clsolid.presets`).
    """

    neighborhood: int = neighborhood_option(11)
    scales: int = scales_option()
    pyramid: str = option("binomial", "coarser exemplars: [1 2 1]/4 low-pass then 2:1 decimation, or plain "
                          "decimation (the thesis)", group=_TUNE, check=Choice(PYRAMIDS), advanced=True)
    views: int | str = views_option()
    levels: int | None = levels_option()
    despeckle: bool = despeckle_option()
    heuristic: str = option("h2-product", "how the views' LCPDFs combine: " + ", ".join(HEURISTICS)
                            + ", or a thesis/paper tag", group=_ML, check=_Heuristic(), metavar="NAME")
    xi: float = option(-3.0, "cooling parameter xi < 0 of the per-voxel temperatures", group=_TUNE,
                       check=Real(hi=0, hi_open=True), advanced=True)
    stop_fraction: float = option(0.95, "stop a scale when the global temperature fell by this fraction",
                                  group=_TUNE, check=Real(0, 1, lo_open=True), advanced=True)
    max_sweeps: int = option(30, "most sweeps per scale", group=_TUNE, check=Int(1), advanced=True)
    upsampling: str | None = option(None, "coarse-to-fine copy: one voxel of each 2x2x2 block, or all eight",
                                    group=_TUNE, check=Choice(UPSAMPLING), advanced=True,
                                    none="1/8, or 8/8 under annealing (TIP 2014)")
    inherited: str = option("resynthesize", "voxels from the coarser scale: re-synthesised with t = 0, or fixed",
                            group=_TUNE, check=Choice(INHERITED), advanced=True)
    insert_slices: int | None = option(None, "+in slices per constrained view (0: none, the thesis's -in)",
                                       group=_TUNE, check=Int(0), advanced=True, none="by insert_spacing")
    insert_spacing: float | None = option(None, "+in: an exemplar slice about every this many voxels of each "
                                          "view's depth", group=_TUNE, check=Real(1), advanced=True,
                                          none="5 on categorical exemplars, 6 on grey ones")
    slice_layout: str = option("staggered", "+in slices at the same depths in every view, or staggered between "
                               "views with seeded shifts", group=_TUNE, check=Choice(SLICE_LAYOUTS), advanced=True)
    insert_piece: int = option(0, "+in slices as mosaics of N x N pieces, each from its own exemplar window (a "
                               "multiple of 2^(scales-1); 0: one window a slice)", group=_TUNE, check=Int(0),
                               advanced=True, metavar="N")
    seam_gap: int | None = option(None, "pixels of a +in slice left out on each side of a seam where it tiles the "
                                  "exemplar across its edge", group=_TUNE, check=Int(0), advanced=True,
                                  none="2 where the exemplar's seam shows, else 0")
    initial_temperature: float = option(1.0, "temperature of the voxels not trusted at the start of a scale",
                                        group=_TUNE, check=Real(0, 1, lo_open=True), advanced=True)
    bandwidth_factor: float | tuple[float, ...] | None = option(
        None, "Parzen bandwidth as a multiple of Silverman's: one factor, or one per scale finest first (1: the "
        "thesis)", group=_ML, check=Reals(), metavar="F", none=f"{DEFAULT_BANDWIDTH_FACTOR} at every scale")
    bandwidth: tuple[float, ...] | None = option(
        None, "Parzen bandwidth itself: one value, or one per scale finest first", group=_TUNE, check=Reals(),
        advanced=True, metavar="H", none="bandwidth_factor x Silverman's")
    falloff: float | None = option(None, "sigma (pixels) of the Gaussian weight of each window term by its "
                                   "distance from the centre; 0: every term alike (the thesis)", group=_TUNE,
                                   check=Real(0), advanced=True, none="3 on grey exemplars, 0 on categorical ones")
    parent_weight: float | None = option(None, "weight of each of the coarser scale's 3 x 3 parent terms; 0: none "
                                         "(the thesis)", group=_TUNE, check=Real(0), advanced=True,
                                         none="4 on categorical exemplars, 0 on grey ones")
    parent_min_side: int = option(PARENT_MIN_SIDE, "parent terms only where the coarser exemplar is at least N "
                                  "pixels on its shorter side", group=_TUNE, check=Int(0), advanced=True, metavar="N")
    shared_weight: float | None = option(None, "weight of the window terms on the axis two views share; 1: as any "
                                         "term (the thesis)", group=_TUNE, check=Real(0, 1), advanced=True,
                                         metavar="W", none="0 on categorical exemplars with 2 views, else 1")
    shared_profile: str = option("direction", "which terms shared_weight weighs: by their direction to the shared "
                                 "axis, or that axis's own only (thin networks stay more connected)", group=_TUNE,
                                 check=Choice(SHARED_PROFILES), advanced=True)
    relaxation: str = option("gibbs", "a voxel's new label: the argmax (icm, the thesis), a draw from the LCPDF "
                             "(gibbs) or TIP 2014's simulated annealing", group=_ML, check=Choice(RELAXATIONS))
    anneal_start: float = option(1.0, "annealing: initial global temperature t_in of every scale", group=_TUNE,
                                 check=Real(0, lo_open=True), advanced=True)
    anneal_cooling: float = option(0.8, "annealing: t_in is multiplied by this after every sweep", group=_TUNE,
                                   check=Real(0, 1, lo_open=True, hi_open=True), advanced=True)
    sweeps: int | None = option(None, "exactly this many sweeps per scale", group=_TUNE, check=Int(1), advanced=True,
                                none="the temperature stop rule")
    # none by default: they clear too few isolated voxels for their time (docs/design.md#polish-sweeps)
    polish_sweeps: int = option(0, "last sweeps of the finest scale that take each voxel's argmax (as icm), "
                                "visiting every voxel but fixed inherited ones: they clear some of the isolated voxels "
                                "that draws leave; 0: none", group=_TUNE, check=Int(0), advanced=True, metavar="N")
    balance: float = option(1.0, "label-histogram balance: each sweep aims this far towards the exemplar's "
                            "fractions (0: off, the thesis)", group=_ML, check=Real(0, 1), metavar="B")
    likelihood: str = option("auto", "the Parzen sum over every exemplar site (exact, the thesis) or over "
                             "k-coherence candidates and a sample (pruned); auto: pruned for categorical and large "
                             "grey exemplars", group=_ML, check=Choice(LIKELIHOODS))
    distance: str = option("auto", "how neighbourhoods differ: squared grey-level differences (the thesis), "
                           "mismatch counts, or mismatches weighted by phase fractions; auto: weighted on "
                           "categorical exemplars, squared on grey ones", group=_ML, check=Choice(DISTANCES))
    prune_similar: int | None = option(None, "pruned: windows taken per source, itself included", group=_TUNE,
                                       check=Int(1, 16), advanced=True, none="1 with projected candidates, else 8")
    prune_sample: int | None = option(None, "pruned: sites sampled to estimate the rest of the sum", group=_TUNE,
                                      check=Int(0, 4096), advanced=True, none="32 with projected candidates, else 64")
    prune_min_weight: float = option(0.0, "pruned: a neighbourhood whose mean (1 - t)^2 is below this gets the "
                                     "exact sum", group=_TUNE, check=Real(0, 1), advanced=True)
    prune_projected: int | None = option(None, "pruned: also each voxel's nearest sites by the distance projected on "
                                         "the windows' first AXES principal axes (0: off)", group=_TUNE,
                                         check=Int(0, 64), advanced=True, metavar="AXES",
                                         none="24 where auto prunes a grey exemplar, else 0")
    prune_projected_k: int = option(32, "pruned: projected candidates per voxel and view", group=_TUNE,
                                    check=Int(1, 256), advanced=True, metavar="K")
    prune_projected_probe: int = option(8, "pruned: search the P lists of sites nearest to the voxel's projection "
                                        "(0: every site)", group=_TUNE, check=Int(0, 1024), advanced=True, metavar="P")
    prune_projected_sweeps: int = option(1, "pruned: search projected candidates in the first N sweeps of each "
                                         "scale (0: every sweep)", group=_TUNE, check=Int(0, 1 << 20), advanced=True,
                                         metavar="N")
    region: int = option(0, "visit the block region by region, cubes of at most N voxels, every set of one before "
                         "the next (0: set by set over the whole block)", group=_TUNE, check=Int(0), advanced=True,
                         metavar="N")

    def __post_init__(self) -> None:
        validate(self)
        if self.insert_piece % 2 ** (self.scales - 1):
            raise InputError(f"insert_piece={self.insert_piece!r} must be 0 (whole exemplar windows) or a "
                             f"multiple of 2^(scales-1) = {2 ** (self.scales - 1)}, so that every scale "
                             "has the same pieces")
        if self.bandwidth is not None and self.bandwidth_factor is not None:
            raise InputError("give bandwidth or bandwidth_factor, not both")
        if self.bandwidth is not None:
            object.__setattr__(self, "bandwidth", self._per_scale("bandwidth", self.bandwidth))
        elif self.bandwidth_factor is not None:
            object.__setattr__(self, "bandwidth_factor", self._per_scale("bandwidth_factor", self.bandwidth_factor))
        else:
            object.__setattr__(self, "bandwidth_factor", (DEFAULT_BANDWIDTH_FACTOR,) * self.scales)
        if self.upsampling is None:  # 1/8 for ICM (thesis §5.3.3), 8/8 for annealing (TIP 2014)
            object.__setattr__(self, "upsampling", "8/8" if self.relaxation == "annealing" else "1/8")

    def _per_scale(self, name: str, value) -> tuple[float, ...]:
        """One positive number for every scale, or one per scale (finest first)."""
        values = (value,) * self.scales if isinstance(value, numbers.Real) else tuple(value)
        if len(values) != self.scales:
            raise InputError(f"{name}={value!r} must be a positive number or one per scale "
                             f"({self.scales} values, finest first)")
        return tuple(float(v) for v in values)

    def for_exemplar(self, n_levels: int, categorical: bool, seam_ratio: float = 0.0,
                     shape: tuple[int, int] | None = None, per_view: bool = False,
                     colour: bool = False) -> "MLParams":
        """These parameters with every option left to the exemplar (None, ``"auto"``) decided.

        Parameters
        ----------
        n_levels : int
            The exemplar's levels.
        categorical : bool
            Whether those are its own values, not a quantisation of grey ones (``LevelMap.exact``).
        seam_ratio : float
            Its :func:`~clsolid.core.slices.seam_ratio`.
        shape : tuple of 2 ints, optional
            Its rows and columns (None: small).
        per_view : bool
            Whether each view has its own exemplar: the exact sum then (the pruned one follows
            sources within one exemplar), and ``likelihood="pruned"`` is refused.
        colour : bool
            Whether the labels are a colour exemplar's palette: compared by their colours
            (``distance="squared"``), the pruned sum at every size, without projected
            candidates; compared as phases, as any labels.

        Returns
        -------
        MLParams
        """
        phases = is_categorical(n_levels, categorical)
        k = self.neighborhood
        large = shape is not None and math.prod(window_grid(shape, k)) >= AUTO_PROJECTED_SITES
        # On two phases the weights are one constant: the plain count is the same distance.
        counted = "weighted" if n_levels > 2 else "mismatch"
        distance = (counted if phases else "squared") if self.distance == "auto" else self.distance
        by_colour = colour and distance == "squared"
        likelihood = self.likelihood
        if per_view and likelihood == "pruned":
            raise InputError("likelihood='pruned' takes one exemplar; with an exemplar per view use "
                             "likelihood='exact' (or 'auto', which chooses it)")
        if likelihood == "auto":  # colours: three terms a neighbour, pruned at every size (docs/design.md#colour)
            likelihood = "exact" if per_view else "pruned" if phases or large or by_colour else "exact"
        projected = self.prune_projected
        if projected is None:  # colours have no projection (clsolid.ml.pruned.ProjectedWindows)
            projected = AUTO_PROJECTED_AXES if likelihood == "pruned" and large and not phases and not by_colour else 0
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
            shared = CATEGORICAL_SHARED_WEIGHT if phases and self.view_names == VIEW_SETS[2] else 1.0
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
        return view_set(self.views)

    @property
    def heuristic_code(self) -> int:
        return HEURISTICS[self.heuristic][0]

    def polish_at(self, level: int) -> int:
        """The polish sweeps that end scale *level* (0: the finest): ``polish_sweeps`` at the
        finest, none coarser, where the finer scale re-draws most voxels anyway."""
        return self.polish_sweeps if level == 0 else 0

    @property
    def relaxation_code(self) -> int:
        """0 icm, 1 gibbs, 2 annealing (the kernel's numbering)."""
        return RELAXATIONS.index(self.relaxation)

    @classmethod
    def from_dict(cls, d: dict) -> "MLParams":
        """The parameters recorded by :meth:`to_dict` (e.g. ``SynthesisResult.params``, a checkpoint's);
        other keys are ignored. Keys a record predates take the value it ran with, not today's default."""
        kept = {k: d[k] for k in cls.__dataclass_fields__ if k in d}
        kept.setdefault("parent_weight", 0.0)  # before parent terms there were none
        kept.setdefault("despeckle", False)  # nor the last step on phases
        if "shared_weight" in kept:  # weighed the shared line alone before the profiles
            kept.setdefault("shared_profile", "line")
        if kept.get("prune_projected"):
            kept = {**_PROJECTED_AS_IT_RAN, **kept}
        for name in ("bandwidth", "bandwidth_factor"):  # lists in a JSON record
            if isinstance(kept.get(name), list):
                kept[name] = tuple(kept[name])
        return cls(**kept)

    def to_dict(self) -> dict:
        """Every parameter, JSON-ready (per-scale values as lists)."""
        d = asdict(self)
        d["bandwidth"] = list(self.bandwidth) if self.bandwidth else None
        return d
