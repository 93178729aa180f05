"""dam_runtime: synthesize speech animation from an exported model with numpy alone.

A single file with no dependency but numpy: copy it into an application and
load a model written by ``dam.export.runtime.export_runtime`` (``.json`` or
``.npz``). It reproduces the toolkit's ``predict`` of

* the DAM (Chen et al. 2012; also its M = 0 variant ``dam-m0``): one mode per
  phone by the cheapest path over the animeme graph (Section VI,
  ``E = w_c E_c + w_s E_s``; solved here by dynamic programming, which finds
  the same optimum as the toolkit), then Eq. (2), the concatenation of
  dominated animemes;
* the Cohen-Massaro (1993) model (``cohen-massaro``): per-phone targets
  blended by normalised exponential dominance;
* the per-phone mean (``phone-mean``).

Frame ``i`` is at ``i / frame_rate`` seconds, for every ``i / frame_rate <=``
the end of the last phone.

Example::

    import dam_runtime
    model = dam_runtime.load("face.dam.json")
    frames = model.synthesize(["sil", "h", "a", "l", "o", "sil"],
                              ends=[0.1, 0.18, 0.3, 0.38, 0.55, 0.7])
    # frames: ndarray (n_frames, n_channels); model.channels names the columns

Phones the model never saw raise ``KeyError`` (map them before calling).
"""

import json
import math

import numpy as np

FORMAT = "dam-runtime"
VERSION = 1
SILENCE_LABELS = frozenset({"", "sil", "sp", "spn", "pau", "<sil>", "silence"})
BOUNDARY = "#"

__all__ = ["load", "Model", "FORMAT", "VERSION"]


def load(path):
    """Load an exported model (``.json`` or ``.npz``)."""
    path = str(path)
    if path.endswith(".npz"):
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(bytes(z["__meta__"]).decode("utf-8"))
            arrays = {k: z[k] for k in z.files if k != "__meta__"}
    else:
        with open(path, encoding="utf-8") as fh:
            meta = json.load(fh)
        arrays = meta.pop("arrays", None) if isinstance(meta, dict) else None
        arrays = {k: np.asarray(v, dtype=float) for k, v in (arrays or {}).items()}
    if not isinstance(meta, dict) or meta.get("format") != FORMAT or meta.get("version") != VERSION:
        raise ValueError(f"{path}: not a {FORMAT} version {VERSION} file")
    return Model(meta, arrays)


