"""Standard face-rig names, and linear maps from a model's channels onto them.

A model trained on articulator channels (VTL tract parameters, EMA, the toy
rig's gestures) drives a standard face rig through a linear map
``weights = values @ matrix + offset``: given by the user (a JSON file),
one of the hand-made maps below, or fitted by least squares to frames where
both sides are known (:meth:`LinearMap.fit`, e.g. from a cross-mapping
with :class:`dam.crossmap.CrossMapper`). The glTF writer then matches the
mapped channels to the rig's morph targets by name.

Presets
-------
``"arkit"``
    Apple ARKit's 52 blendshape locations (``ARFaceAnchor.BlendShapeLocation``),
    the names most commercial face rigs and capture apps use.
``"oculus"``
    The 15 visemes of Meta's Oculus LipSync (``sil PP FF TH DD kk CH SS nn
    RR aa E ih oh ou``), as the blendshape names ``viseme_sil`` ... ``viseme_ou``
    that avatar rigs carry (e.g. Ready Player Me).
"""

from __future__ import annotations

import json
import os

import numpy as np

from dam.corpus import DataError
from dam.corpus.atomic import atomic_write

__all__ = [
    "ARKIT_52",
    "OCULUS_15",
    "PRESETS",
    "preset_names",
    "LinearMap",
    "TOY_TO_ARKIT",
    "TOY_TO_OCULUS",
    "SAMPA_TO_OCULUS",
    "OCULUS_TO_ARKIT",
]

ARKIT_52 = (
    "eyeBlinkLeft",
    "eyeLookDownLeft",
    "eyeLookInLeft",
    "eyeLookOutLeft",
    "eyeLookUpLeft",
    "eyeSquintLeft",
    "eyeWideLeft",
    "eyeBlinkRight",
    "eyeLookDownRight",
    "eyeLookInRight",
    "eyeLookOutRight",
    "eyeLookUpRight",
    "eyeSquintRight",
    "eyeWideRight",
    "jawForward",
    "jawLeft",
    "jawRight",
    "jawOpen",
    "mouthClose",
    "mouthFunnel",
    "mouthPucker",
    "mouthLeft",
    "mouthRight",
    "mouthSmileLeft",
    "mouthSmileRight",
    "mouthFrownLeft",
    "mouthFrownRight",
    "mouthDimpleLeft",
    "mouthDimpleRight",
    "mouthStretchLeft",
    "mouthStretchRight",
    "mouthRollLower",
    "mouthRollUpper",
    "mouthShrugLower",
    "mouthShrugUpper",
    "mouthPressLeft",
    "mouthPressRight",
    "mouthLowerDownLeft",
    "mouthLowerDownRight",
    "mouthUpperUpLeft",
    "mouthUpperUpRight",
    "browDownLeft",
    "browDownRight",
    "browInnerUp",
    "browOuterUpLeft",
    "browOuterUpRight",
    "cheekPuff",
    "cheekSquintLeft",
    "cheekSquintRight",
    "noseSneerLeft",
    "noseSneerRight",
    "tongueOut",
)

OCULUS_15 = tuple(
    f"viseme_{v}" for v in ("sil", "PP", "FF", "TH", "DD", "kk", "CH", "SS", "nn", "RR", "aa", "E", "ih", "oh", "ou")
)

PRESETS = {"arkit": ARKIT_52, "oculus": OCULUS_15}

#: Hand-made maps from the toy tract rig's gestures (:data:`dam.crossmap.outlines.TOY_CONTROLS`):
#: source -> {target: gain}. Jaw opening opens the jaw; rounding puckers and funnels; closure closes
#: and presses the lips.
TOY_TO_ARKIT = {
    "jaw_open": {"jawOpen": 1.0, "mouthLowerDownLeft": 0.2, "mouthLowerDownRight": 0.2},
    "lip_round": {"mouthPucker": 0.8, "mouthFunnel": 0.5},
    "lip_close": {"mouthClose": 0.8, "mouthPressLeft": 0.3, "mouthPressRight": 0.3},
    "tongue_front": {"mouthStretchLeft": 0.2, "mouthStretchRight": 0.2},
}
TOY_TO_OCULUS = {
    "jaw_open": {"viseme_aa": 1.0},
    "lip_round": {"viseme_ou": 0.7, "viseme_oh": 0.3},
    "lip_close": {"viseme_PP": 1.0},
    "tip_up": {"viseme_DD": 0.6, "viseme_nn": 0.4},
    "dorsum_up": {"viseme_kk": 1.0},
    "tongue_front": {"viseme_E": 0.5, "viseme_ih": 0.5},
}
_HAND_MAPS = {("toy", "arkit"): TOY_TO_ARKIT, ("toy", "oculus"): TOY_TO_OCULUS}

