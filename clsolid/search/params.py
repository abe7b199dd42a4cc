"""Parameters of the fixed-neighbourhood search methods (thesis_spec §1), validated on construction."""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

from ..core.checks import int_in, one_of
from ..core.orders import ORDERS
from ..core.views import VIEW_SETS
from ..errors import InputError
from .match import MAX_K, check_side

#: The search methods.
METHODS = ("wl", "kopf", "chen-wang")
#: How a finer level starts (thesis_spec §1.3, ambiguous there): the coarser result
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
#: for kopf weighted on exemplars of 3 to MAX_PHASES values (on two phases the two agree), else
#: squared (measured worse for chen-wang, mixed for wl: docs/choices.md).
DISTANCES = ("auto", "squared", "weighted")
#: An exemplar with at most this many values is categorical: its voxels take a phase, never a blend.
MAX_PHASES = 8
#: kopf's weight of each parent term (the 9 of the coarser level's 3 x 3 square) against the
#: k x k square's 1: measured on the gallery (docs/choices.md), it keeps the coarse structure that
#: the finest level's matches otherwise drift from.
KOPF_PARENT_WEIGHT = 4.0
#: chen-wang's candidate set size (thesis §5.2.1, §6.3.3).
DEFAULT_CANDIDATES = 15
#: The principal components the coherence search's seeding passes compare (docs/choices.md).
DEFAULT_SEED_COMPONENTS = 16
#: kopf's anchor slices: one about every 5 voxels of each constrained view's depth, as the
#: likelihood method's +in slices on categorical exemplars (on the gallery, 64² -> 48³, seeds
#: 1-8, against one every 6: mirror correlations <= 0.1 in 106 runs of 120 against 99,
#: patches <= 0.3 in 80 of 88 against 77; against none, seed 1: mirror 10 -> 12 of 15,
#: autocorrelation 3 -> 7 of 13; docs/choices.md).
DEFAULT_INSERT_SPACING = 5.0


