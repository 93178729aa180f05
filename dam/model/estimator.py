"""The Dominated Animeme Model (Chen et al. 2012), complete.

Training (Section V): modes per phone by affinity propagation
(:mod:`dam.model.modes`), then per channel the EM alternation (:mod:`dam.model.em`) of the
least-squares E-step (:mod:`dam.model.estep`) and the Gauss-Newton M-step
(:mod:`dam.model.mstep`). Synthesis (Section VI): one mode per segment by A* over
the animeme graph (:mod:`dam.model.astar`), then Eq. (2) (:mod:`dam.model.synthesis`).

Eq. (2) is by default the weighted average ``sum_j D_j A_j / sum_j D_j``
(``normalize=True``), for ``dam`` and ``dam-m0`` alike. The paper's text
concatenates DAMs "with the summation of their normalized values", while
Eq. (2) as printed is a plain sum; the plain sum counts both neighbours in
full around every phone boundary (dominance is 1 at t = 0 and t = 1 of
adjacent phones), and on the bundled VocalTractLab corpus the weighted
average is clearly ahead (``benchmarks/results/dam_accuracy_vtl.md``,
``dam_plainsum.md``; the README's DAM section explains why). ``normalize=False``
is the paper's literal Eq. (2), and :class:`DAMPaper` (``dam-paper``) the
paper's model in one word.

Loading a saved model and synthesizing imports numpy only.
"""

from __future__ import annotations

import numpy as np

from dam.base import Interval, Options, Synthesizer
from dam.corpus.data import Alignment, Corpus
from dam.model import animeme as _animeme
from dam.model.astar import BOUNDARY, ModeGraph, astar, free_path, mode_nll, smoothness_costs
from dam.model.dominance import dominance
from dam.model.synthesis import concatenate
from dam.modelfile import StateArray, StateNames, StateRanges

__all__ = ["DAM", "DAMM0", "DAMPaper"]