#: The Oculus viseme of every German SAMPA phone of the bundled ``vtl`` corpus (Meta's viseme
#: reference: PP p b m, FF f v, TH, DD t d, kk k g, CH tS dZ S, SS s z, nn n l, RR r, aa, E, ih, oh, ou).
#: Choices where German has no English counterpart: C (ich-Laut) and S as CH; ts as SS; x, N as kk;
#: R as RR; h and j as the neighbouring open/close vowels aa and ih; rounded front vowels as ou.
SAMPA_TO_OCULUS = {
    "sil": "sil",
    "p": "PP",
    "b": "PP",
    "m": "PP",
    "f": "FF",
    "v": "FF",
    "t": "DD",
    "d": "DD",
    "k": "kk",
    "g": "kk",
    "x": "kk",
    "N": "kk",
    "S": "CH",
    "C": "CH",
    "s": "SS",
    "z": "SS",
    "ts": "SS",
    "n": "nn",
    "l": "nn",
    "R": "RR",
    "h": "aa",
    "j": "ih",
    "a": "aa",
    "a:": "aa",
    "6": "aa",
    "aI": "aa",
    "aU": "aa",
    "@": "E",
    "E": "E",
    "E:": "E",
    "e:": "E",
    "I": "ih",
    "i:": "ih",
    "O": "oh",
    "o:": "oh",
    "OY": "oh",
    "2:": "ou",
    "9": "oh",
    "U": "ou",
    "u:": "ou",
    "Y": "ou",
    "y:": "ou",
}

#: Each Oculus viseme as ARKit blendshape weights (hand-made, after Apple's blendshape descriptions).
OCULUS_TO_ARKIT = {
    "PP": {"mouthClose": 0.6, "mouthPressLeft": 0.5, "mouthPressRight": 0.5},
    "FF": {"mouthRollLower": 0.6, "mouthUpperUpLeft": 0.2, "mouthUpperUpRight": 0.2, "jawOpen": 0.05},
    "TH": {"tongueOut": 0.4, "jawOpen": 0.15},
    "DD": {"jawOpen": 0.2, "mouthStretchLeft": 0.1, "mouthStretchRight": 0.1},
    "kk": {"jawOpen": 0.25, "mouthStretchLeft": 0.1, "mouthStretchRight": 0.1},
    "CH": {"mouthFunnel": 0.5, "mouthPucker": 0.2, "jawOpen": 0.1},
    "SS": {"mouthStretchLeft": 0.35, "mouthStretchRight": 0.35, "jawOpen": 0.05},
    "nn": {"jawOpen": 0.15},
    "RR": {"mouthPucker": 0.35, "mouthFunnel": 0.2, "jawOpen": 0.15},
    "aa": {"jawOpen": 0.7, "mouthLowerDownLeft": 0.3, "mouthLowerDownRight": 0.3},
    "E": {"jawOpen": 0.35, "mouthStretchLeft": 0.3, "mouthStretchRight": 0.3},
    "ih": {"jawOpen": 0.2, "mouthSmileLeft": 0.3, "mouthSmileRight": 0.3},
    "oh": {"jawOpen": 0.45, "mouthFunnel": 0.5},
    "ou": {"jawOpen": 0.15, "mouthPucker": 0.8, "mouthFunnel": 0.3},
}


def preset_names(name: str) -> tuple[str, ...]:
    """The target names of preset ``name`` (``"arkit"`` or ``"oculus"``)."""
    try:
        return PRESETS[str(name).lower()]
    except KeyError:
        raise DataError(None, "preset", name, f"unknown preset; use one of {', '.join(PRESETS)}") from None


