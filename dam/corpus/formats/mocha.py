"""MOCHA-TIMIT and mngu0: EMA as EST tracks with ESPS/xwaves labels.

**MOCHA-TIMIT** (Wrench, CSTR Edinburgh) ships per utterance ``<spk>_<nnn>.ema``
(an EST track, binary, either byte order; :mod:`dam.corpus.formats.est`),
``<spk>_<nnn>.lab`` (ESPS/xwaves labels: a header closed by ``#``, then
``end_time colour phone`` lines) and ``<spk>_<nnn>.wav``; the laryngograph
(``.lar``) and electropalatograph (``.epg``) files, when present, are not
trajectories and are left alone. The EMA has 20 channels at 500 frames/s, ten
coils times x and y, stored in units of 1/100 mm (MOCHAtools, Qin and
Carreira-Perpiñán 2009, divide by 100 to get millimetres; this reader does
the same, so trajectories are in **millimetres**). When a file's header names
its channels (``Channel_N``) those names are kept; otherwise the layout is
:data:`MOCHA_CHANNELS`: the x channels of five coils, their y channels, then
the x and y channels of five more (upper incisor ``ui``, lower incisor ``li``,
upper lip ``ul``, lower lip ``ll``, tongue tip ``tt``, blade ``tb``, dorsum
``td``, velum ``v``, bridge of the nose ``bn``). MOCHAtools do not name or use
channels 13 and 18; they are kept here as ``coil10_x``/``coil10_y``.

**mngu0** (Richmond et al. 2011) uses the same two file kinds and differs in
three details: its EST headers name the channels (coil and axis, such as
``T1_py``; the names are kept), the rate is 200 frames/s, and values are
already in millimetres (scale 1). Its files are named ``mngu0_*``, which is
how :func:`~dam.corpus.formats.detect.detect_format` tells them apart. A frame the
EST file marks as a *break* (value flag 0) is a dropout: here it becomes
masked frames (:mod:`dam.corpus.formats.tracks`), where the generic
directory reader refuses it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dam.corpus.data import SILENCE, DataError
from dam.corpus.formats.est import read_est, stored_frame_rate
from dam.corpus.formats.tracks import Track, audio_beside, build_corpus, pair_by_stem, uniform_rate

__all__ = [
    "MOCHA_CHANNELS",
    "MOCHA_SCALE",
    "read_ema_track",
    "load_mocha_corpus",
    "load_mngu0_corpus",
    "looks_like_mocha",
]

_COILS_A = ("ui", "li", "ul", "ll", "tt")
_COILS_B = ("tb", "td", "v", "coil10", "bn")
#: the 20 channels of a MOCHA-TIMIT .ema file, in file order
MOCHA_CHANNELS = tuple(
    [f"{c}_x" for c in _COILS_A]
    + [f"{c}_y" for c in _COILS_A]
    + [f"{c}_x" for c in _COILS_B]
    + [f"{c}_y" for c in _COILS_B]
)
#: MOCHA-TIMIT EMA units per millimetre: values are stored in 1/100 mm
MOCHA_SCALE = 0.01


def read_ema_track(path, *, scale: float = 1.0, default_channels=None) -> Track:
    """An EST EMA file as a :class:`~dam.corpus.formats.tracks.Track`.

    Parameters
    ----------
    path : path-like
    scale : float, default 1.0
        Multiplies every value (``MOCHA_SCALE`` turns MOCHA units into mm).
    default_channels : sequence of str, optional
        Names when the header has none; otherwise ``c0, c1, ...``.

    Returns
    -------
    Track
        Break frames (value flag 0) masked in every channel.
    """
    path = str(path)
    est = read_est(path)
    if len(est.times) < 2:
        raise DataError(path, "NumFrames", len(est.times), "need at least 2 frames")
    names = est.channels
    if names is None:
        n = est.values.shape[1]
        if default_channels is not None and len(default_channels) != n:
            raise DataError(
                path,
                "NumChannels",
                n,
                f"the {len(default_channels)}-channel layout does not fit and the header names no channels",
            )
        names = list(default_channels) if default_channels is not None else [f"c{i}" for i in range(n)]
    uniform_rate(est.times, path)  # refuses uneven frames, naming the first
    rate = stored_frame_rate(est.times)
    mask = np.repeat(est.present[:, None], est.values.shape[1], axis=1)
    start = float(est.times[0])
    if abs(start) <= 0.5 / rate:  # float32 times: a first frame within half a frame of 0 is at 0
        start = 0.0
    return Track(
        est.values * scale, list(names), rate, start_time=start, mask=None if mask.all() else mask, source=path
    )


def _load_est_corpus(
    path, *, fmt: str, scale: float, default_channels, read_alignment, frame_rate, silence: str, tier, metadata: dict
):
    root = Path(path)
    if not root.is_dir():
        raise DataError(str(root), "path", str(root), "not a directory")
    entries = []
    for stem, ema, lab in pair_by_stem(root, (".ema",), (".lab", ".textgrid"), what="EMA"):
        track = read_ema_track(ema, scale=scale, default_channels=default_channels)
        alignment = read_alignment(lab, tier=tier, silence=silence)
        entries.append((stem, alignment, track, audio_beside(ema)))
    return build_corpus(
        entries, frame_rate=frame_rate, name=root.name, source=str(root), metadata={"format": fmt, **metadata}
    )


def load_mocha_corpus(
    path,
    *,
    read_alignment,
    frame_rate: float | None = None,
    silence: str = SILENCE,
    tier: str | None = "phones",
    scale: float = MOCHA_SCALE,
    **_ignored,
):
    """Read a MOCHA-TIMIT speaker directory (``.ema`` + ``.lab`` [+ ``.wav``] per utterance).

    Parameters
    ----------
    path : path-like
    read_alignment : callable
        ``read_alignment(path, tier=, silence=)``, handed in by :func:`dam.corpus.io.load_corpus`.
    frame_rate : float, optional
        Resample (default: the files' own 500 frames/s).
    silence : str, default "sil"
    tier : str, default "phones"
        TextGrid tier, if the labels are TextGrids instead of ``.lab`` files.
    scale : float, default 0.01
        File units to millimetres.

    Returns
    -------
    Corpus
        Channels in mm; ``metadata`` has ``format: "mocha"`` and ``length_unit: "mm"``.
    """
    return _load_est_corpus(
        path,
        fmt="mocha",
        scale=scale,
        default_channels=MOCHA_CHANNELS,
        read_alignment=read_alignment,
        frame_rate=frame_rate,
        silence=silence,
        tier=tier,
        metadata={"length_unit": "mm"},
    )


def load_mngu0_corpus(
    path,
    *,
    read_alignment,
    frame_rate: float | None = None,
    silence: str = SILENCE,
    tier: str | None = "phones",
    **_ignored,
):
    """Read an mngu0 EMA directory (``.ema`` + ``.lab`` per utterance); values already in mm.

    Same parameters as :func:`load_mocha_corpus` (no scaling).
    """
    return _load_est_corpus(
        path,
        fmt="mngu0",
        scale=1.0,
        default_channels=None,
        read_alignment=read_alignment,
        frame_rate=frame_rate,
        silence=silence,
        tier=tier,
        metadata={"length_unit": "mm"},
    )


def looks_like_mocha(ema_path) -> bool:
    """True if an ``.ema`` file has MOCHA's 20-channel layout (by header names, or 20 unnamed channels)."""
    try:
        with open(ema_path, "rb") as fh:
            head = fh.read(4096)
    except OSError:
        return False
    text = head.split(b"EST_Header_End")[0].decode("latin-1")
    fields = dict(line.split(None, 1) for line in text.splitlines() if len(line.split(None, 1)) == 2)
    names = [v.strip() for k, v in fields.items() if k.startswith("Channel_")]
    if names:
        return set(names) >= {"tt_x", "tt_y", "ul_x", "ll_x"}
    return fields.get("NumChannels", "").strip() == "20"
