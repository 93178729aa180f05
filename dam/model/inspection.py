"""What a fitted DAM learned, as text: modes per phone, sigmas, EM convergence."""

from __future__ import annotations

import numpy as np

from dam.model.estimator import DAM

__all__ = ["inspect_report"]


def inspect_report(model: DAM, *, max_phones: int | None = None) -> str:
    """A readable summary of a fitted DAM (what ``dam inspect MODEL_FILE`` prints).

    Per phone: training count, modes with their occurrence counts, and the
    median sigma over channels per mode; then the EM convergence per channel
    and the phones that have one mode and why.
    """
    model._check_fitted()
    ch = list(model.channels_)
    lines = [
        f"{type(model).__name__} ({model.name}): degree M={model.degree}, "
        f"{'weighted average' if model.normalize else 'plain sum'} (Eq. 2), "
        f"extrapolate={model.extrapolate!r}, modes={model.modes!r}",
        f"{len(model.phone_modes_)} phones, {len(model.mode_phone_)} modes, {len(ch)} channels "
        f"@ {model.frame_rate_:g} Hz: {' '.join(ch)}",
        f"A* weights w_c={model.w_c:g}, w_s={model.w_s:g}; dominance truncated below "
        f"{model.dominance_tol:g}; median phone duration {model.time_scale_ * 1000:.0f} ms",
        "",
        f"{'phone':>8} {'count':>6} {'modes':>5}  mode sizes / median sigma (durations)",
    ]
    phones = list(model.phone_modes_)[:max_phones] if max_phones else list(model.phone_modes_)
    for p in phones:
        first, G = model.phone_modes_[p]
        parts = [f"{int(model.mode_counts_[first + g])}/{np.median(model.sigma_[first + g]):.2f}" for g in range(G)]
        lines.append(f"{p:>8} {model.phone_counts_.get(p, 0):>6} {G:>5}  {'  '.join(parts)}")
    if len(ch) and len(model.loss_curve_):
        w = max(12, *(len(c) for c in ch))
        lines += ["", f"{'channel':>{w}} {'iters':>5} {'conv':>5}  EM objective (MSE + ridge) first -> last"]
        for c, name in enumerate(ch):
            cur = model.loss_curve_[c]
            lines.append(
                f"{name:>{w}} {int(model.n_iter_[c]):>5} {str(bool(model.converged_[c])):>5}  "
                f"{cur[0]:.4g} -> {cur[-1]:.4g}"
            )
    if model.single_mode_:
        lines += ["", "phones with one mode:"]
        why: dict[str, list] = {}
        for p, r in model.single_mode_.items():
            why.setdefault(r, []).append(p)
        for r, ps in why.items():
            lines.append(f"  {r}: {' '.join(ps)}")
    return "\n".join(lines)
