"""The ``dam`` command line. Nothing in the library imports this package.

Conventions: ``--help`` on every command; results on standard output,
progress and messages on standard error; exit status 0 on success, 1 on bad
input (a one-line ``dam: error: ...`` naming the file, the field and the
value, never a traceback; ``--debug`` shows it), 2 on bad usage.

A command group is a module here with functions ``add_<name>(subparsers)``
that register a parser and set ``func``; :data:`COMMANDS` lists them in the
order ``dam --help`` shows them. Keep heavy imports inside the handlers.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from dam._version import __version__
from dam.cli.common import parse_param  # noqa: F401  (kept importable: dam.cli.parse_param)
from dam.progress import MODES as PROGRESS_MODES

# "module:function" adders, in the order of `dam --help`.
COMMANDS: list[str] = [
    "dam.cli.models:add_models",
    "dam.cli.models:add_fit",
    "dam.cli.models:add_predict",
    "dam.cli.models:add_evaluate",
    "dam.cli.compare:add_demo",
    "dam.cli.compare:add_compare",
    "dam.cli.inspect:add_inspect",
    "dam.cli.rig:add_crossmap",
    "dam.cli.rig:add_retarget",
    "dam.cli.rig:add_rigsolve",
    "dam.cli.datasets:add_generate_vtl",
    "dam.cli.datasets:add_vtl_audio",
    "dam.cli.datasets:add_vtl_lexicon",
    "dam.cli.datasets:add_generate_tiny",
    "dam.cli.speech:add_align",
    "dam.cli.speech:add_animate",
    "dam.cli.export:add_export_runtime",
]


# -- parser and main ------------------------------------------------------
def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="dam",
        description="Speech animation and coarticulation modelling: fit, predict, evaluate "
        "and compare synthesizers that turn phone timings into trajectories.",
    )
    parser.add_argument("--version", action="version", version=f"dam {__version__}")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress or messages on standard error")
    parser.add_argument("--debug", action="store_true", help="show Python tracebacks on errors")
    parser.add_argument("--progress", choices=PROGRESS_MODES, default="auto", help=PROGRESS_HELP)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for spec in COMMANDS:
        module, _, fn = spec.partition(":")
        getattr(importlib.import_module(module), fn)(sub)
    for p in sub.choices.values():  # `dam fit ... --quiet` works as well as `dam --quiet fit ...`
        have = {o for a in p._actions for o in a.option_strings}
        if "--quiet" not in have:
            p.add_argument(
                "-q",
                "--quiet",
                action="store_true",
                default=argparse.SUPPRESS,
                help="no progress or messages on standard error",
            )
        if "--progress" not in have:
            p.add_argument("--progress", choices=PROGRESS_MODES, default=argparse.SUPPRESS, help=PROGRESS_HELP)
    return parser


PROGRESS_HELP = (
    "progress on standard error: auto (a bar with the time left, on a terminal only; the default), "
    "bar, json (one JSON object per line per step, for programs embedding dam) or none"
)


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    from dam.progress import reporting

    try:
        with reporting(args.progress, quiet=args.quiet):
            return int(args.func(args) or 0)
    except KeyboardInterrupt:
        print("dam: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except Exception as exc:
        if args.debug:
            raise
        msg = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
        msg = msg.removeprefix("<input>: ")  # a DataError about a command-line value names no file
        print(f"dam: error: {msg}", file=sys.stderr)
        return 1
