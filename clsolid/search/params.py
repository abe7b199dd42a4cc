"""Parameters of the fixed-neighbourhood search methods (Urs thesis, ch. 3 and 5): each declared once,
with its check and help."""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

from ..core.options import (
    Choice,
    Flag,
    Int,
    Real,
    despeckle_option,
    documented,
    levels_option,
    neighborhood_option,
    option,
    scales_option,
    validate,
    views_option,
)
from ..core.orders import ORDERS
from ..core.views import view_set
from ..errors import InputError
from .match import MAX_K

#: The search methods.
METHODS = ("wl", "kopf", "chen-wang")
#: How a finer level starts (the thesis is ambiguous there): the coarser result
#: up-sampled (Kopf), or fresh noise tied to the coarser level only by the parent square.
INITS = ("upsample", "noise")
#: kopf's rule for a voxel's new value: the thesis's (each view's matched centre) or Kopf et
#: al.'s own (every overlapping matched square proposes a value; clsolid.search.kopf).
RULES = ("centres", "overlap")
#: "sets": conflict-free sets in parallel, in a seeded order (fast, the default); the others
#: visit one voxel at a time in that order (clsolid.core.orders; small blocks, fidelity checks).
ORDERS_ALL = ("sets",) + ORDERS
#: kopf's histogram re-weighting: against the whole block's histogram, or the slice's (in the
#: view of the match) that holds the voxel.
HISTOGRAMS = ("global", "slice")
#: How each voxel's best match is found: the exhaustive search (the reference) or among
#: k-coherence candidates (clsolid.search.coherence).
SEARCHES = ("exact", "coherence")
#: How the matched squares compare a categorical exemplar's phases (clsolid.search.codes):
#: "squared" grey-level differences (the thesis), "weighted" mismatches of phase codes; "auto":
#: for kopf weighted on categorical exemplars of 3 or more phases (on two the two agree), else
#: squared (worse for chen-wang, mixed for wl: docs/design.md#phase-codes).
DISTANCES = ("auto", "squared", "weighted")
#: kopf's weight of each parent term (the 9 of the coarser level's 3 x 3 square) against the
#: k x k square's 1: it keeps the coarse structure that the finest level's matches otherwise
#: drift from (docs/design.md#parent-terms).
KOPF_PARENT_WEIGHT = 4.0
#: chen-wang's candidate set size (Urs thesis §5.2.1, §6.3.3).
DEFAULT_CANDIDATES = 15
#: The principal components the coherence search's seeding passes compare (docs/design.md#coherence-search).
DEFAULT_SEED_COMPONENTS = 16
#: kopf's anchor slices: one about every 5 voxels of each constrained view's depth, as the
#: likelihood method's +in slices on categorical exemplars; without them the coarse levels
#: settle into mirror-symmetric blocks (docs/design.md#anchor-slices).
DEFAULT_INSERT_SPACING = 5.0


_SEARCH, _TUNE = "search", "search-tuning"
_KOPF = ("kopf",)


