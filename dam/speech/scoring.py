"""Comparing phone sequences: edit distance and phone error rate."""

from __future__ import annotations

__all__ = ["edit_distance", "phone_error_rate"]


def edit_distance(a, b) -> int:
    """Levenshtein distance between two sequences (substitutions, insertions, deletions cost 1).

    Examples
    --------
    >>> from dam.speech.scoring import edit_distance
    >>> edit_distance(["K", "AE", "T"], ["K", "AA", "T", "S"])
    2
    """
    row = list(range(len(b) + 1))
    for i in range(1, len(a) + 1):
        prev, row[0] = row[:], i
        for j in range(1, len(b) + 1):
            row[j] = min(prev[j] + 1, row[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1]))
    return row[-1]


def phone_error_rate(hypotheses, references) -> float:
    """Summed edit distance over summed reference length, for lists of phone sequences."""
    total = sum(len(r) for r in references)
    if total == 0:
        raise ValueError("the references hold no phones")
    return sum(edit_distance(h, r) for h, r in zip(hypotheses, references, strict=True)) / total
