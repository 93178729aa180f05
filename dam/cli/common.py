"""Helpers every command shares: corpus names, ``--param`` values, messages on standard error."""

from __future__ import annotations

import argparse
import json
import sys

__all__ = ["corpus_arg", "parse_param", "info"]


def corpus_arg(spec):
    """A corpus directory or a bundled corpus name (``tiny``, ``vtl:train``) as a Corpus."""
    from dam.datasets import resolve

    return resolve(spec)


def parse_param(text: str) -> tuple[str, object]:
    """``key=value`` with value read as JSON when it can be (numbers, true/false, null, lists)."""
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"--param expects key=value, got {text!r}")
    key, _, raw = text.partition("=")
    lowered = {"true": True, "false": False, "none": None, "null": None}
    if raw.lower() in lowered:
        return key.strip(), lowered[raw.lower()]
    try:
        return key.strip(), json.loads(raw)
    except json.JSONDecodeError:
        return key.strip(), raw


def info(args, msg: str) -> None:
    """``msg`` on standard error unless ``--quiet``."""
    if not getattr(args, "quiet", False):
        print(msg, file=sys.stderr)
