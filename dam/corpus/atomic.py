"""Atomic file writing and output-path checks: nothing the toolkit writes is ever half a file.

Every file dam writes (model files, corpus files, EST tracks, comparison
tables and figures, exports) goes through :func:`atomic_write` (a file
object) or :func:`atomic_path` (a temporary path, for writers that only
take a file name). Both write a temporary file in the destination's own
directory, flush and ``fsync`` it, then ``os.replace`` it over the
destination: a reader, a crash, a kill or a full disk leaves the old file or
the new one, never a mixture, and two processes saving to one path leave one
complete file (the last to finish). On failure the temporary file is removed
and the destination is untouched.

:func:`atomic_directory` does the same for a directory written as a whole
(a generated corpus). :func:`check_output` is the check every command runs on
its output paths before any work starts: an output is never one of the inputs
and never inside an input directory, its directory exists, and an existing
directory that holds other files is replaced only when asked (``overwrite``).

This module is on the ground floor: it imports nothing else from dam except
:class:`dam.corpus.data.DataError`.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from typing import IO

from dam.corpus.data import DataError

__all__ = ["atomic_write", "atomic_path", "atomic_directory", "check_output", "OutputPathError", "TEMP_PREFIX"]

#: Temporary files start with this (plus the destination's name), so a file left by a
#: process killed before its rename is recognisable and never mistaken for the output.
TEMP_PREFIX = ".dam-tmp-"


class OutputPathError(DataError):
    """An output path that would overwrite an input, or lies in a missing directory."""


def _fsync_dir(directory: str) -> None:
    """Make the rename itself durable (POSIX); a no-op where directories cannot be opened."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _temp_name(path: str, *, directory: bool = False) -> str:
    d = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(d):
        raise OutputPathError(path, "directory", d, "the output directory does not exist", "create it first")
    base = TEMP_PREFIX + os.path.basename(path) + "-"
    if directory:
        return tempfile.mkdtemp(dir=d, prefix=base)
    fd, tmp = tempfile.mkstemp(dir=d, prefix=base)
    os.close(fd)
    return tmp


@contextlib.contextmanager
def atomic_path(path) -> Iterator[str]:
    """A temporary path beside ``path`` that replaces ``path`` when the block succeeds.

    For writers that take a file name (praatio, matplotlib's ``savefig``).
    The temporary file exists (empty) when the block starts; the writer
    overwrites it. On an exception it is removed and ``path`` is untouched.

    Parameters
    ----------
    path : path-like
        The destination. Its directory must exist.

    Yields
    ------
    str
        The temporary path to write to.

    Examples
    --------
    >>> import os, tempfile
    >>> from dam.corpus.atomic import atomic_path
    >>> d = tempfile.mkdtemp()
    >>> with atomic_path(os.path.join(d, "a.txt")) as tmp:
    ...     _ = open(tmp, "w").write("hello")
    >>> open(os.path.join(d, "a.txt")).read()
    'hello'
    """
    path = os.fspath(path)
    if os.path.isdir(path):
        raise OutputPathError(path, "output", path, "is a directory, not a file")
    tmp = _temp_name(path)
    try:
        yield tmp
        # The writer may have closed its own handle without syncing: sync by path.
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        _keep_mode(path, tmp)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    _fsync_dir(os.path.dirname(os.path.abspath(path)))


def _keep_mode(path: str, tmp: str) -> None:
    """The new file gets the old one's permissions (else the usual umask default, not mkstemp's 0600)."""
    try:
        mode = os.stat(path).st_mode & 0o7777
    except OSError:
        mode = 0o666 & ~_umask()
    with contextlib.suppress(OSError):
        os.chmod(tmp, mode)


