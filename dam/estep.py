"""The E-step of Chen et al. (2012), Eqs. (3)-(7): animeme coefficients by least squares.

With every dominance fixed, the training signal is linear in the animeme
coefficients. Row ``i`` of the design matrix (one frame of the corpus, all
utterances stacked) holds, in the columns of mode ``b``,
``sum_h D_{b_h}(t_{b_h}^i) P_m(2 t_{b_h}^i - 1)`` summed over the occurrences
``h`` of that mode (Eq. 7: repeated occurrences share columns). Truncated
dominance makes it sparse. The normal equations (Eq. 5) with a small ridge
``(X^T X + lambda I) a = X^T y`` have only ``n_modes * (M + 1)`` unknowns, so
``X^T X`` is formed sparse and solved densely by Cholesky.

With ``normalize=True`` (weighted average) every row is divided by the
frame's summed dominance, which keeps the problem linear.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .animeme import basis
from .dominance import dominance
from .synthesis import segment_windows

__all__ = ["Occurrences", "pairs", "design_matrix", "solve_normal_equations", "fitted_values"]


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
    def from_corpus(cls, corpus, mode_of_segment, n_modes: int, **kw) -> "Occurrences":
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
        return cls(cat(starts), cat(ends), cat(nf).astype(np.int64), cat(off).astype(np.int64),
                   cat(mode), row, n_modes, corpus.frame_rate, **kw)

    @property
    def n_coef(self) -> int:
        return self.n_modes * (self.degree + 1)


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
    k, frame, t = segment_windows(occ.starts, occ.ends, s_occ, occ.frame_rate, occ.n_frames,
                                  occ.eps, occ.tol)
    D = dominance(t, s_occ[k], occ.eps, occ.tol)
    keep = D > 0.0
    k, frame, t, D = k[keep], frame[keep], t[keep], D[keep]
    return k, occ.offset[k] + frame, t, D


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
        same frame) are summed, as in Eq. (7).
    """
    from scipy import sparse

    k, row, t, D = pairs(occ, sigma) if pr is None else pr
    M1 = occ.degree + 1
    vals = D[:, None] * basis(t, occ.degree, occ.extrapolate)
    if occ.normalize:
        S = np.bincount(row, weights=D, minlength=occ.n_rows)
        vals /= S[row][:, None]
    cols = occ.mode[k][:, None] * M1 + np.arange(M1)
    X = sparse.csr_matrix((vals.ravel(), (np.repeat(row, M1), cols.ravel())),
                          shape=(occ.n_rows, occ.n_coef))
    X.sum_duplicates()
    return X


def solve_normal_equations(X, Y: np.ndarray, lam: float) -> np.ndarray:
    """Solve ``(X^T X + lam I) a = X^T Y`` (Eq. 5 with a ridge).

    Parameters
    ----------
    X : sparse matrix, shape (n_rows, n_coef)
    Y : ndarray, shape (n_rows,) or (n_rows, n_targets)
        Several targets sharing one design are solved at once.
    lam : float
        Ridge (>= 0).

    Returns
    -------
    ndarray, shape (n_coef,) or (n_coef, n_targets)
    """
    from scipy import linalg

    G = (X.T @ X).toarray()
    G[np.diag_indices_from(G)] += lam
    rhs = X.T @ Y
    try:
        return linalg.cho_solve(linalg.cho_factor(G, check_finite=False), rhs, check_finite=False)
    except linalg.LinAlgError:  # singular without ridge: least-norm solution
        return linalg.lstsq(G, rhs, check_finite=False)[0]


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