class DAM(Synthesizer):
    """Dominated Animeme Model: polynomial animemes under Gaussian-tailed dominance.

    Parameters
    ----------
    degree : int, default 4
        Degree M of the animeme polynomial (the paper's M = 4).
    normalize : bool, default True
        Eq. (2) as the Cohen-Massaro weighted average ``sum D A / sum D``
        (True, the default) or as the paper's printed plain sum (False). The
        paper's text concatenates DAMs "with the summation of their normalized
        values", while Eq. (2) as printed is a plain sum; the plain sum counts
        both neighbours in full around every phone boundary (dominance is 1 at
        t = 0 and t = 1 of adjacent phones); on the bundled VocalTractLab
        corpus the weighted average is clearly ahead. See Notes.
    extrapolate : {"polynomial", "hold", "trained"}, default "polynomial"
        The animeme outside [0, 1]: the polynomial itself (the paper), the
        value at the nearer edge, or the polynomial wherever training
        evaluated the mode (``support_``) and its value at the nearer edge of
        that range beyond it (``dam-paper``; see :class:`DAMPaper`).
    modes : {"affinity", "single"}, default "affinity"
        Modes per phone by affinity propagation, or one mode per phone.
    n_resample : int, default 20
        K: points on [0, 1] each occurrence is resampled to for clustering.
    mode_preference : "median", "min" or float, default "min"
        Affinity propagation preference (lower: fewer modes); see
        :func:`dam.modes.cluster_modes`. scikit-learn's "median" finds many
        small modes that do not generalise to held-out data.
    min_occurrences : int, default 10
        Phones with fewer training occurrences get one mode.
    min_mode_size : int, default 5
        Smaller clusters are merged into the nearest mode.
    ridge : float, default 1e-6
        Ridge on the (shifted-Legendre) coefficients: the objective per frame
        is the mean squared error plus ``ridge * ||a||^2``; keeps rare modes
        identifiable.
    eps : float, default 1e-8
        The epsilon of Eq. (1).
    sigma_init : float or "auto", default "auto"
        Starting sigma of every mode: a number (the paper: 1.0), or "auto":
        per channel the best common start among :data:`dam.em.SIGMA_GRID`
        (1.0 included) by the first E-step's error. With
        ``extrapolate="polynomial"`` the objective has local minima (the
        polynomial tails can stand in for the dominance) and from 1.0 the EM
        stalls in some of them on data generated with known parameters;
        with ``"hold"`` the start hardly matters.
    tol : float, default 1e-3
        EM stops when the objective improves by less than this fraction in
        an iteration.
    max_iter : int, default 30
        EM iterations at most (per channel). A channel that stops here with
        its last relative improvement still >= ``tol`` gets a
        :class:`dam.base.ConvergenceWarning` (and ``converged_`` False).
    gn_steps : int, default 1
        Gauss-Newton steps per M-step (by variable projection, so each
        step also re-solves the animemes: see :func:`dam.mstep.gauss_newton_sigma`).
    w_c, w_s : float, default 1000 and 1
        Weights of the data and smoothness terms of Eq. (10).
    context_smoothing : float, default 0.5
        Additive smoothing of the context counts behind ``E_c``.
    dominance_tol : float, default 1e-4
        Dominance below this is truncated to 0 (constant cost per phone).
    unknown_phone : {"error", "fallback"}, default "error"
        Unseen phones raise, or follow :func:`dam.phonetics.fallback_phone`.
    fit_modes : {"selected", "clustered"}, default "selected"
        The mode each training occurrence is fitted as: the one synthesis
        will choose for its context (the cheapest ``E_c``, from the context
        counts of the clustering), or the cluster it fell in. Clusters that
        context cannot predict leave animemes fitted for choices synthesis
        never makes; on the bundled corpus (jaw, lip, tongue tip) "selected"
        lowers held-out RMSE from 0.274 to 0.261 (weighted average) and from
        0.481 to 0.429 (plain sum): ``benchmarks/results/dam_plainsum.md``.
    random_state : int, default 0
        Seed of affinity propagation.
    verbose : int, default 0
        1: progress bar over channels; 2: also one line per channel.

    Attributes
    ----------
    coef_ : ndarray, shape (n_modes, degree + 1, n_channels)
        Shifted-Legendre coefficients of every mode's animeme
        (:meth:`modes_of` gives the paper's monomial ``a^0 .. a^M``).
    sigma_ : ndarray, shape (n_modes, n_channels)
        Dominance fall-off of every mode, per channel, in phone durations.
    support_ : ndarray, shape (n_modes, 2), or None
        Lowest and highest local time where rendering the training
        utterances (each occurrence in its training mode) evaluates every
        mode's animeme, [0, 1] included
        (:func:`dam.model.estep.animeme_support`); used by
        ``extrapolate="trained"``. None for a model given its parameters.
    mode_phone_ : list of str, length n_modes
        Phone of every (global) mode; a phone's modes are consecutive.
    phone_modes_ : dict str -> [first, count]
        Global mode range of every phone.
    mode_counts_ : ndarray of int, shape (n_modes,)
        Training occurrences of every mode.
    mode_shapes_ : ndarray, shape (n_modes, n_resample, n_channels)
        Mean resampled training occurrence of every mode (what clustering saw).
    single_mode_ : dict str -> str
        Phones that got one mode, and why (too few occurrences, no
        convergence, ``modes='single'``, or clustering found one).
    context_counts_ : dict
        Mode counts per phone in trigram/bigram/unigram contexts (``E_c``).
    loss_curve_ : list of ndarray
        Per channel, the EM objective (mean squared error plus ridge term per
        frame) after the first E-step and after every iteration.
    n_iter_ : ndarray of int, shape (n_channels,)
    converged_ : ndarray of bool, shape (n_channels,)
    channel_scale_ : ndarray, shape (n_channels,)
        Standard deviation of every channel in training.
    time_scale_ : float
        Median training phone duration (seconds), the time unit of ``E_s``.

    Notes
    -----
    Where the paper is vague, :mod:`dam.model.em`, :mod:`dam.model.mstep` and
    :mod:`dam.model.astar` say what was decided. Two empirical findings
    (``benchmarks/bench_dam_accuracy.py``):

    * Why ``normalize=True`` is the default: the paper's text concatenates
      DAMs "with the summation of their normalized values", while Eq. (2) as
      printed is a plain sum (``normalize=False``, one parameter away).
      With the plain sum the dominance is 1 on the closed
      interval [0, 1], so at a boundary both neighbours count in full; with
      constant animemes (``dam-m0``) the output doubles there. Where
      boundaries fall on frame times (the bundled ``vtl`` corpus) the
      weighted average is clearly ahead of the plain sum on held-out data
      (``benchmarks/results/dam_accuracy_vtl.md``). Before issue 11 the
      plain sum lost even to ``phone-mean``: the animemes were fitted with
      the clustering's mode labels, which synthesis cannot reproduce
      (``fit_modes``; ``benchmarks/results/dam_plainsum.md``).
    * With ``extrapolate="polynomial"`` the objective has local minima (the
      polynomial tails can stand in for the dominance); with ``"hold"``
      parameters generated with known values are recovered from any start.
    * With the weighted average, no other variant won on both bundled
      corpora (held-out RMSE, tiny / vtl, before ``fit_modes``): the defaults
      0.059 / 0.236; ``extrapolate="hold"`` 0.056 / 0.280; ``modes="single"``
      0.064 / 0.2365; ``mode_preference="median"`` 0.057 / 0.242. So the
      other defaults stay as they are.
    """

    name = "dam"
    _tags = {"deterministic": True, "numpy_runtime": True}
    _parameter_constraints = {
        "degree": [Interval(int, 0, None, closed="left")],
        "normalize": ["boolean"],
        "extrapolate": [Options(_animeme.EXTRAPOLATE)],
        "modes": [Options({"affinity", "single"})],
        "n_resample": [Interval(int, 2, None, closed="left")],
        "mode_preference": [Options({"median", "min"}), Interval(float, None, None)],
        "min_occurrences": [Interval(int, 1, None, closed="left")],
        "min_mode_size": [Interval(int, 1, None, closed="left")],
        **dict.fromkeys(
            ["ridge", "eps", "tol", "w_c", "w_s", "context_smoothing"], [Interval(float, 0, None, closed="left")]
        ),
        "sigma_init": [Options({"auto"}), Interval(float, 0, None, closed="neither")],
        "max_iter": [Interval(int, 0, None, closed="left")],
        "gn_steps": [Interval(int, 1, None, closed="left")],
        "dominance_tol": [Interval(float, 0, 1, closed="left")],
        "fit_modes": [Options({"clustered", "selected"})],
    }  # unknown_phone, random_state and verbose: as declared by Synthesizer
    # What a DAM model file holds, checked at save and load (dam.modelfile.check_state).
    _state_schema = {
        "channel_scale_": StateArray("float", ("n_channels",), low=np.finfo(float).tiny),
        "time_scale_": Interval(float, 0, None, closed="neither"),
        "mode_phone_": StateNames("n_modes", unique=False),
        "phone_modes_": StateRanges("n_modes", keys="n_phones"),
        "single_mode_": None,
        "mode_shapes_": StateArray("float", ("n_modes", None, "n_channels")),
        "mode_counts_": StateArray("int", ("n_modes",), low=0),
        "context_counts_": None,
        "coef_": StateArray("float", ("n_modes", None, "n_channels")),
        "sigma_": StateArray("float", ("n_modes", "n_channels"), low=0),
        # None: given parameters (from_parameters) or a file from before it was learned
        "support_": StateArray("float", ("n_modes", 2), optional=True),
        "loss_curve_": None,
        "n_iter_": StateArray("int", ("n_channels",), low=0),
        "converged_": StateArray("bool", ("n_channels",)),
    }

    def __init__(
        self,
        *,
        degree: int = 4,
        normalize: bool = True,
        extrapolate: str = "polynomial",
        modes: str = "affinity",
        n_resample: int = 20,
        mode_preference="min",
        min_occurrences: int = 10,
        min_mode_size: int = 5,
        ridge: float = 1e-6,
        eps: float = 1e-8,
        sigma_init="auto",
        tol: float = 1e-3,
        max_iter: int = 30,
        gn_steps: int = 1,
        w_c: float = 1000.0,
        w_s: float = 1.0,
        context_smoothing: float = 0.5,
        dominance_tol: float = 1e-4,
        unknown_phone: str = "error",
        fit_modes: str = "selected",
        random_state=0,
        verbose: int = 0,
    ):
        self.degree = degree
        self.normalize = normalize
        self.extrapolate = extrapolate
        self.modes = modes
        self.n_resample = n_resample
        self.mode_preference = mode_preference
        self.min_occurrences = min_occurrences
        self.min_mode_size = min_mode_size
        self.ridge = ridge
        self.eps = eps
        self.sigma_init = sigma_init
        self.tol = tol
        self.max_iter = max_iter
        self.gn_steps = gn_steps
        self.w_c = w_c
        self.w_s = w_s
        self.context_smoothing = context_smoothing
        self.dominance_tol = dominance_tol
        self.unknown_phone = unknown_phone
        self.random_state = random_state
        self.verbose = verbose
        self.fit_modes = fit_modes

    @classmethod
    def get_test_params(cls) -> list[dict]:
        return [
            {"degree": 2, "max_iter": 3, "n_resample": 8},
            {
                "degree": 1,
                "modes": "single",
                "normalize": False,
                "extrapolate": "hold",
                "max_iter": 2,
                "unknown_phone": "fallback",
            },
        ]

    # -- training ----------------------------------------------------------
    def _fit(self, corpus: Corpus) -> None:
        import scipy.linalg  # noqa: F401  (loaded first, so threadpoolctl sees its BLAS)
        from threadpoolctl import threadpool_limits

        # The linear algebra here is small (hundreds of unknowns); a
        # multithreaded BLAS on a busy machine makes it hundreds of times slower.
        with threadpool_limits(limits=1, user_api="blas"):
            self._fit_em(corpus)

    def _fit_em(self, corpus: Corpus) -> None:
        from dam.model.em import fit_em
        from dam.model.estep import Occurrences, animeme_support
        from dam.model.modes import cluster_modes, resample_occurrences

        Y = np.concatenate(corpus.trajectories)
        scale = Y.std(axis=0)
        self.channel_scale_ = np.where(scale > 1e-12, scale, 1.0)
        durations = np.concatenate([a.durations for a in corpus.alignments])
        self.time_scale_ = float(np.median(durations))

        # Section V-A: resample every occurrence, cluster each phone's occurrences.
        shapes = [
            resample_occurrences(u.trajectory, u.frame_rate, u.alignment.starts, u.alignment.ends, self.n_resample)
            for u in corpus
        ]
        where: dict[str, list] = {}
        for ui, u in enumerate(corpus):
            for j, p in enumerate(u.alignment.labels):
                where.setdefault(p, []).append((ui, j))
        local = [np.zeros(len(u.alignment), dtype=int) for u in corpus]
        self.phone_modes_, self.single_mode_ = {}, {}
        mode_phone, mode_shapes, mode_counts = [], [], []
        for p in sorted(where):
            occ = np.array([shapes[ui][j] for ui, j in where[p]])  # (n_occ, K, C)
            feats = (occ / self.channel_scale_).reshape(len(occ), -1)
            res = cluster_modes(
                feats,
                method=self.modes,
                min_occurrences=self.min_occurrences,
                min_mode_size=self.min_mode_size,
                preference=self.mode_preference,
                random_state=self.random_state,
            )
            if res.n_modes == 1:
                self.single_mode_[p] = res.reason
            self.phone_modes_[p] = [len(mode_phone), res.n_modes]
            for g in range(res.n_modes):
                members = res.labels == g
                mode_phone.append(p)
                mode_shapes.append(occ[members].mean(axis=0))
                mode_counts.append(int(members.sum()))
            for (ui, j), g in zip(where[p], res.labels):
                local[ui][j] = g
        self.mode_phone_ = mode_phone
        self.mode_shapes_ = np.array(mode_shapes)
        self.mode_counts_ = np.array(mode_counts, dtype=int)
        glob = [
            np.array([self.phone_modes_[p][0] + g for p, g in zip(u.alignment.labels, loc)], dtype=int)
            for u, loc in zip(corpus, local)
        ]
        self.context_counts_ = _context_counts(corpus, local, self.phone_modes_)
        if self.fit_modes == "selected":
            # fit every occurrence with the mode synthesis will choose for its context (E_c), not
            # the cluster it fell in: the animemes are then fitted for the modes they will be used as
            graph = ModeGraph(self.phone_modes_, self.context_counts_)
            glob = []
            for u in corpus:
                pid, first, count = graph.layers(u.alignment.labels)
                glob.append(first + np.argmin(graph.node_costs(pid, count, float(self.context_smoothing))[0], axis=1))

        # Sections V-B..D: EM per channel.
        occ = Occurrences.from_corpus(
            corpus,
            glob,
            len(mode_phone),
            degree=int(self.degree),
            normalize=bool(self.normalize),
            extrapolate=self.extrapolate,
            eps=float(self.eps),
            tol=float(self.dominance_tol),
        )
        coef, sigma, curves, n_iter, converged = fit_em(
            occ,
            Y,
            sigma_init=self.sigma_init,
            ridge=self.ridge,
            tol=self.tol,
            max_iter=int(self.max_iter),
            gn_steps=int(self.gn_steps),
            verbose=self.verbose,
            channels=list(corpus.channels),
            weights=None
            if all(m is None for m in corpus.masks)
            else np.concatenate(
                [np.ones(u.trajectory.shape) if u.mask is None else u.mask.astype(float) for u in corpus]
            ),
        )
        self.coef_, self.sigma_ = coef, sigma
        self.support_ = animeme_support(occ, sigma)
        self.loss_curve_, self.n_iter_, self.converged_ = curves, n_iter, converged
        self._build_graph()

    @classmethod
    def from_parameters(
        cls,
        phones: dict,
        *,
        frame_rate: float,
        channels,
        basis: str = "monomial",
        context_counts: dict | None = None,
        channel_scale=None,
        time_scale: float = 0.1,
        **params,
    ) -> DAM:
        """A DAM with given animemes and sigmas, as if fitted (for synthetic data and teaching).

        Parameters
        ----------
        phones : dict str -> (coef, sigma)
            ``coef`` of shape (n_modes, degree + 1, n_channels) (or
            (degree + 1, n_channels) for one mode); ``sigma`` of shape
            (n_modes, n_channels) (or (n_channels,), or a float).
        frame_rate : float
        channels : sequence of str
        basis : {"monomial", "legendre"}, default "monomial"
            Whether ``coef`` holds the paper's ``a^0 .. a^M`` or shifted-Legendre coefficients.
        context_counts : dict, optional
            As ``context_counts_``; default: no context (uniform ``E_c``).
        channel_scale : array-like, optional
            Default ones.
        time_scale : float, default 0.1
        **params
            Hyperparameters (``degree`` is taken from the coefficients).
        """
        channels = list(channels)
        C = len(channels)
        coefs, sigmas, mode_phone, phone_modes = [], [], [], {}
        degree = None
        for p in sorted(phones):
            coef, sigma = phones[p]
            coef = np.asarray(coef, dtype=float)
            if coef.ndim == 2:
                coef = coef[None]
            G = coef.shape[0]
            if coef.shape[2] != C:
                raise ValueError(f"phone {p!r}: coef has {coef.shape[2]} channels, expected {C}")
            if degree is None:
                degree = coef.shape[1] - 1
            elif coef.shape[1] - 1 != degree:
                raise ValueError(f"phone {p!r}: degree {coef.shape[1] - 1} differs from {degree}")
            if basis == "monomial":
                coef = np.moveaxis(_animeme.monomial_to_legendre(np.moveaxis(coef, 1, 0)), 0, 1)
            elif basis != "legendre":
                raise ValueError(f"parameter 'basis' is {basis!r}; use 'monomial' or 'legendre'")
            sigma = np.broadcast_to(np.asarray(sigma, dtype=float).reshape(G if np.ndim(sigma) == 2 else 1, -1), (G, C))
            phone_modes[p] = [len(mode_phone), G]
            mode_phone += [p] * G
            coefs.append(coef)
            sigmas.append(sigma)
        model = cls(**{**params, "degree": degree})
        model.frame_rate_ = float(frame_rate)
        model.channels_ = channels
        model.phone_counts_ = {p: 1 for p in sorted(phones)}
        model.coef_ = np.concatenate(coefs)
        model.sigma_ = np.concatenate(sigmas).copy()
        model.support_ = None  # no training: the polynomial on the whole time line
        model.mode_phone_ = mode_phone
        model.phone_modes_ = phone_modes
        model.mode_counts_ = np.zeros(len(mode_phone), dtype=int)
        model.mode_shapes_ = np.zeros((len(mode_phone), 0, C))
        model.single_mode_ = {p: "given" for p, (_, G) in phone_modes.items() if G == 1}
        model.context_counts_ = dict(context_counts or {})
        model.loss_curve_, model.n_iter_, model.converged_ = [], np.zeros(C, dtype=int), np.ones(C, dtype=bool)
        model.channel_scale_ = np.ones(C) if channel_scale is None else np.asarray(channel_scale, dtype=float)
        model.time_scale_ = float(time_scale)
        model._build_graph()
        return model

    # -- synthesis -----------------------------------------------------------
    def _build_graph(self) -> None:
        """The mode graph (:class:`dam.model.astar.ModeGraph`), once per fit and load.

        Kept under a private name (never saved, not learned state): ``predict``
        only reads it, so it leaves the model unchanged.
        """
        self._mode_graph = ModeGraph(self.phone_modes_, self.context_counts_)

    def _set_state(self, state: dict) -> None:
        super()._set_state({"support_": None, **state})
        self._build_graph()

    def _graph_of(self) -> ModeGraph:
        graph = self.__dict__.get("_mode_graph")
        if graph is None:  # state set by hand (not by fit, load or from_parameters)
            graph = ModeGraph(self.phone_modes_, self.context_counts_)
        return graph

    def _layers(self, alignment: Alignment, graph: ModeGraph):
        """Labels after any fallback, and per segment: phone index, first global mode, mode count."""
        labels = self._known_labels(alignment, self.unknown_phone)
        return (labels, *graph.layers(labels))

    def _edge_costs(self, graph, first, count, durations, joints) -> np.ndarray:
        return _weighted(
            self.w_s,
            graph.edge_costs(first, count, durations, self.coef_, joints, self.time_scale_, self.channel_scale_),
        )

    def _graph(self, labels, durations):
        """Node costs ``w_c E_c`` (n_seg, G_max), edge costs ``w_s E_s`` (n_seg - 1, G_max, G_max)
        (missing modes +inf, see :func:`dam.model.astar.pad_layers`) and the back-off level of every ``E_c``."""
        graph = self._graph_of()
        pid, first, count = graph.layers(labels)
        nll, level = graph.node_costs(pid, count, float(self.context_smoothing))
        ecost = self._edge_costs(graph, first, count, durations, np.arange(len(labels) - 1))
        return _weighted(self.w_c, nll), ecost, [ModeGraph.LEVELS[v] for v in level]

    def _choose(self, alignment: Alignment, method: str = "dp"):
        """Section VI: global mode and first global mode of every segment, and the node costs.

        ``method="dp"`` (synthesis): the chain split at single-mode segments and
        every block of multi-mode segments solved exactly by dynamic programming,
        all blocks together (:func:`dam.model.astar.free_path`); ``"astar"``: the
        paper's A* on the whole graph. Both return the cheapest path (the tests
        prove them equal). A one-phone alignment needs no search: its cheapest
        ``E_c``, read from the context counts (:func:`dam.model.astar.mode_nll`).
        """
        graph = self._graph_of()
        labels, pid, first, count = self._layers(alignment, graph)
        free = count > 1
        if not free.any():  # nothing to choose
            return first, first, np.zeros((len(pid), 1))
        if len(pid) == 1:  # one phone (e.g. streaming): its cheapest E_c, read from the counts directly
            nll, _ = mode_nll(
                self.context_counts_, labels[0], BOUNDARY, BOUNDARY, int(count[0]), self.context_smoothing
            )
            nodes = _weighted(self.w_c, nll[None, :])
            return first + np.argmin(nodes[0]), first, nodes
        nll, _ = graph.node_costs(pid, count, float(self.context_smoothing))
        nodes = _weighted(self.w_c, nll)
        # edges only where a path can differ: at the joints of multi-mode segments
        joints = np.flatnonzero(free[:-1] | free[1:])
        edges = np.zeros((len(pid) - 1, nodes.shape[1], nodes.shape[1]))
        edges[joints] = self._edge_costs(graph, first, count, alignment.durations, joints)
        if method == "astar":
            return first + np.asarray(astar(nodes, edges)[0], dtype=np.int64), first, nodes
        return first + free_path(nodes, edges, free), first, nodes

    def select_modes(self, alignment: Alignment, method: str = "dp"):
        """Mode of every segment (Section VI).

        Parameters
        ----------
        alignment : Alignment
        method : {"dp", "astar"}, default "dp"
            The exact dynamic program synthesis uses, or the paper's A*; the
            same cheapest path (ties aside).

        Returns
        -------
        modes : ndarray of int, shape (n_segments,)
            Global mode indices (rows of ``coef_``).
        cost : float
            Total cost ``E = sum w_c E_c + sum w_s E_s`` of the chosen path.
        """
        self._check_fitted()
        if method not in ("dp", "astar"):
            raise ValueError(f"parameter 'method' is {method!r}; use 'dp' or 'astar'")
        glob, first, nodes = self._choose(alignment, method)
        cost = float(nodes[np.arange(len(glob)), glob - first].sum())
        if len(glob) > 1:
            edges, d = _animeme.boundary_derivatives(self.coef_[glob], order=2), alignment.durations
            es = smoothness_costs(
                edges[:-1, 1][:, None], edges[1:, 0][:, None], d[:-1], d[1:], self.time_scale_, self.channel_scale_
            )
            cost += float(self.w_s * es.sum())
        return glob, cost

    def synthesize(self, alignment: Alignment, modes=None, n_frames: int | None = None) -> np.ndarray:
        """Eq. (2) for an alignment, with chosen (Section VI) or given modes.

        Parameters
        ----------
        alignment : Alignment
        modes : sequence of int, optional
            Local mode (0 .. n_modes of the phone - 1) of every segment; default
            the cheapest path (:meth:`select_modes`).
        n_frames : int, optional
            Default ``alignment.n_frames(frame_rate_)``.

        Returns
        -------
        ndarray, shape (n_frames, n_channels)
        """
        self._check_fitted()
        n = alignment.n_frames(self.frame_rate_) if n_frames is None else n_frames
        if modes is None:
            glob = self._choose(alignment)[0]
        else:
            labels, _, first, counts = self._layers(alignment, self._graph_of())
            modes = np.asarray(modes, dtype=int)
            if modes.shape != (len(labels),):
                raise ValueError(f"modes has shape {modes.shape}, expected ({len(labels)},)")
            if np.any((modes < 0) | (modes >= counts)):
                j = int(np.flatnonzero((modes < 0) | (modes >= counts))[0])
                raise ValueError(f"segment {j} ({labels[j]!r}): mode {modes[j]} out of range 0..{counts[j] - 1}")
            glob = first + modes
        return concatenate(
            alignment.starts,
            alignment.ends,
            self.coef_[glob],
            self.sigma_[glob],
            self.frame_rate_,
            n,
            normalize=bool(self.normalize),
            extrapolate=self.extrapolate,
            eps=float(self.eps),
            tol=float(self.dominance_tol),
            support=self._support_of(glob),
        )

    def _support_of(self, glob):
        """``support_`` of the modes ``glob`` when ``extrapolate="trained"`` uses it, else None."""
        support = self.__dict__.get("support_")
        return None if self.extrapolate != "trained" or support is None else support[glob]

    def _predict(self, alignment: Alignment, n_frames: int) -> np.ndarray:
        return self.synthesize(alignment, n_frames=n_frames)

    # -- inspection ----------------------------------------------------------
    def modes_of(self, phone: str) -> dict:
        """Everything learned about one phone.

        Returns
        -------
        dict with keys
            ``n_modes``; ``counts`` (n_modes,); ``sigma`` (n_modes, n_channels);
            ``coef_legendre`` and ``coef_monomial`` (n_modes, degree + 1,
            n_channels), the latter the paper's ``a^0 .. a^M``; ``single_mode``
            (why the phone has one mode, or "").
        """
        self._check_fitted()
        if phone not in self.phone_modes_:
            raise KeyError(f"phone {phone!r} not in the model; phones: {' '.join(self.phone_modes_)}")
        first, G = self.phone_modes_[phone]
        sl = slice(first, first + G)
        leg = self.coef_[sl]
        return {
            "n_modes": G,
            "counts": self.mode_counts_[sl].copy(),
            "sigma": self.sigma_[sl].copy(),
            "coef_legendre": leg.copy(),
            "coef_monomial": np.moveaxis(_animeme.legendre_to_monomial(np.moveaxis(leg, 1, 0)), 0, 1),
            "single_mode": self.single_mode_.get(phone, ""),
        }

    def _mode_row(self, phone: str, mode: int) -> int:
        self._check_fitted()
        if phone not in self.phone_modes_:
            raise KeyError(f"phone {phone!r} not in the model; phones: {' '.join(self.phone_modes_)}")
        first, G = self.phone_modes_[phone]
        if not 0 <= mode < G:
            raise ValueError(f"phone {phone!r} has modes 0..{G - 1}, not {mode}")
        return first + int(mode)

    def animeme_curve(self, phone: str, mode: int, t) -> np.ndarray:
        """``A(t)`` of one mode at local times ``t``, shape (len(t), n_channels)."""
        g = self._mode_row(phone, mode)
        support = self._support_of(g)
        return _animeme.evaluate(self.coef_[g], t, self.extrapolate, None if support is None else tuple(support))

    def dominance_curve(self, phone: str, mode: int, t) -> np.ndarray:
        """``D(t)`` of one mode at local times ``t``, shape (len(t), n_channels)."""
        return dominance(
            np.asarray(t, dtype=float)[:, None],
            self.sigma_[self._mode_row(phone, mode)],
            float(self.eps),
            float(self.dominance_tol),
        )

    def explain(self, alignment: Alignment) -> list[dict]:
        """The chosen mode of every segment and what it cost.

        Returns
        -------
        list of dict, one per segment
            ``phone`` (after any fallback), ``label`` (as given), ``start``,
            ``end``, ``mode`` (local), ``n_modes``, ``context`` (which back-off
            level answered ``E_c``), ``E_c``, ``E_s`` (to the previous segment;
            0 for the first), ``cost`` (``w_c E_c + w_s E_s``), ``total``
            (cumulative).
        """
        self._check_fitted()
        labels = self._known_labels(alignment, self.unknown_phone)
        nodes, ecosts, levels = self._graph(labels, alignment.durations)
        glob, _ = self.select_modes(alignment)
        local = glob - np.array([self.phone_modes_[p][0] for p in labels])
        out, total = [], 0.0
        for j, p in enumerate(labels):
            g = int(local[j])
            ec = float(nodes[j][g]) / self.w_c if self.w_c else 0.0
            es = float(ecosts[j - 1][int(local[j - 1]), g]) / self.w_s if (j and self.w_s) else 0.0
            cost = self.w_c * ec + self.w_s * es
            total += cost
            out.append(
                {
                    "phone": p,
                    "label": alignment.labels[j],
                    "start": float(alignment.starts[j]),
                    "end": float(alignment.ends[j]),
                    "mode": g,
                    "n_modes": self.phone_modes_[p][1],
                    "context": levels[j],
                    "E_c": ec,
                    "E_s": es,
                    "cost": cost,
                    "total": total,
                }
            )
        return out