@dataclass(frozen=True)
class SearchParams:
    """Every parameter of a search method.

    Attributes
    ----------
    method : {"wl", "kopf", "chen-wang"}
        ``"wl"``: Wei-Levoy extended to 2D->3D (thesis_spec §1.6.1): each view's best
        match, averaged; repeated per voxel with the centre included until the matches
        stop changing. ``"kopf"``: each view's best match weighted by Kopf's robust
        weight and the grey-level histogram re-weighting (§1.6.2; ``clsolid.search.kopf``).
        ``"chen-wang"``: each view's choice among its best match's candidate set by the
        index histogram, Kopf's weights re-weighted by the position histogram, and the
        discrete solver that copies one exemplar pixel (§1.6.3; ``clsolid.search.chenwang``).
    neighborhood : int
        Side of the full square (odd; the thesis uses 5-11; default 7, ``ch5_np_common``).
    scales : int
        Gaussian pyramid levels of exemplar and volume (default 3; ``scales`` as for the
        likelihood method).
    iterations : int
        Passes over every voxel at each level (default 10).
    views : {2, 3}
        Constrained views: front + right, or all three.
    inner : int
        Most searches per voxel and pass for ``wl``'s inner repetition (the thesis: "about
        four"); 1 = a single search. ``kopf`` searches once.
    parent : bool
        Multi-resolution neighbourhood: the k x k square plus the 3 x 3 square of the
        coarser level (Wei & Levoy; thesis_spec §1.3). Ignored at the coarsest level.
    parent_weight : float or None
        The weight of each of the parent square's 9 terms in the distance, against 1 for
        each of the k x k square's (the sources are silent; a departure, docs/choices.md).
        None (default): :data:`KOPF_PARENT_WEIGHT` for ``kopf``, whose gallery scores it
        lifts, 1 (the published form) for the others (``chen-wang`` gains from 4 too,
        ``wl`` does not: docs/choices.md).
    init : {"upsample", "noise"}
        How a finer level starts: the coarser result, each voxel copied to its 2x2x2 block
        (default), or noise drawn from that level's exemplar pixels (Wei & Levoy's reading;
        from noise, every full-square neighbourhood is nearest to the flat patches of the
        majority phase, and a binary exemplar collapses to it). The coarsest level always
        starts from noise.
    rule : {"centres", "overlap"}
        ``kopf`` only: the thesis's rule (each view's matched centre value, set by set) or
        Kopf et al.'s (the whole block matched, then each voxel takes the weighted mean or
        vote of what every overlapping matched square proposes for it).
    order : {"sets", "lexicographic", "random", "morton", "hilbert"}
        How a pass visits the voxels: conflict-free sets updated in parallel, the sets in a
        seeded order (default; equal to a sequential pass in an order that visits set after
        set), or one voxel at a time along a raster, a seeded random permutation (drawn
        anew every pass), or the 3D Morton or Hilbert curve (thesis App. B; one search per
        voxel and view, so for small blocks).
    causal : bool
        Match the L-shaped causal neighbourhood (the rows above the centre and the centre
        row's left half, in each view's plane) instead of the full square (thesis_spec
        §1.2); the parent 3 x 3 stays whole. Meant for a raster ``order``, where it is what
        has already been visited; default False (full squares).
    histogram : {"global", "slice"}
        ``kopf`` only: re-weight each view's match by the whole block's grey-level
        histogram (Kopf's, default) or by that of the view's slice holding the voxel (the
        thesis's option).
    search : {"exact", "coherence"} or None
        How each view's best match is found: the exhaustive search over every exemplar
        site (the reference), or the accelerated one, among the k-coherence candidates
        that the voxel's 3 x 3 neighbours' matches propose (``clsolid.search.coherence``;
        exhaustive where they propose none). None (default): ``"coherence"`` for ``kopf``
        (on the gallery, 64² → 48³, seeds 1-4, it met every target in at least as many
        runs as the exact search, hrtem's lattice gone, at a quarter of the time;
        docs/choices.md), ``"exact"`` for ``wl`` and ``chen-wang`` (measured on one or two
        seeds only, and ``wl``'s phases drifted further with it).
    exact_passes : int or None
        ``search="coherence"`` only: the first ``exact_passes`` passes of every level that
        searches among the candidates search every exemplar site instead, and their matches
        seed the candidates of the passes after (0: only where no neighbour proposes a
        site). None (default): 1 for ``kopf`` on a grey exemplar (more than
        :data:`MAX_PHASES` values; on the gallery, 64² → 48³, seeds 1-8, patches <= 0.3 in
        24 of 24 runs against 16, hrtem's worst 0.20 against 0.64, at about twice the time
        of a 48³ volume), else 0 (``kopf``'s categorical exemplars gained nothing: C2 and
        autocorrelation a little worse); resolved by :meth:`for_exemplar`.
    seed_components : int or None
        ``search="coherence"`` only: the ``exact_passes`` compare each voxel with every site
        on this many leading principal components of the level's neighbourhoods, the site
        found there taking its distance on every term (:mod:`clsolid.search.projection`);
        0: on every term (the exhaustive search). Squared differences only: on phase codes
        (``distance="weighted"``) they always compare every term. None (default): 16 for
        ``kopf`` (on the gallery's grey exemplars, 64² → 48³, seeds 1-8, the same targets met
        as with every term, about 0.5 s faster at 64³; docs/choices.md), else 0.
    coherence_levels : int or None
        ``search="coherence"`` only: how many of the finest levels search among the
        candidates; the coarser levels search every exemplar site, and their matches seed
        the candidates of the first level that does. A coarser level costs about a 32nd of
        the next finer one's exhaustive search (an eighth of the voxels, a quarter of the
        sites), and the structure it settles is what the finer levels keep. None (default):
        1 for ``kopf`` (on the gallery, 64² → 48³, seeds 1 and 2: grass's and gravel's
        autocorrelation 0.23 and 0.25 against 0.34 and 0.36, mirror met in 28 runs of 30
        against 26; README, Gallery), ``scales`` (every level among the candidates, the
        coarsest level's first pass exhaustive) for the others (``chen-wang``'s brick lost
        its autocorrelation with 1: 0.57 against 0.32; ``wl`` not measured).
    index_histogram : bool or None
        ``search="coherence"``, ``wl`` and ``kopf``: rank each voxel's candidates by Chen &
        Wang's index histogram as well as by distance, ``(sqrt(distance) + eps) * (1 +
        max(0, use / uniform - 1))``, ``use`` the voxels (of every view) whose match is the
        candidate now and ``uniform`` views x voxels / sites (``chen-wang``'s index weight,
        here over the k-coherence candidates; ``clsolid.search.coherence``; a departure
        from the thesis's kopf). A part of the exemplar that fits a periodic state cannot
        take over the block: on the gallery it turned hrtem's lattice of stripes back into
        fringes (docs/choices.md). None (default): with the coherence search, True for
        ``wl`` and for ``kopf`` on a grey exemplar (more than :data:`MAX_PHASES` values),
        False for ``kopf`` on a categorical one (it copied more of the exemplar verbatim)
        and for ``chen-wang`` (it has its own); resolved by :meth:`for_exemplar`.
    specify : bool or None
        ``wl`` and ``kopf``: after every pass, map the block's grey levels rank for rank
        onto the level exemplar's histogram (``clsolid.search.specify``; a departure from
        the thesis). Levels whose exemplar is categorical (at most ``kopf.MAX_PHASES``
        values) are left alone: their voxels are phases, not means. None (default): True
        for ``kopf``, whose re-weighting exists to keep the histogram and alone does not
        (docs/choices.md), False for ``wl`` (the published form) and ``chen-wang`` (it
        copies exemplar pixels).
    balance : float or None
        ``kopf`` only, categorical exemplars: the weighted vote of every conflict-free set
        is biased so that the block's phase fractions move ``balance`` of the way to the
        exemplar's (1: exactly; 0: off, the thesis), the likelihood method's label-histogram
        balance (``clsolid.ml.balance``) applied to the views' votes
        (:func:`clsolid.search.kopf.balanced_set_vote`). None (default): 1 for ``kopf``, 0
        for the others. Kopf's overlap rule balances its vote always.
    candidates : int
        ``chen-wang`` only: the size of each exemplar site's candidate set, the site itself
        included (the thesis's k; tested with 1, 5, 15, 25; default 15).
    insert_spacing : float or None
        Anchor slices (a departure; docs/choices.md): about every ``insert_spacing`` voxels
        of each constrained view's depth, an exemplar slice at a seeded shift, the views'
        slices staggered (:mod:`clsolid.core.slices`, the likelihood method's ``+in``),
        written into every level but the finest and written again after every pass there,
        so that the coarse levels cannot settle into a block that is its own x<->z mirror
        image; the finest level starts those voxels from noise. 0: none (the thesis). None
        (default): 5 for ``kopf``, 0 for the others.
    distance : {"auto", "squared", "weighted"}
        How the finest level's squares compare the phases of a categorical exemplar:
        squared differences of their grey values (the thesis), or ``"weighted"``
        mismatches, phase a against phase b costing ``1/(2 f_a) + 1/(2 f_b)`` (f: the
        phases' fractions; the likelihood method's weighted distance, ``clsolid.search.codes``),
        so that which phase has which grey value does not matter. ``"auto"`` (default):
        for ``kopf`` weighted on exemplars of 3 to :data:`MAX_PHASES` values, squared
        otherwise (on two phases the two are the same) and for the other methods (where
        the gallery measured it worse or mixed); resolved by :meth:`for_exemplar`.
    """

    method: str = "wl"
    neighborhood: int = 7
    scales: int = 3
    iterations: int = 10
    views: int = 2
    inner: int = 4
    parent: bool = True
    parent_weight: float | None = None
    init: str = "upsample"
    rule: str = "centres"
    order: str = "sets"
    causal: bool = False
    histogram: str = "global"
    candidates: int = DEFAULT_CANDIDATES
    search: str | None = None
    exact_passes: int | None = None
    seed_components: int | None = None
    coherence_levels: int | None = None
    index_histogram: bool | None = None
    specify: bool | None = None
    balance: float | None = None
    insert_spacing: float | None = None
    distance: str = "auto"

    #: The anchor slices' layout, count and make (read by :mod:`clsolid.core.slices`): always
    #: staggered, their number set by ``insert_spacing``, each slice one exemplar window, seams
    #: included where it wraps the exemplar (the likelihood method's seam gap did not help kopf's
    #: brick or tissue, and cost a 24^3 lamellae block its mirror target: docs/choices.md).
    slice_layout = "staggered"
    insert_piece = 0
    seam_gap = 0

    def __post_init__(self) -> None:
        one_of("method", self.method, METHODS)
        check_side(self.neighborhood)
        int_in("scales", self.scales, 1, 8)
        int_in("iterations", self.iterations, 1, 1000)
        int_in("inner", self.inner, 1, 100)
        if self.views not in VIEW_SETS:
            raise InputError(f"views={self.views!r} must be 2 (front + right) or 3 (front + right + top)")
        one_of("init", self.init, INITS)
        one_of("rule", self.rule, RULES)
        if self.rule != "centres" and self.method != "kopf":
            raise InputError(f"rule={self.rule!r} is kopf's; method {self.method!r} has only 'centres'")
        one_of("order", self.order, ORDERS_ALL)
        if self.order != "sets" and self.rule == "overlap":
            raise InputError("rule='overlap' matches and updates the whole block at once: it has no visiting "
                             "order (use order='sets')")
        one_of("histogram", self.histogram, HISTOGRAMS)
        if self.histogram != "global" and self.method != "kopf":
            raise InputError(f"histogram={self.histogram!r} is kopf's re-weighting; method {self.method!r} has none")
        if self.search is None:
            object.__setattr__(self, "search", "coherence" if self.method == "kopf" else "exact")
        one_of("search", self.search, SEARCHES)
        if self.exact_passes is not None:
            int_in("exact_passes", self.exact_passes, 0, 1000)
        if self.exact_passes and self.search != "coherence":
            raise InputError(f"exact_passes={self.exact_passes!r} seeds the coherence search: give "
                             "search='coherence' (the exact search searches every site in every pass)")
        if self.seed_components is not None and self.search != "coherence":
            raise InputError(f"seed_components={self.seed_components!r} is the coherence search's seeding "
                             "passes' (exact_passes): give search='coherence'")
        if self.search == "coherence" and self.seed_components is None:  # measured for kopf only
            object.__setattr__(self, "seed_components", DEFAULT_SEED_COMPONENTS if self.method == "kopf" else 0)
        if self.seed_components is not None:
            int_in("seed_components", self.seed_components, 0, 10000)
        if self.search != "coherence":
            if self.coherence_levels is not None:
                raise InputError(f"coherence_levels={self.coherence_levels!r} says which levels search among the "
                                 "coherence candidates: give search='coherence'")
        else:
            if self.coherence_levels is None:
                object.__setattr__(self, "coherence_levels", 1 if self.method == "kopf" else self.scales)
            int_in("coherence_levels", self.coherence_levels, 1, 8)
        self._check_index_histogram()
        int_in("candidates", self.candidates, 1, MAX_K)
        if self.candidates != DEFAULT_CANDIDATES and self.method != "chen-wang":
            raise InputError(f"candidates={self.candidates!r} is chen-wang's candidate set; method "
                             f"{self.method!r} has none")
        if not isinstance(self.causal, bool):
            raise InputError(f"causal={self.causal!r} must be True or False")
        if self.causal and self.rule == "overlap":
            raise InputError("causal=True: Kopf's overlap rule needs every square whole (use rule='centres')")
        if self.specify is None:
            object.__setattr__(self, "specify", self.method == "kopf")
        if not isinstance(self.specify, bool):
            raise InputError(f"specify={self.specify!r} must be True, False or None (True for kopf)")
        if self.specify and self.method == "chen-wang":
            raise InputError("specify=True maps blended grey levels; chen-wang copies exemplar pixels, it has none")
        if self.balance is None:
            object.__setattr__(self, "balance", 1.0 if self.method == "kopf" else 0.0)
        if not (isinstance(self.balance, (int, float)) and not isinstance(self.balance, bool)
                and 0 <= self.balance <= 1):
            raise InputError(f"balance={self.balance!r} must be a number in [0, 1] (0 = off, 1 = the exemplar's "
                             "phase fractions exactly)")
        if self.balance and self.method != "kopf":
            raise InputError(f"balance={self.balance!r} is kopf's (and the likelihood method's); method "
                             f"{self.method!r} has none")
        object.__setattr__(self, "balance", float(self.balance))
        if self.insert_spacing is None:
            object.__setattr__(self, "insert_spacing", DEFAULT_INSERT_SPACING if self.method == "kopf" else 0.0)
        if (isinstance(self.insert_spacing, bool) or not isinstance(self.insert_spacing, (int, float))
                or not (self.insert_spacing == 0 or 1 <= self.insert_spacing < float("inf"))):
            raise InputError(f"insert_spacing={self.insert_spacing!r} must be 0 (no anchor slices) or a number "
                             ">= 1 (voxels between a view's anchor slices)")
        object.__setattr__(self, "insert_spacing", float(self.insert_spacing))
        if not isinstance(self.parent, bool):
            raise InputError(f"parent={self.parent!r} must be True or False")
        if self.parent_weight is None:
            object.__setattr__(self, "parent_weight", KOPF_PARENT_WEIGHT if self.method == "kopf" else 1.0)
        if (isinstance(self.parent_weight, bool) or not isinstance(self.parent_weight, (int, float))
                or not 0 < self.parent_weight < float("inf")):
            raise InputError(f"parent_weight={self.parent_weight!r} must be a positive number (each parent term's "
                             "weight against 1 for the square's)")
        object.__setattr__(self, "parent_weight", float(self.parent_weight))
        one_of("distance", self.distance, DISTANCES)

    def _check_index_histogram(self) -> None:
        if self.index_histogram is None:
            return  # resolved per exemplar (for_exemplar)
        if not isinstance(self.index_histogram, bool):
            raise InputError(f"index_histogram={self.index_histogram!r} must be True, False or None")
        if self.index_histogram and self.search != "coherence":
            raise InputError("index_histogram=True ranks the coherence candidates: give search='coherence' (the "
                             "exact search takes the best match of every site)")
        if self.index_histogram and self.method == "chen-wang":
            raise InputError("index_histogram=True: chen-wang keeps its own index histogram, over its candidate sets")

    def for_exemplar(self, n_values: int) -> "SearchParams":
        """These parameters with ``distance="auto"``, ``index_histogram=None`` and
        ``exact_passes=None`` resolved for an exemplar of *n_values* grey values."""
        out, grey_kopf = self, self.method == "kopf" and n_values > MAX_PHASES
        if out.distance == "auto":
            phases = out.method == "kopf" and 3 <= n_values <= MAX_PHASES
            out = replace(out, distance="weighted" if phases else "squared")
        if out.index_histogram is None:
            measured_better = out.method == "wl" or grey_kopf
            out = replace(out, index_histogram=out.search == "coherence" and measured_better)
        if out.exact_passes is None:
            out = replace(out, exact_passes=1 if grey_kopf and out.search == "coherence" else 0)
        return out

    def keeps_exemplar_values(self, n_values: int) -> bool:
        """Whether every voxel of the finished block is one of the exemplar's own values, for
        an exemplar of *n_values* values: ``chen-wang`` copies pixels, ``kopf`` votes among a
        categorical exemplar's phases, and ``specify`` maps a grey block onto the exemplar's
        histogram after every pass; otherwise the block holds means of exemplar values."""
        if self.method == "chen-wang":
            return True
        if n_values <= MAX_PHASES:
            return self.method == "kopf"
        return self.specify

    @property
    def view_names(self) -> tuple[str, ...]:
        return VIEW_SETS[self.views]

    @property
    def insert_slices(self) -> int | None:
        """Anchor slices a view gets: none with ``insert_spacing=0``, else as the spacing says (None)."""
        return 0 if self.insert_spacing == 0 else None

    @classmethod
    def from_dict(cls, d: dict) -> "SearchParams":
        """The parameters recorded by :meth:`to_dict` (e.g. ``SynthesisResult.params``); other keys are ignored."""
        return cls(**{k: d[k] for k in cls.__dataclass_fields__ if k in d})

    def to_dict(self) -> dict:
        return asdict(self)
