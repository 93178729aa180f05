"""A Praat TextGrid of the phones an animation was made from, and the DAM's chosen modes.

Tier ``phones``: one interval per segment, its label. Tier ``modes`` (when
the modes are known): the same intervals, each labelled with the mode the
DAM chose for that phone (its local index, ``0 .. n_modes - 1``, as
:meth:`dam.model.DAM.synthesize` takes them). Written with praatio, the
library :func:`dam.corpus.read_textgrid` reads with.
"""

from __future__ import annotations

from dam.corpus import DataError
from dam.corpus.atomic import atomic_path

from .tables import ExportReport, _check_modes, check_animation

__all__ = ["write_phones_textgrid", "chosen_modes"]


def chosen_modes(model, alignment):
    """Local mode of every segment that ``model`` would choose, or None for a model without modes.

    Parameters
    ----------
    model : Synthesizer
        A fitted model; the DAM (anything with ``select_modes`` and ``phone_modes_``) has modes.
    alignment : Alignment

    Returns
    -------
    list of int, length len(alignment), or None
    """
    if not hasattr(model, "select_modes") or not hasattr(model, "phone_modes_"):
        return None
    glob, _ = model.select_modes(alignment)
    labels = model._known_labels(alignment, getattr(model, "unknown_phone", "error"))
    return [int(g - model.phone_modes_[lab][0]) for g, lab in zip(glob, labels)]


def write_phones_textgrid(
    values, path, *, channels, frame_rate, alignment=None, metadata=None, modes=None, **options
) -> ExportReport:
    """Write the phones (and modes) of an animation as a long-format Praat TextGrid.

    Parameters
    ----------
    values : ndarray, shape (n_frames, n_channels)
        The animation (checked for consistency with the alignment; not written).
    path : str
    channels : sequence of str
    frame_rate : float
    alignment : Alignment
        Required: the phones.
    metadata : dict, optional
        Not stored (a TextGrid has no place for it).
    modes : sequence of int, optional
        Local mode per segment (:func:`chosen_modes`); adds the ``modes`` tier.
    """
    from praatio import textgrid as ptg

    if options:
        name = sorted(options)[0]
        raise DataError(path, name, options[name], "not an option of the TextGrid format")
    if alignment is None:
        raise DataError(path, "alignment", None, "a TextGrid export needs the phones (alignment=...)")
    values, channels, frame_rate = check_animation(values, channels, frame_rate, path, alignment)
    modes = _check_modes(modes, alignment, path)
    # the grid spans the animation: its last frame may lie a little past the last phone
    end = max(alignment.duration, (len(values) - 1) / frame_rate)
    spans = list(zip(alignment.starts.tolist(), alignment.ends.tolist()))
    tg = ptg.Textgrid()
    tg.addTier(ptg.IntervalTier("phones", [(s, e, lab) for (s, e), lab in zip(spans, alignment.labels)], 0.0, end))
    if modes is not None:
        tg.addTier(ptg.IntervalTier("modes", [(s, e, str(m)) for (s, e), m in zip(spans, modes)], 0.0, end))
    with atomic_path(path) as tmp:
        tg.save(tmp, format="long_textgrid", includeBlankSpaces=True, reportingMode="silence")
    return ExportReport(path, "textgrid", values.shape[0], values.shape[1], frame_rate)
