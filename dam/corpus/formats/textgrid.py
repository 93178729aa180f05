"""Praat TextGrids (long and short text format), read and written through praatio."""

from __future__ import annotations

import os

from dam.corpus.atomic import atomic_path
from dam.corpus.data import SILENCE, Alignment, DataError
from dam.corpus.encoding import read_text

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
    read_text(path)  # the encoding rule of dam.corpus.encoding, with the byte offset of a bad byte
    try:
        tg = ptg.openTextgrid(path, includeEmptyIntervals=True, reportingMode="silence")
    except Exception as exc:  # praatio raises many types for malformed files
        detail = " ".join(str(exc).split())
        tg = _snapped_textgrid(path) if "overlap" in detail else None
        if tg is None:
            raise DataError(path, "TextGrid", type(exc).__name__, f"cannot be parsed: {detail}") from None
    interval_tiers = [n for n in tg.tierNames if isinstance(tg.getTier(n), ptg.IntervalTier)]
    if tier in tg.tierNames and tier in interval_tiers:
        name = tier
    elif tier is not None and tier != "phones":
        raise DataError(path, "tier", tier, "no interval tier of that name", f"interval tiers: {interval_tiers}")
    elif interval_tiers:
        name = interval_tiers[0]
    else:
        raise DataError(path, "tier", tier, "the TextGrid has no interval tier")
    entries = tg.getTier(name).entries
    if not entries:
        raise DataError(path, f"tier {name!r}", 0, "the tier has no intervals")
    labels = [e.label for e in entries]
    return Alignment(labels, [e.start for e in entries], [e.end for e in entries], source=path, silence=silence)


def _snapped_textgrid(path):
    """The TextGrid at ``path`` with overlaps below :data:`~dam.corpus.data.TIME_TOL` (1 µs) snapped.

    Other tools write boundaries with float noise (an interval starting 1e-16 s before its
    neighbour ends), which praatio refuses as an overlap: such a start is moved to the previous
    end. A longer overlap is a DataError naming the interval; None if the file cannot be parsed.
    """
    from praatio import textgrid as ptg
    from praatio.utilities import textgrid_io

    from dam.corpus.data import TIME_TOL

    try:
        parsed = textgrid_io.parseTextgridStr(read_text(path), includeEmptyIntervals=True)
        tg = ptg.Textgrid()
        for t in parsed["tiers"]:
            entries = [(float(e[0]), float(e[1]), e[2]) for e in t["entries"]]
            if t["class"] != "IntervalTier":
                tg.addTier(ptg.PointTier(t["name"], entries, float(t["xmin"]), float(t["xmax"])))
                continue
            for i in range(1, len(entries)):
                start, prev_end = entries[i][0], entries[i - 1][1]
                if prev_end - TIME_TOL <= start < prev_end:
                    entries[i] = (prev_end,) + entries[i][1:]
                elif start < prev_end:
                    raise DataError(
                        path,
                        f"tier {t['name']!r} interval {i + 1} xmin",
                        start,
                        f"overlaps the previous interval {entries[i - 1][2]!r} (which ends at "
                        f"{prev_end:g}) by {prev_end - start:.3g} s",
                        "overlaps below 1 microsecond are snapped; longer ones are errors",
                    )
            tg.addTier(ptg.IntervalTier(t["name"], entries, float(t["xmin"]), float(t["xmax"])))
        return tg
    except DataError:
        raise
    except Exception:
        return None


def write_textgrid(alignment: Alignment, path, *, tier: str = "phones", format: str = "long_textgrid") -> None:
    """Write ``alignment`` as a one-tier Praat TextGrid (silence keeps its canonical label)."""
    from praatio import textgrid as ptg

    entries = list(zip(alignment.starts.tolist(), alignment.ends.tolist(), alignment.labels))
    tg = ptg.Textgrid()
    tg.addTier(ptg.IntervalTier(tier, entries, 0.0, alignment.duration))
    with atomic_path(path) as tmp:
        tg.save(tmp, format=format, includeBlankSpaces=True, reportingMode="silence")