@documented
@dataclass(frozen=True)
class SearchParams:
    """Every parameter of a fixed-neighbourhood search method, validated on construction.

    ``method`` is ``"wl"`` (Wei-Levoy extended to 2D->3D, Urs thesis §5.2: each view's best
    match, averaged), ``"kopf"`` (Kopf et al.'s robust weights and histogram re-weighting;
    :mod:`clsolid.search.kopf`) or ``"chen-wang"`` (candidate sets, index and position
    histograms and a discrete solver that copies one exemplar pixel; :mod:`clsolid.search.chenwang`).
    Each field is declared once (:func:`clsolid.core.options.option`), with its check, its
    one-line help and its command-line group. Fields whose default is None are decided by the
    method, or by the exemplar (:meth:`for_exemplar`).
    """

    method: str = option("wl", "the search method", group=_SEARCH, check=Choice(METHODS), flag=None)
    neighborhood: int = neighborhood_option(7)
    scales: int = scales_option()
    iterations: int = option(10, "passes over every voxel at each level", group=_SEARCH, check=Int(1, 1000),
                             metavar="N")
    views: int | str = views_option()
    levels: int | None = levels_option()
    despeckle: bool = despeckle_option()
    inner: int = option(4, "wl: most searches per voxel and pass, the centre included after the first", group=_TUNE,
                        check=Int(1, 100), advanced=True)
    parent: bool = option(True, "match the coarser level's 3 x 3 square too (a multi-resolution neighbourhood)",
                          group=_TUNE, check=Flag(), advanced=True)
    parent_weight: float | None = option(None, "each parent term's weight against 1 for the square's", group=_TUNE,
                                         check=Real(0, lo_open=True), advanced=True,
                                         none=f"{KOPF_PARENT_WEIGHT:g} for kopf, 1 for the others")
    init: str = option("upsample", "a finer level starts from the coarser result up-sampled, or from noise",
                       group=_TUNE, check=Choice(INITS), advanced=True)
    rule: str = option("centres", "kopf: a voxel's value from each view's matched centre (the thesis) or from every "
                       "overlapping matched square (Kopf et al.)", group=_SEARCH, check=Choice(RULES), methods=_KOPF)
    order: str = option("sets", "conflict-free sets in parallel, or one voxel at a time in raster, random, Morton or "
                        "Hilbert order (small blocks)", group=_TUNE, check=Choice(ORDERS_ALL), advanced=True)
    causal: bool = option(False, "match the L-shaped causal neighbourhood instead of the full square", group=_TUNE,
                          check=Flag(), advanced=True)
    histogram: str = option("global", "kopf: re-weight by the whole block's histogram, or by the voxel's slice's",
                            group=_TUNE, check=Choice(HISTOGRAMS), advanced=True, methods=_KOPF)
    candidates: int = option(DEFAULT_CANDIDATES, "chen-wang: candidate set size per exemplar pixel, itself included",
                             group=_SEARCH, check=Int(1, MAX_K), metavar="K", methods=("chen-wang",))
    search: str | None = option(None, "each view's best match over every exemplar site (exact) or among the "
                                "k-coherence candidates of the neighbours' matches (faster)", group=_SEARCH,
                                check=Choice(SEARCHES), none="coherence for kopf, exact for wl and chen-wang")
    exact_passes: int | None = option(None, "coherence search: the first N passes of every level search every site, "
                                      "seeding the candidates after", group=_TUNE, check=Int(0, 1000), advanced=True,
                                      metavar="N", none="1 for kopf on a grey exemplar, else 0")
    seed_components: int | None = option(None, "coherence search: those passes compare sites on the N leading "
                                         "principal components (0: every term)", group=_TUNE, check=Int(0, 10000),
                                         advanced=True, metavar="N", none="16 for kopf, else 0")
    coherence_levels: int | None = option(None, "coherence search: how many of the finest levels search among the "
                                          "candidates (the coarser ones every site)", group=_TUNE, check=Int(1, 8),
                                          advanced=True, metavar="N", none="1 for kopf, every level for the others")
    index_histogram: bool | None = option(None, "coherence search: rank candidates by Chen & Wang's index histogram "
                                          "too", group=_TUNE, check=Flag(), advanced=True,
                                          none="on for wl, and for kopf on grey exemplars")
    specify: bool | None = option(None, "wl, kopf: after every pass, map the block's grey levels rank for rank onto "
                                  "the exemplar's histogram", group=_SEARCH, check=Flag(),
                                  none="on for kopf, off for wl")
    balance: float | None = option(None, "on categorical exemplars, kopf's vote of each set aims this far "
                                   "towards the exemplar's phase fractions (0: off, the thesis)", group=_SEARCH,
                                   check=Real(0, 1), metavar="B", none="1 for kopf, 0 for the others")
    insert_spacing: float | None = option(None, "anchor slices: an exemplar slice about every this many voxels of "
                                          "each view's depth (0: none, the thesis)", group=_TUNE, check=Real(0),
                                          advanced=True, none=f"{DEFAULT_INSERT_SPACING:g} for kopf, 0 for the others")
    distance: str = option("auto", "how the finest level's squares compare a categorical exemplar's phases: squared "
                           "grey-level differences, or weighted mismatches", group=_SEARCH, check=Choice(DISTANCES))

    #: The anchor slices' layout, count and make (read by :mod:`clsolid.core.slices`): always
    #: staggered, their number set by ``insert_spacing``, each slice one exemplar window, seams
    #: included where it wraps the exemplar (docs/design.md#anchor-slices).
    slice_layout = "staggered"
    insert_piece = 0
    seam_gap = 0

    def __post_init__(self) -> None:
        validate(self)
        method = self.method
        kopf = method == "kopf"
        if self.rule != "centres" and not kopf:
            raise InputError(f"rule={self.rule!r} is kopf's; method {method!r} has only 'centres'")
        if self.order != "sets" and self.rule == "overlap":
            raise InputError("rule='overlap' matches and updates the whole block at once: it has no visiting "
                             "order (use order='sets')")
        if self.histogram != "global" and not kopf:
            raise InputError(f"histogram={self.histogram!r} is kopf's re-weighting; method {method!r} has none")
        if self.search is None:
            object.__setattr__(self, "search", "coherence" if kopf else "exact")
        coherence = self.search == "coherence"
        if self.exact_passes and not coherence:
            raise InputError(f"exact_passes={self.exact_passes!r} seeds the coherence search: give "
                             "search='coherence' (the exact search searches every site in every pass)")
        if self.seed_components is not None and not coherence:
            raise InputError(f"seed_components={self.seed_components!r} is the coherence search's seeding "
                             "passes' (exact_passes): give search='coherence'")
        if coherence and self.seed_components is None:
            object.__setattr__(self, "seed_components", DEFAULT_SEED_COMPONENTS if kopf else 0)
        if not coherence and self.coherence_levels is not None:
            raise InputError(f"coherence_levels={self.coherence_levels!r} says which levels search among the "
                             "coherence candidates: give search='coherence'")
        if coherence and self.coherence_levels is None:
            object.__setattr__(self, "coherence_levels", 1 if kopf else self.scales)
        self._check_index_histogram()
        if self.candidates != DEFAULT_CANDIDATES and method != "chen-wang":
            raise InputError(f"candidates={self.candidates!r} is chen-wang's candidate set; method "
                             f"{method!r} has none")
        if self.causal and self.rule == "overlap":
            raise InputError("causal=True: Kopf's overlap rule needs every square whole (use rule='centres')")
        if self.specify is None:
            object.__setattr__(self, "specify", kopf)
        if self.specify and method == "chen-wang":
            raise InputError("specify=True maps blended grey levels; chen-wang copies exemplar pixels, it has none")
        if self.balance is None:
            object.__setattr__(self, "balance", 1.0 if kopf else 0.0)
        if self.balance and not kopf:
            raise InputError(f"balance={self.balance!r} is kopf's (and the likelihood method's); method "
                             f"{method!r} has none")
        object.__setattr__(self, "balance", float(self.balance))
        if self.insert_spacing is None:
            object.__setattr__(self, "insert_spacing", DEFAULT_INSERT_SPACING if kopf else 0.0)
        if 0 < self.insert_spacing < 1:
            raise InputError(f"insert_spacing={self.insert_spacing!r} must be 0 (no anchor slices) or a number "
                             ">= 1 (voxels between a view's anchor slices)")
        object.__setattr__(self, "insert_spacing", float(self.insert_spacing))
        if self.parent_weight is None:
            object.__setattr__(self, "parent_weight", KOPF_PARENT_WEIGHT if kopf else 1.0)
        object.__setattr__(self, "parent_weight", float(self.parent_weight))

    def _check_index_histogram(self) -> None:
        if self.index_histogram is None:
            return  # resolved per exemplar (for_exemplar)
        if self.index_histogram and self.search != "coherence":
            raise InputError("index_histogram=True ranks the coherence candidates: give search='coherence' (the "
                             "exact search takes the best match of every site)")
        if self.index_histogram and self.method == "chen-wang":
            raise InputError("index_histogram=True: chen-wang keeps its own index histogram, over its candidate sets")

    def for_exemplar(self, n_values: int, categorical: bool, colour: bool = False) -> "SearchParams":
        """These parameters with ``distance="auto"``, ``index_histogram=None`` and
        ``exact_passes=None`` resolved for an exemplar of *n_values* values, *categorical* if
        they are phases (:func:`clsolid.phases.is_categorical`). A *colour* exemplar's squares
        compare colours (:mod:`clsolid.search.palette`): no phase codes, no grey-level
        histogram specification, no seeding on principal components (its queries are
        gathered on the host), and not Kopf's overlap rule."""
        out, grey_kopf = self, self.method == "kopf" and not categorical and not colour
        if colour:
            if out.distance == "weighted":
                raise InputError("distance='weighted' compares phases by name; a colour exemplar's squares compare "
                                 "colours in CIELAB (leave distance out)")
            if out.rule == "overlap":
                raise InputError("rule='overlap' averages grey values; with a colour exemplar use rule='centres'")
            out = replace(out, distance="squared", specify=False,
                          seed_components=0 if out.search == "coherence" else None)
        if out.distance == "auto":
            phases = out.method == "kopf" and categorical and n_values >= 3
            out = replace(out, distance="weighted" if phases else "squared")
        elif out.distance == "weighted" and n_values < 2:  # one value: no mismatch to weigh, as squared
            out = replace(out, distance="squared")
        if out.index_histogram is None:
            measured_better = out.method == "wl" or grey_kopf
            out = replace(out, index_histogram=out.search == "coherence" and measured_better)
        if out.exact_passes is None:
            out = replace(out, exact_passes=1 if grey_kopf and out.search == "coherence" else 0)
        return out

    def keeps_exemplar_values(self, categorical: bool) -> bool:
        """Whether every voxel of the finished block is one of the exemplar's own values:
        ``chen-wang`` copies pixels, ``kopf`` votes among a *categorical* exemplar's phases, and
        ``specify`` maps a grey block onto the exemplar's histogram after every pass; otherwise
        the block holds means of exemplar values."""
        if self.method == "chen-wang":
            return True
        if categorical:
            return self.method == "kopf"
        return self.specify

    @property
    def view_names(self) -> tuple[str, ...]:
        return view_set(self.views)

    @property
    def insert_slices(self) -> int | None:
        """Anchor slices a view gets: none with ``insert_spacing=0``, else as the spacing says (None)."""
        return 0 if self.insert_spacing == 0 else None

    @classmethod
    def from_dict(cls, d: dict) -> "SearchParams":
        """The parameters recorded by :meth:`to_dict` (e.g. ``SynthesisResult.params``); other keys are ignored.
        Keys a record predates take the value it ran with, not today's default."""
        kept = {k: d[k] for k in cls.__dataclass_fields__ if k in d}
        kept.setdefault("despeckle", False)  # before the last step on phases there was none
        return cls(**kept)

    def to_dict(self) -> dict:
        return asdict(self)