@contextlib.contextmanager
def atomic_write(path, mode: str = "w", *, encoding: str | None = "utf-8", newline: str | None = None) -> Iterator[IO]:
    """Open a temporary file that atomically replaces ``path`` when the block succeeds.

    Parameters
    ----------
    path : path-like
        The destination. Its directory must exist.
    mode : {"w", "wb"}, default "w"
        Text or binary.
    encoding : str, default "utf-8"
        Text mode only.
    newline : str, optional
        Text mode only, as :func:`open`.

    Yields
    ------
    file object
        Write to it; it is flushed, ``fsync``-ed and renamed over ``path``
        after the block. If the block raises (or the write fails: disk full),
        the temporary file is removed and ``path`` keeps its old content.

    Raises
    ------
    OutputPathError
        ``path`` is a directory or its directory does not exist.

    Examples
    --------
    >>> import os, tempfile
    >>> from dam.corpus.atomic import atomic_write
    >>> p = os.path.join(tempfile.mkdtemp(), "model.txt")
    >>> with atomic_write(p) as fh:
    ...     _ = fh.write("new")
    >>> open(p).read()
    'new'
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_write: mode is {mode!r}; use 'w' or 'wb'")
    with atomic_path(path) as tmp:
        if mode == "wb":
            fh = open(tmp, "wb")
        else:
            fh = open(tmp, "w", encoding=encoding, newline=newline)
        with fh:
            yield fh
            fh.flush()


@contextlib.contextmanager
def atomic_directory(path, *, overwrite: bool = False) -> Iterator[str]:
    """A temporary directory that becomes ``path`` when the block succeeds.

    For a directory written as a whole (a generated corpus): readers see no
    directory, the old one or the complete new one. An existing ``path`` is
    replaced only with ``overwrite=True`` (the old directory is renamed away,
    the new one renamed in, then the old one deleted); without it an existing
    non-empty ``path`` raises :class:`OutputPathError` before anything is written.

    Yields
    ------
    str
        The temporary directory to fill.
    """
    path = os.fspath(path).rstrip(os.sep) or os.sep
    if os.path.exists(path):
        if not os.path.isdir(path):
            raise OutputPathError(path, "output", path, "exists and is not a directory")
        if os.listdir(path) and not overwrite:
            raise OutputPathError(
                path,
                "output",
                path,
                "the directory exists and is not empty",
                "choose a new directory or pass overwrite (--overwrite) to replace it",
            )
    tmp = _temp_name(path, directory=True)
    old = None
    try:
        yield tmp
        os.chmod(tmp, 0o777 & ~_umask())
        if os.path.isdir(path):
            old = os.path.join(_temp_name(path + "-old", directory=True), "d")
            os.replace(path, old)
        os.replace(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        if old is not None and os.path.isdir(old) and not os.path.exists(path):
            os.replace(old, path)  # the new directory could not be moved in: put the old one back
        raise
    finally:
        if old is not None:
            shutil.rmtree(os.path.dirname(old), ignore_errors=True)
    _fsync_dir(os.path.dirname(os.path.abspath(path)))


def _umask() -> int:
    """The process umask, read without changing it where the system allows (threads may be writing)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    m = os.umask(0)
    os.umask(m)
    return m


# -- output paths -----------------------------------------------------------------
def _same(a: str, b: str) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.realpath(a) == os.path.realpath(b)


def _inside(path: str, directory: str) -> bool:
    d = os.path.realpath(directory)
    p = os.path.realpath(path)
    return os.path.commonpath([p, d]) == d


