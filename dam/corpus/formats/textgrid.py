"""Praat TextGrids (long and short text format), read and written through praatio."""
from __future__ import annotations

import os

from dam.corpus.data import SILENCE, Alignment, DataError

__all__ = ["read_textgrid", "write_textgrid"]


def read_textgrid(path, *, tier: str | None = "phones", silence: str = SILENCE) -> Alignment:
    """Read one interval tier of a Praat TextGrid (long or short text format).

    Parameters
    ----------
    path : path-like
    tier : str or None, default "phones"
        Tier name. If the TextGrid has no tier of that name (and ``tier`` is
        the default), the first interval tier is used; a name given
        explicitly must exist.
    silence : str, default "sil"
    """
    from praatio import textgrid as ptg
    path = os.fspath(path)
    try:
        tg = ptg.openTextgrid(path, includeEmptyIntervals=True, reportingMode="silence")
    except Exception as exc:  # praatio raises many types for malformed files
        detail = " ".join(str(exc).split())
        raise DataError(path, "TextGrid", type(exc).__name__, f"cannot be parsed: {detail}") from None
    interval_tiers = [n for n in tg.tierNames if isinstance(tg.getTier(n), ptg.IntervalTier)]
    if tier in tg.tierNames and tier in interval_tiers:
        name = tier
    elif tier is not None and tier != "phones":
        raise DataError(path, "tier", tier, "no interval tier of that name",
                        f"interval tiers: {interval_tiers}")
    elif interval_tiers:
        name = interval_tiers[0]
    else:
        raise DataError(path, "tier", tier, "the TextGrid has no interval tier")
    entries = tg.getTier(name).entries
    if not entries:
        raise DataError(path, f"tier {name!r}", 0, "the tier has no intervals")
    labels = [e.label for e in entries]
    return Alignment(labels, [e.start for e in entries], [e.end for e in entries],
                     source=path, silence=silence)


def write_textgrid(alignment: Alignment, path, *, tier: str = "phones",
                   format: str = "long_textgrid") -> None:
    """Write ``alignment`` as a one-tier Praat TextGrid (silence keeps its canonical label)."""
    from praatio import textgrid as ptg
    entries = list(zip(alignment.starts.tolist(), alignment.ends.tolist(), alignment.labels))
    tg = ptg.Textgrid()
    tg.addTier(ptg.IntervalTier(tier, entries, 0.0, alignment.duration))
    tg.save(os.fspath(path), format=format, includeBlankSpaces=True, reportingMode="silence")