class LinearMap:
    """``weights = values @ matrix + offset``: model channels onto rig targets.

    Parameters
    ----------
    sources : sequence of str, length n_sources
        The model's channel names (the columns it reads).
    targets : sequence of str, length n_targets
        Rig target names (e.g. :data:`ARKIT_52`).
    matrix : array-like, shape (n_sources, n_targets)
    offset : array-like, shape (n_targets,), default zeros
    preset : str, optional
        If given, every target must be a name of that preset.
    source : str, optional
        File the map came from (error messages).

    Examples
    --------
    >>> import numpy as np
    >>> m = LinearMap.hand_made("toy", "arkit")
    >>> w = m.apply(np.array([[1.0, 0, 0, 0, 0, 0, 0]]), ["jaw_open", "tongue_front", "lip_round",
    ...                                                 "tongue_back", "lip_close", "tip_up", "dorsum_up"])
    >>> float(w[0, m.targets.index("jawOpen")])
    1.0
    """

    def __init__(self, sources, targets, matrix, offset=None, *, preset: str | None = None, source=None):
        self.sources = tuple(str(s) for s in sources)
        self.targets = tuple(str(t) for t in targets)
        self.source = source
        M = np.asarray(matrix, dtype=float)
        if M.shape != (len(self.sources), len(self.targets)):
            raise DataError(
                source,
                "matrix",
                M.shape,
                f"must be (n_sources, n_targets) = ({len(self.sources)}, {len(self.targets)})",
            )
        b = np.zeros(len(self.targets)) if offset is None else np.asarray(offset, dtype=float)
        if b.shape != (len(self.targets),):
            raise DataError(source, "offset", b.shape, f"must have one value per target ({len(self.targets)})")
        if not (np.all(np.isfinite(M)) and np.all(np.isfinite(b))):
            raise DataError(source, "matrix", "non-finite", "the map must be finite")
        for field, names in (("sources", self.sources), ("targets", self.targets)):
            if len(set(names)) != len(names):
                raise DataError(source, field, next(n for n in names if names.count(n) > 1), "duplicate name")
        if preset is not None:
            allowed = preset_names(preset)
            bad = [t for t in self.targets if t not in allowed]
            if bad:
                raise DataError(
                    source, "targets", bad, f"not names of the {preset} preset", f"its names are {list(allowed)}"
                )
        self.preset = preset
        self.matrix, self.offset = M, b

    def __repr__(self) -> str:
        preset = f", {self.preset}" if self.preset else ""
        return f"LinearMap({len(self.sources)} sources -> {len(self.targets)} targets{preset})"

    @classmethod
    def hand_made(cls, sources: str, preset: str) -> LinearMap:
        """One of the hand-made maps: ``("toy", "arkit")`` or ``("toy", "oculus")``; targets are the whole preset."""
        from dam.crossmap.outlines import TOY_CONTROLS

        key = (sources, str(preset).lower())
        if key not in _HAND_MAPS:
            raise DataError(None, "map", key, f"no hand-made map; there are {sorted(_HAND_MAPS)}")
        targets = preset_names(preset)
        src = list(TOY_CONTROLS)
        M = np.zeros((len(src), len(targets)))
        for s, row in _HAND_MAPS[key].items():
            for t, g in row.items():
                M[src.index(s), targets.index(t)] = g
        return cls(src, targets, M, preset=key[1])

    @classmethod
    def fit(cls, values, weights, sources, targets, *, ridge: float = 1e-6, preset: str | None = None) -> LinearMap:
        """Least squares ``weights ~= values @ matrix + offset`` (with a small ridge on the matrix).

        Parameters
        ----------
        values : array-like, shape (n_frames, n_sources)
            Model channels on frames where the rig weights are known.
        weights : array-like, shape (n_frames, n_targets)
            The rig's weights on the same frames (e.g. a cross-mapping's output).
        sources, targets : sequence of str
        ridge : float, default 1e-6
            Relative to the mean squared (centred) value.
        """
        X = np.asarray(values, dtype=float)
        W = np.asarray(weights, dtype=float)
        if X.ndim != 2 or W.ndim != 2 or len(X) != len(W) or len(X) < 2:
            raise DataError(None, "values/weights", (X.shape, W.shape), "need paired 2-D frames (at least 2)")
        mx, mw = X.mean(0), W.mean(0)
        Xc = X - mx
        lam = ridge * max(float((Xc**2).mean()), 1e-12) * len(X)
        M = np.linalg.solve(Xc.T @ Xc + lam * np.eye(X.shape[1]), Xc.T @ (W - mw))
        return cls(sources, targets, M, mw - mx @ M, preset=preset)

    def then(self, other: LinearMap) -> LinearMap:
        """The map ``other(self(x))``: ``self``'s targets must be ``other``'s sources (any order)."""
        missing = [t for t in other.sources if t not in self.targets]
        if missing:
            raise DataError(
                other.source,
                "sources",
                missing,
                "not targets of the first map",
                f"its targets are {list(self.targets)}",
            )
        cols = [self.targets.index(t) for t in other.sources]
        return LinearMap(
            self.sources,
            other.targets,
            self.matrix[:, cols] @ other.matrix,
            self.offset[cols] @ other.matrix + other.offset,
            preset=other.preset,
        )

    @classmethod
    def from_phones(cls, corpus, table: dict, preset: str = "oculus", *, ridge: float = 1e-6) -> LinearMap:
        """Fit channels -> visemes on a corpus whose frames are labelled by ``table[phone]``.

        Every frame's target is 1 for the viseme of its phone and 0 for the
        others; the least-squares map (:meth:`fit`) then turns articulator
        channels into viseme weights.

        Parameters
        ----------
        corpus : dam.Corpus
        table : dict str -> str
            Phone -> viseme name without the ``viseme_`` prefix (e.g. :data:`SAMPA_TO_OCULUS`).
        preset : str, default "oculus"
        """
        from dam.corpus import frame_labels

        targets = preset_names(preset)
        names = [t.removeprefix("viseme_") for t in targets]
        missing = sorted(corpus.phones - set(table))
        if missing:
            raise DataError(corpus.source, "table", missing, "phones of the corpus without a viseme")
        X, W = [], []
        for u in corpus:
            labels = frame_labels(u.alignment, u.frame_rate, u.n_frames)
            onehot = np.zeros((u.n_frames, len(targets)))
            onehot[np.arange(u.n_frames), [names.index(table[lab]) for lab in labels]] = 1.0
            X.append(u.trajectory)
            W.append(onehot)
        return cls.fit(np.concatenate(X), np.concatenate(W), corpus.channels, targets, ridge=ridge, preset=preset)

    @classmethod
    def vtl(cls, preset: str) -> LinearMap:
        """VTL tract parameters -> ``"oculus"`` visemes (fitted on the bundled ``vtl`` corpus with
        :data:`SAMPA_TO_OCULUS`) or -> ``"arkit"`` (that map, then :data:`OCULUS_TO_ARKIT`)."""
        import dam.datasets

        preset = str(preset).lower()
        preset_names(preset)
        visemes = cls.from_phones(dam.datasets.load("vtl"), SAMPA_TO_OCULUS, "oculus")
        if preset == "oculus":
            return visemes
        M = np.zeros((len(OCULUS_15), len(ARKIT_52)))
        for v, row in OCULUS_TO_ARKIT.items():
            for t, g in row.items():
                M[OCULUS_15.index(f"viseme_{v}"), ARKIT_52.index(t)] = g
        return visemes.then(cls(OCULUS_15, ARKIT_52, M, preset="arkit"))

    def apply(self, values, channels) -> np.ndarray:
        """Map ``values`` (n_frames, n_channels) whose columns are named ``channels``; shape (n_frames, n_targets)."""
        channels = list(channels)
        missing = [s for s in self.sources if s not in channels]
        if missing:
            raise DataError(
                self.source, "sources", missing, "the model has no such channels", f"its channels are {channels}"
            )
        X = np.asarray(values, dtype=float)[:, [channels.index(s) for s in self.sources]]
        return X @ self.matrix + self.offset

    # -- files ---------------------------------------------------------------------------------
    def to_dict(self) -> dict:
        return {
            "format": "dam-linear-map",
            "version": 1,
            "preset": self.preset,
            "sources": list(self.sources),
            "targets": list(self.targets),
            "matrix": self.matrix.tolist(),
            "offset": self.offset.tolist(),
        }

    def save(self, path) -> None:
        """Write the map as JSON (atomically)."""
        with atomic_write(os.fspath(path), "w") as fh:
            json.dump(self.to_dict(), fh, indent=1)

    @classmethod
    def load(cls, path) -> LinearMap:
        """Read a map: ``{"sources": [...], "targets": [...] | "preset": "arkit", "matrix": [[...]], "offset": [...]}``.

        With a preset and no ``targets``, the targets are the whole preset.
        ``matrix`` may instead be a dict ``{source: {target: gain}}``.
        """
        from .tables import read_json_object

        path = os.fspath(path)
        doc = read_json_object(path, "map")
        preset = doc.get("preset")
        targets = doc.get("targets") or (preset_names(preset) if preset else None)
        if targets is None:
            raise DataError(path, "targets", None, "give 'targets' or a 'preset'")
        M = doc.get("matrix")
        if isinstance(M, dict):
            sources = doc.get("sources") or list(M)
            targets = list(targets)
            dense = np.zeros((len(sources), len(targets)))
            for s, row in M.items():
                if s not in sources:
                    raise DataError(path, "matrix", s, "a source not listed in 'sources'")
                for t, g in row.items():
                    if t not in targets:
                        raise DataError(path, f"matrix[{s!r}]", t, "not a target name", f"targets: {targets}")
                    dense[sources.index(s), targets.index(t)] = float(g)
            M = dense
        elif "sources" not in doc or M is None:
            raise DataError(path, "sources", None, "give 'sources' and 'matrix'")
        else:
            sources = doc["sources"]
        return cls(sources, targets, M, doc.get("offset"), preset=preset, source=path)
