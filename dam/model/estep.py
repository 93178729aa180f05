"""The E-step of Chen et al. (2012), Eqs. (3)-(7): animeme coefficients by least squares.

With every dominance fixed, the training signal is linear in the animeme
coefficients. Row ``i`` of the design matrix (one frame of the corpus, all
utterances stacked) holds, in the columns of mode ``b``,
``sum_h D_{b_h}(t_{b_h}^i) P_m(2 t_{b_h}^i - 1)`` summed over the occurrences
``h`` of that mode (Eq. 7: repeated occurrences share columns). Truncated
dominance makes it sparse (:func:`design_matrix` builds it as a scipy CSR
matrix). The normal equations (Eq. 5) with a small ridge
``(X^T X + lambda I) a = X^T y`` have only ``n_modes * (M + 1)`` unknowns, so
``X^T X`` is accumulated from the same entries utterance by utterance
(:func:`gram`: a frame only meets its own utterance's phones) and solved
densely by Cholesky. ``benchmarks/bench_dam.py`` measures both ways.

With ``normalize=True`` (weighted average) every row is divided by the
frame's summed dominance, which keeps the problem linear.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from dam.model.animeme import basis, trained_support
from dam.model.dominance import dominance
from dam.model.synthesis import segment_windows

__all__ = [
    "Occurrences",
    "pairs",
    "design_values",
    "design_matrix",
    "gram",
    "normal_equations",
    "solve_normal_equations",
    "fitted_values",
    "animeme_support",
]


@dataclass
class Occurrences:
    """Every phone occurrence of a training corpus, utterances stacked.

    Attributes
    ----------
    starts, ends : ndarray, shape (n_occ,)
        Times in seconds within the occurrence's utterance.
    n_frames : ndarray of int, shape (n_occ,)
        Frames of the occurrence's utterance.
    offset : ndarray of int, shape (n_occ,)
        Row of the utterance's first frame in the stacked corpus.
    mode : ndarray of int, shape (n_occ,)
        Global mode index of the occurrence.
    n_rows : int
        Frames in the corpus.
    n_modes : int
    frame_rate : float
    degree : int
    normalize : bool
    extrapolate : str
    eps, tol : float
    """

    starts: np.ndarray
    ends: np.ndarray
    n_frames: np.ndarray
    offset: np.ndarray
    mode: np.ndarray
    n_rows: int
    n_modes: int
    frame_rate: float
    degree: int = 4
    normalize: bool = False
    extrapolate: str = "polynomial"
    eps: float = 1e-8
    tol: float = 1e-4

    @classmethod
    def from_corpus(cls, corpus, mode_of_segment, n_modes: int, **kw) -> Occurrences:
        """``mode_of_segment``: one int array per utterance, the global mode of each segment."""
        starts, ends, nf, off, mode = [], [], [], [], []
        row = 0
        for u, m in zip(corpus, mode_of_segment):
            a = u.alignment
            starts.append(a.starts)
            ends.append(a.ends)
            nf.append(np.full(len(a), u.n_frames))
            off.append(np.full(len(a), row))
            mode.append(np.asarray(m, dtype=int))
            row += u.n_frames
        cat = np.concatenate
        return cls(
            cat(starts),
            cat(ends),
            cat(nf).astype(np.int64),
            cat(off).astype(np.int64),
            cat(mode),
            row,
            n_modes,
            corpus.frame_rate,
            **kw,
        )

    @property
    def n_coef(self) -> int:
        return self.n_modes * (self.degree + 1)

    @cached_property
    def utterance_bounds(self) -> np.ndarray:
        """First occurrence of every utterance, and ``n_occ`` at the end, shape (n_utt + 1,)."""
        first = np.flatnonzero(np.r_[True, self.offset[1:] != self.offset[:-1]])
        return np.r_[first, len(self.offset)]

    @cached_property
    def local_modes(self):
        """Per utterance the modes it uses; per occurrence its index among them.

        Returns
        -------
        modes : list of ndarray of int, one per utterance
        local : ndarray of int, shape (n_occ,)
        utt : ndarray of int, shape (n_occ,)
            Utterance of every occurrence.
        """
        b = self.utterance_bounds
        modes, local = [], np.empty(len(self.mode), dtype=np.int64)
        for _u, (o0, o1) in enumerate(zip(b[:-1], b[1:])):
            m, inv = np.unique(self.mode[o0:o1], return_inverse=True)
            modes.append(m)
            local[o0:o1] = inv
        utt = np.repeat(np.arange(len(b) - 1), np.diff(b))
        return modes, local, utt


def pairs(occ: Occurrences, sigma: np.ndarray):
    """(occurrence, row, local time, dominance) for every frame a truncated dominance reaches.

    Parameters
    ----------
    sigma : ndarray, shape (n_modes,)
        One channel's sigma of every mode.

    Returns
    -------
    k : ndarray of int, shape (n_pairs,)
        Occurrence index.
    row : ndarray of int, shape (n_pairs,)
    t : ndarray, shape (n_pairs,)
    D : ndarray, shape (n_pairs,)
    """
    s_occ = sigma[occ.mode]
    k, frame, t = segment_windows(occ.starts, occ.ends, s_occ, occ.frame_rate, occ.n_frames, occ.eps, occ.tol)
    D = dominance(t, s_occ[k], occ.eps, occ.tol)
    keep = D > 0.0
    k, frame, t, D = k[keep], frame[keep], t[keep], D[keep]
    return k, occ.offset[k] + frame, t, D


def design_values(occ: Occurrences, pr):
    """Entries of the design matrix at every pair: values and columns, shape (n_pairs, degree + 1)."""
    k, row, t, D = pr
    M1 = occ.degree + 1
    vals = D[:, None] * basis(t, occ.degree, occ.extrapolate)
    if occ.normalize:
        S = np.bincount(row, weights=D, minlength=occ.n_rows)
        vals /= S[row][:, None]
    cols = occ.mode[k][:, None] * M1 + np.arange(M1)
    return vals, cols


# gram() forms Z in dense blocks of this many consecutive rows (frames): each block
# touches only the modes whose dominance reaches it, so the work and memory are
# linear in the corpus (or utterance) length, whatever the utterances' lengths.
GRAM_ROWS = 128


def gram(occ: Occurrences, k, row, blocks, targets: np.ndarray, weights=None):
    """``Z^T Z`` and ``Z^T targets`` of a sparse matrix, block of rows by block of rows.

    ``Z`` has one or more column blocks; block ``b`` has ``w_b`` columns per
    mode, and pair ``p`` adds ``vals_b[p, m]`` at row ``row[p]``, column
    ``base_b + mode(p) * w_b + m`` (entries of one mode's occurrences that meet
    in a frame add up, as in Eq. 7). Dominance is local, so a block of
    :data:`GRAM_ROWS` consecutive frames meets only the few modes of the
    phones around it: its slice of ``Z`` is small and dense; it is formed,
    multiplied by BLAS and added into the result. Time and memory grow
    linearly with the number of frames, also for one long utterance.
    ``benchmarks/bench_dam.py`` compares it with scipy's sparse ``Z.T @ Z``.

    Parameters
    ----------
    occ : Occurrences
    k, row : ndarray of int, shape (n_pairs,)
        Occurrence and row of every pair.
    blocks : list of (vals, base)
        ``vals`` of shape (n_pairs, w_b); ``base`` the block's first global column.
    targets : ndarray, shape (n_rows,) or (n_rows, n_targets)
    weights : ndarray, shape (n_rows,), optional
        Row weights ``w``: returns ``Z^T W Z`` and ``Z^T W targets`` (0 drops
        a row: a frame whose value is missing, ``Utterance.mask``).

    Returns
    -------
    ZtZ : ndarray, shape (n_cols, n_cols)
        ``n_cols = max(base_b + n_modes * w_b)``.
    Zty : ndarray, shape (n_cols, n_targets)
    """
    targets = np.asarray(targets, dtype=float).reshape(occ.n_rows, -1)
    n_cols = max(base + occ.n_modes * v.shape[1] for v, base in blocks)
    ZtZ = np.zeros((n_cols, n_cols))
    Zty = np.zeros((n_cols, targets.shape[1]))
    if len(k) == 0:
        return ZtZ, Zty
    R = GRAM_ROWS
    n_chunks = (occ.n_rows + R - 1) // R
    chunk = row // R
    mode = occ.mode[k]
    # the modes each chunk meets, numbered 0.. within the chunk
    key, local = np.unique(chunk * occ.n_modes + mode, return_inverse=True)
    key_chunk, key_mode = np.divmod(key, occ.n_modes)
    first_key = np.searchsorted(key_chunk, np.arange(n_chunks + 1))
    L = np.diff(first_key)  # modes met, per chunk
    local = local - first_key[chunk]
    wsum = sum(v.shape[1] for v, _ in blocks)
    width = L * wsum  # local columns per chunk
    flat, off = [], 0
    for vals, _ in blocks:
        w = vals.shape[1]
        flat.append(((row - chunk * R) * width[chunk] + off * L[chunk] + local * w)[:, None] + np.arange(w))
        off += w
    flat = np.hstack(flat)
    wts = np.hstack([v for v, _ in blocks])
    order = np.argsort(chunk, kind="stable")
    flat, wts = flat[order], wts[order]
    bounds = np.searchsorted(chunk[order], np.arange(n_chunks + 1))
    for c in np.flatnonzero(np.diff(bounds)):
        p0, p1 = bounds[c], bounds[c + 1]
        r0, r1 = c * R, min((c + 1) * R, occ.n_rows)
        wu = int(width[c])
        Zl = np.bincount(flat[p0:p1].ravel(), weights=wts[p0:p1].ravel(), minlength=R * wu)
        Zl = Zl.reshape(R, wu)[: r1 - r0]
        m = key_mode[first_key[c] : first_key[c + 1]]
        g = np.concatenate(
            [
                base + (m[:, None] * w + np.arange(w)).ravel()
                for (v, base), w in zip(blocks, (v.shape[1] for v, _ in blocks))
            ]
        )
        yl = targets[r0:r1]
        if weights is not None:
            sw = np.sqrt(weights[r0:r1])[:, None]
            Zl, yl = Zl * sw, yl * sw
        ZtZ[np.ix_(g, g)] += Zl.T @ Zl
        Zty[g] += Zl.T @ yl
    return ZtZ, Zty


def normal_equations(occ: Occurrences, sigma: np.ndarray, Y: np.ndarray, pr=None, weights=None):
    """``X^T X`` and ``X^T Y`` of Eq. (5) for one set of sigmas (see :func:`gram`; ``weights``: ``X^T W X``).

    Returns
    -------
    G : ndarray, shape (n_coef, n_coef)
    XtY : ndarray, shape (n_coef, n_targets)
    """
    pr = pairs(occ, sigma) if pr is None else pr
    vals, _ = design_values(occ, pr)
    return gram(occ, pr[0], pr[1], [(vals, 0)], Y, weights)


def design_matrix(occ: Occurrences, sigma: np.ndarray, pr=None):
    """The sparse design matrix of Eqs. (3)-(7) for one channel's sigmas.

    Parameters
    ----------
    occ : Occurrences
    sigma : ndarray, shape (n_modes,)
    pr : tuple, optional
        Output of :func:`pairs` for the same sigma (to reuse it).

    Returns
    -------
    scipy.sparse.csr_matrix, shape (n_rows, n_modes * (degree + 1))
        Duplicate (row, column) entries (occurrences of one mode reaching the
        same frame) stand for their sum, as in Eq. (7).
    """
    from scipy import sparse

    pr = pairs(occ, sigma) if pr is None else pr
    vals, cols = design_values(occ, pr)
    row = pr[1]
    order = np.argsort(row, kind="stable")  # CSR directly: rows in order, no COO pass
    M1 = occ.degree + 1
    indptr = np.zeros(occ.n_rows + 1, dtype=np.int64)
    np.cumsum(np.bincount(row, minlength=occ.n_rows) * M1, out=indptr[1:])
    # Occurrences of one mode reaching the same frame leave duplicate
    # (row, column) entries: scipy sums them in every product, as Eq. (7) does.
    return sparse.csr_matrix((vals[order].ravel(), cols[order].ravel(), indptr), shape=(occ.n_rows, occ.n_coef))


def solve_normal_equations(G: np.ndarray, XtY: np.ndarray, lam: float):
    """Solve ``(X^T X + lam I) a = X^T Y`` (Eq. 5 with a ridge) by Cholesky.

    Parameters
    ----------
    G : ndarray, shape (n_coef, n_coef)
        ``X^T X`` (not modified).
    XtY : ndarray, shape (n_coef,) or (n_coef, n_targets)
        Several targets sharing one design are solved at once.
    lam : float
        Ridge (>= 0).

    Returns
    -------
    a : ndarray, shape of ``XtY``
    factor : tuple or None
        The Cholesky factor (for reuse), None if the system was singular and
        solved by least squares instead.
    """
    from scipy import linalg

    A = G.copy()
    A[np.diag_indices_from(A)] += lam
    try:
        fac = linalg.cho_factor(A, check_finite=False)
        return linalg.cho_solve(fac, XtY, check_finite=False), fac
    except linalg.LinAlgError:  # singular without ridge: least-norm solution
        return linalg.lstsq(A, XtY, check_finite=False)[0], None


def fitted_values(occ: Occurrences, coef: np.ndarray, sigma: np.ndarray, pr=None):
    """Model output on the training rows, Eq. (2), and what the M-step reuses.

    Parameters
    ----------
    coef : ndarray, shape (n_modes, degree + 1)
    sigma : ndarray, shape (n_modes,)

    Returns
    -------
    pred : ndarray, shape (n_rows,)
    parts : tuple
        ``(k, row, t, D, A, S)``: the pairs, the animeme value at each pair and
        the summed dominance per row (None unless ``normalize``).
    """
    k, row, t, D = pairs(occ, sigma) if pr is None else pr
    A = np.einsum("pm,pm->p", basis(t, occ.degree, occ.extrapolate), coef[occ.mode[k]])
    num = np.bincount(row, weights=D * A, minlength=occ.n_rows)
    S = None
    if occ.normalize:
        S = np.bincount(row, weights=D, minlength=occ.n_rows)
        num = num / S
    return num, (k, row, t, D, A, S)


def animeme_support(occ: Occurrences, sigma: np.ndarray) -> np.ndarray:
    """Per mode, the local times where rendering the training utterances evaluates its animeme.

    The frames :func:`dam.model.synthesis.concatenate` visits for every
    training occurrence, in its training mode, with the fitted sigmas (the
    window of the largest sigma over channels, as synthesis uses); see
    :func:`dam.model.animeme.trained_support`.

    Parameters
    ----------
    occ : Occurrences
    sigma : ndarray, shape (n_modes, n_channels)

    Returns
    -------
    ndarray, shape (n_modes, 2)
    """
    k, _, t = segment_windows(
        occ.starts, occ.ends, sigma[occ.mode].max(axis=1), occ.frame_rate, occ.n_frames, occ.eps, occ.tol
    )
    return trained_support(occ.mode[k], t, occ.n_modes)