class DAMM0(DAM):
    """The DAM with M = 0: the Cohen-Massaro model as Chen et al. (2012) built their comparison.

    "The Cohen-Massaro model is implemented using our DAM by setting M = 0"
    (Section VII): constant animemes (targets) under the same dominance; every
    other choice, modes included, is the DAM's. Parameters as :class:`DAM`,
    with ``degree=0``.
    """

    name = "dam-m0"
    _preset = {"degree": 0}

    @classmethod
    def get_test_params(cls) -> list[dict]:
        return [
            {"max_iter": 3, "n_resample": 8},
            {"modes": "single", "normalize": False, "max_iter": 2, "unknown_phone": "fallback"},
        ]


class DAMPaper(DAM):
    """The paper's literal DAM, in one word: Eq. (2) as printed (the plain sum), M = 4.

    Chen et al. (2012) as written: ``C*(t) = sum_j D_j(t_j) A_j(t_j)`` with
    quartic animemes ``A(t) = sum_m a^m t^m`` on the time line
    (``normalize=False, degree=4``); every other choice is the DAM's.
    ``dam-m0`` with ``normalize=False`` is its M = 0 row. Why the default
    ``dam`` uses the weighted average instead, with numbers: the README's DAM
    section.

    One choice the paper does not make: outside the local times where
    training evaluated a mode (``support_``), the animeme is held at its
    value at the edge of that range (``extrapolate="trained"``) instead of
    following the quartic that no data constrained there. The paper defines
    ``C(t) = D(t) A(t)`` for all t and fits ``A`` by Eq. (4) on the training
    frames; wherever those frames reach, the two agree, so rendering the
    training utterances is unchanged. Where they do not (a mode fitted only
    as an utterance's first silence, never preceded by a frame, later chosen
    inside an utterance) the quartic's left tail had no data: on ``tiny`` it
    reached -4.0 on the lip aperture 1.2 durations before the silence and
    drove a frame to -0.36 where the data span 0.02-0.83 (issue 11,
    ``tests/model/test_short_segments.py``). ``extrapolate="polynomial"``
    restores the whole-line quartic.
    """

    name = "dam-paper"
    _preset = {"normalize": False, "degree": 4, "extrapolate": "trained"}


def _weighted(w: float, cost: np.ndarray) -> np.ndarray:
    """``w * cost`` with a missing mode's +inf kept +inf (also for ``w = 0``, an ablation)."""
    if w > 0:  # (w is >= 0)
        return float(w) * cost
    return np.where(np.isinf(cost), np.inf, 0.0)


def _context_counts(corpus, local, phone_modes) -> dict:
    from dam.model.astar import context_counts

    return context_counts([u.alignment.labels for u in corpus], local, {p: G for p, (_, G) in phone_modes.items()})