class Model:
    """An exported model: ``synthesize`` (and, for the DAM, ``modes``).

    Attributes: ``frame_rate`` (float), ``channels`` (list of str), ``phones``
    (list of str, the phones it knows).
    """

    def __init__(self, meta, arrays):
        self.meta = meta
        self.frame_rate = float(meta["frame_rate"])
        self.channels = list(meta["channels"])
        self.phones = list(meta["phones"])
        self.silence = meta.get("silence", "sil")
        self._index = {p: i for i, p in enumerate(self.phones)}
        self.kind = meta["model"]
        self.arrays = arrays
        if self.kind in ("dam", "dam-m0"):
            self._first = np.asarray(meta["first"], dtype=np.int64)
            self._count = np.asarray(meta["count"], dtype=np.int64)
            self.power = arrays["power"]  # (n_modes, degree + 1, C) monomial coefficients a^0 .. a^M
            self.sigma = arrays["sigma"]  # (n_modes, C)
            self.edges = arrays["edges"]  # (n_modes, 2, 3, C): A, A', A'' at t = 0 and t = 1
            self.scale = arrays["channel_scale"]  # (C,)
            self._context = meta["context"]
            self._nll = {}
        elif self.kind not in ("phone-mean", "cohen-massaro"):
            raise ValueError(f"model {self.kind!r}: this runtime plays dam, dam-m0, cohen-massaro, phone-mean")

    # -- the phones --------------------------------------------------------------------
    def _segments(self, labels, starts, ends):
        labels = [self.silence if str(x).strip().lower() in SILENCE_LABELS else str(x).strip() for x in labels]
        ends = [float(e) for e in ends]
        if starts is None:
            starts = [0.0] + ends[:-1]
        L, S, E = [], [], []

        def add(lab, s, e):
            if lab == self.silence and L and L[-1] == self.silence:
                E[-1] = e  # adjacent silences are one pause, as in the toolkit
            else:
                L.append(lab), S.append(max(s, 0.0)), E.append(e)

        prev = 0.0
        for lab, s, e in zip(labels, starts, ends):
            s = float(s)
            if s > prev + 1e-6:  # a gap is silence, as in the toolkit
                add(self.silence, prev, s)
            elif abs(s - prev) <= 1e-6:
                s = prev
            if not e > s + 1e-6:
                raise ValueError(f"segment {lab!r}: end {e} is not after its start {s}")
            add(lab, s, e)
            prev = e
        unknown = [x for x in L if x not in self._index]
        if unknown:
            raise KeyError(f"phones not in the model: {sorted(set(unknown))}; known: {' '.join(self.phones)}")
        return L, np.array(S), np.array(E)

    # -- mode selection (Section VI) ------------------------------------------------------
    def _node(self, phone, left, right):
        key = (phone, left, right)
        if key not in self._nll:
            self._nll[key] = float(self.meta["w_c"]) * _mode_nll(
                self._context,
                phone,
                left,
                right,
                int(self._count[self._index[phone]]),
                float(self.meta["context_smoothing"]),
            )
        return self._nll[key]

    def _edge(self, g_prev, g_cur, d_prev, d_cur):
        tau = float(self.meta["time_scale"])
        k = np.arange(3)[:, None]
        p = self.edges[g_prev, 1] * (tau / d_prev) ** k / self.scale  # (G_prev, 3, C)
        c = self.edges[g_cur, 0] * (tau / d_cur) ** k / self.scale  # (G_cur, 3, C)
        return float(self.meta["w_s"]) * ((p[:, None] - c[None, :]) ** 2).sum(axis=(-2, -1))

    def modes(self, labels, ends, starts=None):
        """Global mode (row of the model's arrays) of every segment, by dynamic programming (DAM only)."""
        if self.kind not in ("dam", "dam-m0"):
            raise ValueError(f"a {self.kind} model has no modes")
        L, S, E = self._segments(labels, starts, ends)
        return self._modes(L, S, E)

    def _modes(self, L, S, E):
        pad = [BOUNDARY, *L, BOUNDARY]
        first = [int(self._first[self._index[p]]) for p in L]
        count = [int(self._count[self._index[p]]) for p in L]
        dur = E - S
        zero = np.zeros(1)
        acc, back = (self._node(L[0], pad[0], pad[2]) if count[0] > 1 else zero), []
        for j in range(1, len(L)):
            if count[j] == 1 and count[j - 1] == 1:  # nothing to choose: every path passes here
                acc = zero
                back.append(np.zeros(1, dtype=np.int64))
                continue
            prev = np.arange(first[j - 1], first[j - 1] + count[j - 1])
            cur = np.arange(first[j], first[j] + count[j])
            tot = acc[:, None] + self._edge(prev, cur, dur[j - 1], dur[j])
            b = np.argmin(tot, axis=0)
            # a single-mode segment joins all paths: restart its cost at 0 (a shared constant)
            acc = zero if count[j] == 1 else tot[b, np.arange(len(cur))] + self._node(L[j], pad[j], pad[j + 2])
            back.append(b)
        g = int(np.argmin(acc))
        path = [g]
        for b in reversed(back):
            g = int(b[g])
            path.append(g)
        return np.array(first) + np.array(path[::-1])

    # -- Eq. (2) ----------------------------------------------------------------------------
    def synthesize(self, labels, ends, starts=None, modes=None):
        """Control trajectories, shape (n_frames, n_channels).

        ``labels`` and ``ends`` (seconds) per segment; ``starts`` default to
        the previous end (the first at 0); ``modes`` (global) default to the
        cheapest path.
        """
        L, S, E = self._segments(labels, starts, ends)
        n = int(math.floor(E[-1] * self.frame_rate + 1e-6 * self.frame_rate)) + 1  # frames at t <= end
        if self.kind == "phone-mean":
            idx = np.minimum(np.searchsorted(E, np.arange(n) / self.frame_rate + 1e-9, side="right"), len(L) - 1)
            return self.arrays["table"][np.array([self._index[p] for p in L])[idx]]
        if self.kind == "cohen-massaro":
            return self._cohen_massaro(L, S, E, n)
        glob = self._modes(L, S, E) if modes is None else np.asarray(modes, dtype=np.int64)
        return self._concatenate(S, E, glob, n)

    def _cohen_massaro(self, L, S, E, n_frames):
        """Cohen & Massaro (1993): ``sum_s D_s T_s / sum_s D_s``, ``D = alpha exp(-theta |tau|^c)``."""
        a = self.arrays
        rows = np.array([self._index[p] for p in L])
        first = np.r_[True, rows[1:] != rows[:-1]]  # neighbouring segments of one phone act as one
        last = np.r_[first[1:], True]
        s, e, rows = S[first], E[last], rows[first]
        block, near = int(self.meta["block_frames"]), int(self.meta["neighbours"])
        parts = []
        for b in range(0, n_frames, block):  # blocks of frames, each with the segments near it
            t = np.arange(b, min(b + block, n_frames)) / self.frame_rate
            lo = max(int(np.searchsorted(e, t[0], side="left")) - near, 0)
            hi = int(np.searchsorted(s, t[-1], side="right")) + near
            p = rows[lo:hi]
            tau = (0.5 * (s[lo:hi] + e[lo:hi]))[None, :] - t[:, None]
            theta = np.where((tau > 0)[:, :, None], a["theta_left"][p], a["theta_right"][p])
            log_d = np.log(a["alpha"][p]) - theta * np.abs(tau)[:, :, None] ** a["c"][p]
            log_d -= log_d.max(axis=1, keepdims=True)
            w = np.exp(log_d)
            parts.append(np.einsum("fsc,sc->fc", w, a["target"][p]) / w.sum(axis=1))
        return np.concatenate(parts)

    def _concatenate(self, starts, ends, glob, n_frames):
        fr, eps, tol = self.frame_rate, float(self.meta["eps"]), float(self.meta["tol"])
        sigma = self.sigma[glob]
        C = sigma.shape[1]
        dur = ends - starts
        smax = sigma.max(axis=1)
        if tol <= 0.0:
            r = np.full(len(starts), n_frames / fr) / np.maximum(dur, 1e-12) + 1.0
        elif tol >= 1.0:
            r = np.zeros(len(starts))
        else:
            r = np.sqrt(-(smax * smax + eps) * np.log(tol))
        lo = np.minimum(np.maximum(np.ceil((starts - r * dur) * fr - 1e-9), 0), n_frames).astype(np.int64)
        hi = np.minimum(np.maximum(np.floor((ends + r * dur) * fr + 1e-9) + 1, lo), n_frames).astype(np.int64)
        counts = hi - lo
        seg = np.repeat(np.arange(len(starts)), counts)
        frame = np.arange(seg.size) + (lo - (np.cumsum(counts) - counts))[seg]
        t = (frame / fr - starts[seg]) / dur[seg]
        # (M+1, n_seg, C), contiguous: take() on a transposed view is several times slower
        power = np.ascontiguousarray(self.power[glob].transpose(1, 0, 2))
        extrapolate = self.meta["extrapolate"]
        if extrapolate == "polynomial":
            ta = t
        elif extrapolate == "trained":  # the polynomial where training evaluated it, held beyond
            sup = self.arrays["support"][glob]
            ta = np.minimum(np.maximum(t, sup[:, 0].take(seg)), sup[:, 1].take(seg))
        else:  # "hold"
            ta = np.minimum(np.maximum(t, 0.0), 1.0)
        ta = ta[:, None]
        A = power[-1].take(seg, axis=0)
        for m in range(power.shape[0] - 2, -1, -1):  # Horner's rule
            A *= ta
            A += power[m].take(seg, axis=0)
        u = np.maximum(-t, 0.0) + np.maximum(t - 1.0, 0.0)
        D = np.exp(-(u * u)[:, None] / (sigma * sigma + eps).take(seg, axis=0))  # Eq. (1)
        if tol > 0.0:
            D[D < tol] = 0.0
        A *= D
        flat = ((frame * C)[:, None] + np.arange(C)).ravel()
        num = np.bincount(flat, weights=A.ravel(), minlength=n_frames * C).reshape(n_frames, C)
        if not self.meta["normalize"]:
            return num
        den = np.bincount(flat, weights=D.ravel(), minlength=n_frames * C).reshape(n_frames, C)
        return num / np.maximum(den, 1e-300)


def _smoothed(counts, alpha):
    c = np.asarray(counts, dtype=float)
    return (c + alpha) / (c.sum() + alpha * c.size)


def _mode_nll(stats, phone, left, right, n_modes, alpha):
    """E_c: -log P(mode | phone, left, right), backing off trigram -> bigrams -> unigram."""
    if n_modes == 1:
        return np.zeros(1)
    st = stats.get(phone)
    if st is None:
        return np.full(n_modes, np.log(n_modes))
    tri = st["trigram"].get(left, {}).get(right)
    if tri is not None and sum(tri) > 0:
        return -np.log(_smoothed(tri, alpha))
    seen = [c for c in (st["left"].get(left), st["right"].get(right)) if c is not None and sum(c) > 0]
    if seen:
        return -np.log(np.mean([_smoothed(c, alpha) for c in seen], axis=0))
    return -np.log(_smoothed(st["unigram"], alpha))
