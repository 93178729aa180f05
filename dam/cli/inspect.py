"""``dam inspect MODEL_FILE``: what a fitted DAM learned."""

from __future__ import annotations

import numpy as np

from dam.model import DAM, inspect_report
from dam.modelfile import load


def add_inspect(sub) -> None:
    """The ``dam inspect MODEL_FILE`` subcommand."""
    p = sub.add_parser(
        "inspect",
        help="print what a fitted DAM learned",
        description="Summary of a fitted DAM (or dam-m0): per phone its modes, their "
        "training counts and sigmas; EM convergence per channel; phones "
        "with one mode and why. With --phone, that phone's modes in full "
        "(sigmas per channel and the paper's monomial coefficients).",
    )
    p.add_argument("model_file", metavar="MODEL_FILE")
    p.add_argument("--phone", action="append", default=None, help="show this phone in full (repeatable)")
    p.set_defaults(func=cmd_inspect)


def cmd_inspect(args) -> int:
    model = load(args.model_file)
    if not isinstance(model, DAM):
        raise TypeError(
            f"{args.model_file}: holds a {type(model).__name__} ({model.name!r}); "
            "`dam inspect` reads DAM model files (dam, dam-m0)"
        )
    print(inspect_report(model))
    for phone in args.phone or ():
        info = model.modes_of(phone)
        print(
            f"\nphone {phone!r}: {info['n_modes']} mode(s)"
            + (f" ({info['single_mode']})" if info["single_mode"] else "")
        )
        with np.printoptions(precision=4, suppress=True, linewidth=120):
            for g in range(info["n_modes"]):
                print(f"  mode {g}: {int(info['counts'][g])} occurrences")
                for c, ch in enumerate(model.channels_):
                    print(f"    {ch:>14}: sigma={info['sigma'][g, c]:.3f}  a^0..a^M={info['coef_monomial'][g, :, c]}")
    return 0