def check_output(
    path,
    *,
    inputs: Iterable = (),
    directory: bool = False,
    overwrite: bool = False,
    merge: bool = False,
    option: str = "-o",
) -> str:
    """Check an output path before any work starts; return it as a string.

    Parameters
    ----------
    path : path-like
        Where the command will write (a file, or with ``directory=True`` a directory).
        ``-`` (standard output) is the caller's business and is refused here.
    inputs : iterable of path-like
        The command's input files and directories (None entries and names that
        are not existing paths, such as a bundled corpus name, are ignored).
    directory : bool, default False
        ``path`` is a directory the command fills.
    overwrite : bool, default False
        Allow replacing an existing directory that holds files, or an existing
        file of a corpus directory (never an input, never a directory holding one).
        Other existing files are replaced (atomically) without it.
    merge : bool, default False
        The command adds its own named files to the directory (``dam compare``):
        an existing directory is fine unless it holds a corpus (alignment or
        trajectory files, ``corpus.json``), which needs ``overwrite``.
    option : str, default "-o"
        The option name, for the message.

    Raises
    ------
    OutputPathError
        ``path`` is an input, lies inside an input directory, is a directory
        where a file is meant (or the reverse), its parent directory does not
        exist, or it is a directory that holds files, or a file of a corpus
        (an alignment, ``corpus.json``, a trajectory beside its alignment),
        and may not be written over.

    Examples
    --------
    >>> import os, tempfile
    >>> from dam.corpus.atomic import OutputPathError, check_output
    >>> d = tempfile.mkdtemp(); src = os.path.join(d, "u.TextGrid"); _ = open(src, "w").write("x")
    >>> try:
    ...     check_output(src, inputs=[src])
    ... except OutputPathError as exc:
    ...     print("refused:", "is an input" in str(exc))
    refused: True
    """
    p = os.fspath(path)
    if p == "-":
        raise OutputPathError(p, option, p, "this output cannot go to standard output", "give a path")
    if p == "":
        raise OutputPathError(p, option, p, "empty output path")
    for src in inputs:
        if src is None:
            continue
        s = os.fspath(src)
        if not os.path.exists(s):
            continue
        if _same(p, s):
            raise OutputPathError(p, option, p, f"is an input of this command ({s})", "write the output elsewhere")
        if os.path.isdir(s) and _inside(p, s):
            raise OutputPathError(p, option, p, f"lies inside the input directory {s}", "write the output elsewhere")
        if directory and not merge and _inside(s, p):
            raise OutputPathError(
                p,
                option,
                p,
                f"holds the input {s}, which writing this directory would replace",
                "write the output elsewhere",
            )
    parent = os.path.dirname(os.path.abspath(p))
    if not os.path.isdir(parent):
        raise OutputPathError(p, option, parent, "the output directory does not exist", "create it first")
    if directory:
        if os.path.exists(p) and not os.path.isdir(p):
            raise OutputPathError(p, option, p, "exists and is not a directory")
        if os.path.isdir(p) and not overwrite:
            names = os.listdir(p)
            if merge:
                corpus = [
                    n
                    for n in sorted(names)
                    if n == "corpus.json" or os.path.splitext(n)[1].lower() in (".textgrid", ".lab", ".par")
                ]
                if corpus:
                    raise OutputPathError(
                        p,
                        option,
                        p,
                        f"the directory holds a corpus ({corpus[0]} ...)",
                        "choose another directory or pass --overwrite",
                    )
            elif names:
                raise OutputPathError(
                    p,
                    option,
                    p,
                    "the directory exists and holds files",
                    "choose a new directory or pass --overwrite to replace it",
                )
    elif os.path.isdir(p):
        raise OutputPathError(p, option, p, "is a directory; give a file name")
    elif os.path.isfile(p) and not overwrite and _corpus_member(p):
        raise OutputPathError(
            p, option, p, "is a file of the corpus in its directory (recorded data)", "write the output elsewhere"
        )
    return p


_ALIGNMENT_SUFFIXES = (".textgrid", ".lab", ".par")
_TRAJECTORY_SUFFIXES = (".csv", ".npy", ".ema", ".est", ".trk", ".wav")


def _corpus_member(path: str) -> bool:
    """``path`` is ``corpus.json``, or one file of an utterance of a corpus directory (an
    alignment beside a trajectory of the same stem, or the reverse): recorded data, which an
    output must not replace silently."""
    name = os.path.basename(path)
    if name == "corpus.json":
        return True
    stem, suffix = os.path.splitext(name)
    suffix = suffix.lower()
    partners = (
        _TRAJECTORY_SUFFIXES
        if suffix in _ALIGNMENT_SUFFIXES
        else _ALIGNMENT_SUFFIXES
        if suffix in _TRAJECTORY_SUFFIXES
        else ()
    )
    d = os.path.dirname(os.path.abspath(path))
    try:
        siblings = {os.path.splitext(n)[0] + os.path.splitext(n)[1].lower() for n in os.listdir(d)}
    except OSError:
        return False
    return any(stem + s in siblings for s in partners)
