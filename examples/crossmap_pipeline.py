"""From captured motion to a character's controls, and a DAM trained on them.

The whole path of Chen et al. (2012), with VocalTractLab standing in for the
capture session:

1. *captured motion*: VTL's articulatory model speaks German phrases; every
   frame's midsagittal vocal-tract outline (upper, lower and tongue
   contours, resampled to fixed points) is the captured shape;
2. *key shapes*: affinity propagation picks exemplar frames (Appendix A);
3. *blend weights*: every captured frame as a non-negative blend of the key
   shapes (NNLS);
4. *the target character*: a small blendshape rig with 7 controls in [0, 1]
   (jaw_open, tongue_front, lip_round, ...), with its own proportions; an
   "artist" poses each key shape on it (simulated here by the bounded
   least-squares pose closest to the key shape in the character's
   proportions);
5. *controls*: the blended target vertices of every frame, fitted by the rig's
   controls, bounded in [0, 1];
6. *the DAM* is trained on those controls and synthesizes a held-out phrase
   from its phone timings alone;
7. *rig-space retargeting* (Taylor et al. 2017, Sec. 6) carries the
   synthesized animation to a second character with other controls: the
   principal modes of the first character's controls at +/-3 standard
   deviations are posed once on the second rig, and every frame becomes a
   piece-wise linear blend of those poses.

Each step saves a figure in the output directory, and ``metrics.json`` holds
the numbers. The VTL phrases come from the bundled ``vtl`` corpus when it is
installed, otherwise they are synthesized once (one to two minutes) and cached
in ``<out>/cache`` (git-ignored).

Is it a fair showcase? The DAM (quartic animemes, several modes per phone) needs data: trained on
half a minute of phrases (13) it overfits and loses to the per-phone mean, from about two minutes
on it wins (``benchmarks/bench_crossmap.py`` runs both; the README quotes its table). The default
is two minutes, scored on five held-out phrases. The synthesized controls are clipped to the rig's
[0, 1] before they drive a character (the DAM's polynomials may overshoot the bounds the
cross-mapping respects; ``metrics.json`` records by how much).

Run::

    python examples/crossmap_pipeline.py                 # figures in ./dam-examples/crossmap_pipeline/
    python examples/crossmap_pipeline.py --out /tmp/cm --model phone-mean --minutes 0.3
    python examples/crossmap_pipeline.py --quick         # a few phrases, a short fit: a smoke test
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

import dam
from dam import plotting
from dam.corpus.data import Corpus
from dam.crossmap.crossmapping import CrossMapper, blend_weights, fit_controls
from dam.crossmap.outlines import outline_corpus, plot_outline, toy_tract_rig
from dam.crossmap.retarget import RigSpaceRetargeter
from dam.crossmap.rig import LinearRig
from dam.evaluation.metrics import pearson_per_channel, rmse_per_channel

CONTOURS = ("upper", "lower", "tongue")
N_POINTS = 12
#: The character's proportions: a longer, flatter vocal tract than the speaker's.
CHARACTER_SCALE = (1.25, 0.85)
#: The second character (step 7): other proportions and only five controls.
SECOND_SCALE = (0.9, 1.1)
SECOND_CONTROLS = ("jaw_open", "tongue_front", "lip_round", "lip_close", "tip_up")


NAME = "crossmap_pipeline"


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


# -- 1. captured motion ---------------------------------------------------------
def tract_corpora(minutes: float, cache: str, seed: int = 0, n_test: int = 5) -> tuple[Corpus, Corpus]:
    """(train, test) corpora of VTL tract parameters with disjoint words (``n_test`` test phrases)."""
    from dam import datasets

    try:
        train, test = datasets.load("vtl", "train"), datasets.load("vtl", "test")
    except (KeyError, dam.DataError):  # not bundled (yet) in this install
        train = None
    if train is not None:
        n, total = 0, 0.0
        while n < len(train) and total < 60 * minutes:
            total += train[n].duration
            n += 1
        log(f"captured motion: bundled vtl corpus, {n} training phrases ({total:.0f} s)")
        return train[:n], test[:n_test]
    from dam.corpus.io import load_corpus
    from dam.datasets.vtl import generate_vtl_corpus

    root = os.path.join(cache, f"vtl-{minutes:g}min-seed{seed}")
    paths = [os.path.join(root, s) for s in ("train", "test")]
    if all(os.path.exists(os.path.join(p, "corpus.json")) for p in paths):
        log(f"captured motion: cached VTL phrases in {root}")
        return load_corpus(paths[0]), load_corpus(paths[1])[:n_test]
    os.makedirs(cache, exist_ok=True)
    with open(os.path.join(cache, ".gitignore"), "w") as fh:  # a cache, not a result: keep it out of git
        fh.write("*\n")
    log(f"captured motion: synthesizing {minutes:g} min of phrases with VocalTractLab into {root} ...")
    corpora = generate_vtl_corpus(
        root, seed=seed, n_train_minutes=minutes, n_test_minutes=0.05, audio_fraction=0.0, overwrite=True
    )
    return corpora["train"], corpora["test"][:n_test]


def frame_phones(utt):
    return [utt.alignment.labels[i] for i in utt.alignment.segment_index(utt.frame_rate, utt.n_frames)]


def figure_captured(outlines: Corpus):
    """Step 1: six captured outlines, and three outline points over time with the phones underneath."""
    utt = outlines[0]
    labels = frame_phones(utt)
    fig, axes, _ = plotting.time_grid(
        1,
        1,
        utt.alignment,
        panel_size=(8.0, 2.6),
        title=f"Step 1, captured motion: VocalTractLab vocal-tract outlines of {utt.name} (vtl:train)",
    )
    ax_shapes = fig.add_axes((1.02, 0.25, 0.3, 0.65))  # the outlines beside the time panel
    picks = [i for i in range(0, utt.n_frames, max(1, utt.n_frames // 6))][:6]
    for j, i in enumerate(picks):
        plot_outline(
            utt.trajectory[i],
            contours=CONTOURS,
            n_points=N_POINTS,
            ax=ax_shapes,
            color=plotting.model_color(j),
            label=f"{i / utt.frame_rate:.2f} s /{labels[i]}/",
        )
    ax_shapes.set_title("six frames (outlines)", fontsize=9)
    ax_shapes.set_xlabel("x (cm)")
    ax_shapes.set_ylabel("y (cm)")
    ax_shapes.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=7)
    t = np.arange(utt.n_frames) / utt.frame_rate
    names = list(outlines.channels)
    ax = axes[0, 0]
    for k, ch in enumerate(("tongue11_y", "tongue06_y", "lower11_y")):
        ax.plot(t, utt.trajectory[:, names.index(ch)], color=plotting.model_color(k), label=ch)
    ax.set_ylabel("height of three\noutline points (cm)")
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncols=3, fontsize=7)
    return fig


def figure_key_shapes(cm: CrossMapper, outlines: Corpus):
    """Step 2: the key shapes affinity propagation chose, each with the phone of its frame."""
    frames_phone = [p for u in outlines for p in frame_phones(u)]
    K = len(cm.key_shapes_)
    cols = min(K, 7)
    rows = int(np.ceil(K / cols))
    fig, axes = plotting.figure(
        rows,
        cols,
        panel_size=(1.8, 1.6),
        title=f"Step 2: {K} key shapes found by affinity propagation over "
        f"{sum(u.n_frames for u in outlines)} captured frames (outlines, cm)",
    )
    for k, ax in enumerate(axes.ravel()):
        ax.axis("off")
        if k < K:
            plot_outline(cm.key_shapes_[k], contours=CONTOURS, n_points=N_POINTS, ax=ax, color=plotting.TRUTH, lw=1)
            ax.set_title(f"key {k + 1}: /{frames_phone[cm.key_frame_indices_[k]]}/", fontsize=8)
    return fig


def figure_weights(cm: CrossMapper, utt):
    """Step 3: NNLS blend weights of one utterance and the error of the blend; returns (fig, rmse in cm)."""
    W = blend_weights(utt.trajectory, cm.key_shapes_)
    err = np.sqrt(((W @ cm.key_shapes_ - utt.trajectory) ** 2).mean(axis=1))
    t = np.arange(utt.n_frames) / utt.frame_rate
    fig, axes, _ = plotting.time_grid(
        2,
        1,
        utt.alignment,
        panel_size=(9.0, 1.9),
        title=f"Step 3: NNLS blend weights of the key shapes over {utt.name} (alpha >= 0), and the error of the blend",
    )
    a1, a2 = axes[0, 0], axes[1, 0]
    im = a1.imshow(
        W.T,
        aspect="auto",
        origin="lower",
        cmap="cividis",
        interpolation="nearest",
        extent=(0, utt.n_frames / utt.frame_rate, 0.5, W.shape[1] + 0.5),
    )
    fig.colorbar(im, ax=a1, label="weight alpha (no unit)")
    a1.set_ylabel("key shape")
    a2.plot(t, err, color=plotting.PALETTE[1])
    a2.set_ylabel("outline RMSE (cm)")
    a2.set_title("RMSE of the blend sum_k alpha_k L_k against the captured outline", fontsize=9)
    return fig, float(np.sqrt((err**2).mean()))


# -- 4. the target character ------------------------------------------------------
def character_rig(scale=CHARACTER_SCALE, controls=None) -> LinearRig:
    """The toy outline rig in a character's proportions (a linear map of every point)."""
    base = toy_tract_rig(contours=CONTOURS, n_points=N_POINTS)
    keep = [base.control_names.index(c) for c in (controls or base.control_names)]
    s = np.tile(scale, base.n_dims // 2)
    return LinearRig(base.neutral * s, base.deltas[keep] * s, control_names=[base.control_names[k] for k in keep])


def artist_poses(shapes: np.ndarray, rig: LinearRig, scale=CHARACTER_SCALE) -> tuple[np.ndarray, np.ndarray]:
    """Stand-in for the artist: each shape in the character's proportions, as close as the rig allows."""
    controls = fit_controls(shapes * np.tile(scale, rig.n_dims // 2), rig)
    return controls, rig(controls)


def figure_target(cm: CrossMapper, rig: LinearRig, pose_controls):
    """Step 4: the first key shapes (top) and their poses on the character's rig (bottom)."""
    K = min(len(cm.key_shapes_), 6)
    fig, axes = plotting.figure(
        2,
        K,
        panel_size=(2.0, 1.9),
        title=f"Step 4: key shapes (top, black) posed on the character's "
        f"{rig.n_controls}-control rig (bottom, blue); outlines in cm",
    )
    for k in range(K):
        plot_outline(cm.key_shapes_[k], contours=CONTOURS, n_points=N_POINTS, ax=axes[0, k], color=plotting.TRUTH, lw=1)
        plot_outline(
            cm.target_key_shapes[k],
            contours=CONTOURS,
            n_points=N_POINTS,
            ax=axes[1, k],
            color=plotting.PALETTE[0],
            lw=1,
        )
        axes[0, k].set_title(f"captured key {k + 1}", fontsize=8)
        top = np.argsort(pose_controls[k])[::-1][:2]
        axes[1, k].set_title("\n".join(f"{rig.control_names[j]} = {pose_controls[k, j]:.2f}" for j in top), fontsize=7)
        for ax in axes[:, k]:
            ax.axis("off")
    return fig


def figure_controls(controls: Corpus):
    """Step 5: the cross-mapped controls of one utterance, one panel per control."""
    utt = controls[0]
    t = np.arange(utt.n_frames) / utt.frame_rate
    names = list(controls.channels)
    fig, axes, _ = plotting.time_grid(
        len(names),
        1,
        utt.alignment,
        panel_size=(9.0, 0.75),
        title=f"Step 5: cross-mapped rig controls of {utt.name}, bounded in [0, 1]",
    )
    for ax, j in zip(axes[:, 0], range(len(names))):
        ax.plot(t, utt.trajectory[:, j], color=plotting.PALETTE[0])
        ax.set_ylim(-0.05, 1.05)
        ax.set_ylabel(f"{names[j]}\n(0-1)", rotation=0, ha="right", va="center", fontsize=7)
    return fig


def figure_synthesis(truth, preds: dict, rig: LinearRig):
    """Step 6: synthesized controls of a held-out phrase against the cross-mapped ones (small multiples:
    a row per control, a column per model), and the character at four phones."""
    names = list(truth.channels)
    t = np.arange(truth.n_frames) / truth.frame_rate
    fig, axes, tiers = plotting.time_grid(
        len(names),
        len(preds),
        truth.alignment,
        panel_size=(4.6, 0.75),
        title=f"Step 6: held-out phrase {truth.name}: controls synthesized from "
        "the phones (colour) against the cross-mapped ones (black)",
    )
    handles = {}
    for col, (m, y) in enumerate(preds.items()):
        for j, name in enumerate(names):
            ax = axes[j, col]
            (h0,) = ax.plot(t, truth.trajectory[:, j], color=plotting.TRUTH, lw=1.4)
            (h,) = ax.plot(t, y[:, j], color=plotting.model_color(col), lw=1.1)
            handles.setdefault("cross-mapped (held out)", h0)
            handles[f"{m}, clipped to [0, 1]"] = h
            ax.set_ylim(-0.05, 1.05)
            if col == 0:
                ax.set_ylabel(f"{name}\n(0-1)", rotation=0, ha="right", va="center", fontsize=7)
            else:  # the same [0, 1] scale on every row: its labels on the first column only
                ax.tick_params(labelleft=False)
        axes[0, col].set_title(m)
    plotting.legend_outside(fig, list(handles.values()), list(handles), where="lower")
    return fig


def figure_character(truth, preds: dict, rig: LinearRig):
    """Step 6, the character: its outline at four phones, cross-mapped (black) and synthesized (blue)."""
    al = truth.alignment
    mids = [i for i, lab in enumerate(al.labels) if lab != al.silence][:: max(1, len(al) // 5)][:4]
    first = next(iter(preds))
    fig, axes = plotting.figure(
        1,
        len(mids),
        panel_size=(2.4, 2.2),
        title=f"Step 6: the character at four phones of {truth.name}: cross-mapped "
        f"(black) and synthesized by {first} (blue); outlines in cm",
    )
    for ax, i in zip(axes[0], mids):
        f = min(int(0.5 * (al.starts[i] + al.ends[i]) * truth.frame_rate), truth.n_frames - 1)
        plot_outline(rig(truth.trajectory[f]), contours=CONTOURS, n_points=N_POINTS, ax=ax, color=plotting.TRUTH, lw=1)
        plot_outline(rig(preds[first][f]), contours=CONTOURS, n_points=N_POINTS, ax=ax, color=plotting.PALETTE[0], lw=1)
        ax.set_title(f"/{al.labels[i]}/ at {f / truth.frame_rate:.2f} s", fontsize=8)
        ax.axis("off")
    return fig


def figure_retarget(rt: RigSpaceRetargeter, rig_a: LinearRig, rig_b: LinearRig, utt_b, direct_b):
    """Step 7: reference poses on both characters and the second character's controls over time."""
    poses = rt.reference_poses()
    K = len(poses)
    fig, axes = plotting.figure(
        2,
        K,
        panel_size=(1.5, 1.4),
        title="Step 7, rig-space retargeting: the reference poses (mode k at -/+3 sd) on "
        "the first character (top, black), posed once on the second (bottom, green)",
    )
    for k in range(K):
        plot_outline(rig_a(poses[k]), contours=CONTOURS, n_points=N_POINTS, ax=axes[0, k], color=plotting.TRUTH, lw=0.8)
        axes[0, k].set_title(f"mode {k // 2 + 1} {'-+'[k % 2]}3 sd", fontsize=8)
        plot_outline(
            rig_b(rt.rig_poses[k]),
            contours=CONTOURS,
            n_points=N_POINTS,
            ax=axes[1, k],
            color=plotting.PALETTE[2],
            lw=0.8,
        )
        axes[0, k].axis("off")
        axes[1, k].axis("off")
    names = list(rig_b.control_names)
    t = np.arange(utt_b.n_frames) / utt_b.frame_rate
    fig2, axes2, _ = plotting.time_grid(
        len(names),
        1,
        utt_b.alignment,
        panel_size=(9.0, 0.8),
        title=f"Step 7: the second character's controls over {utt_b.name}: "
        "rig-space retargeted (green) and fitted frame by frame (black)",
    )
    for j, ax in enumerate(axes2[:, 0]):
        (h1,) = ax.plot(t, direct_b[:, j], color=plotting.TRUTH, lw=1.2)
        (h2,) = ax.plot(t, utt_b.trajectory[:, j], color=plotting.PALETTE[2], lw=1.2)
        ax.set_ylabel(f"{names[j]}\n(rig units)", rotation=0, ha="right", va="center", fontsize=7)
    plotting.legend_outside(fig2, [h2, h1], ["rig-space retargeted", "fitted frame by frame"], where="lower")
    return fig, fig2


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--out",
        default=os.path.join(os.getcwd(), "dam-examples", NAME),
        help=f"directory for the figures and metrics.json (default: ./dam-examples/{NAME})",
    )
    ap.add_argument("--model", default="dam", help="registered synthesizer to train on the controls (default: dam)")
    ap.add_argument(
        "--minutes",
        type=float,
        default=2.0,
        help="minutes of training phrases (default: 2; with 0.5 the DAM overfits, see above)",
    )
    ap.add_argument("--test-phrases", type=int, default=5, help="held-out phrases scored (default: 5)")
    ap.add_argument("--step", type=int, default=4, help="outline every STEP-th frame, spline the rest (default: 4)")
    ap.add_argument(
        "--quick", action="store_true", help="a smoke test: 0.1 minutes, one test phrase, a short DAM fit (seconds)"
    )
    args = ap.parse_args(argv)
    if args.quick:
        import warnings

        args.minutes, args.test_phrases, args.step = 0.1, 1, 8
        warnings.filterwarnings("ignore", category=dam.ConvergenceWarning)  # a 3-iteration fit, on purpose
    os.makedirs(args.out, exist_ok=True)
    fig = lambda name: os.path.join(args.out, name)  # noqa: E731
    metrics: dict = {"model": args.model, "minutes": args.minutes}
    t0 = time.perf_counter()

    # 1. captured motion: outlines of the tract trajectories
    tract_train, tract_test = tract_corpora(args.minutes, os.path.join(args.out, "cache"), n_test=args.test_phrases)
    log("1/7 outlines of every frame ...")
    cap_train = outline_corpus(tract_train, contours=CONTOURS, n_points=N_POINTS, step=args.step, verbose=1)
    cap_test = outline_corpus(tract_test, contours=CONTOURS, n_points=N_POINTS, step=args.step)
    plotting.save(figure_captured(cap_train), fig("1_captured_outlines.png"))
    metrics["captured"] = {
        "train_utterances": len(cap_train),
        "train_frames": cap_train.n_frames,
        "channels": cap_train.n_channels,
        "outline_sd_cm": float(np.concatenate(cap_train.trajectories).std(0).mean()),
    }

    # 2. key shapes by affinity propagation
    log("2/7 key shapes (affinity propagation) ...")
    cm = CrossMapper(preference="min", max_frames=1500).fit(cap_train)
    plotting.save(figure_key_shapes(cm, cap_train), fig("2_key_shapes.png"))
    metrics["key_shapes"] = len(cm.key_shapes_)

    # 3. blend weights (NNLS)
    log("3/7 NNLS blend weights ...")
    f3, metrics["blend_rmse_cm"] = figure_weights(cm, cap_train[0])
    plotting.save(f3, fig("3_blend_weights.png"))

    # 4. the character: the artist poses the key shapes on its rig
    log("4/7 posing the key shapes on the character ...")
    rig = character_rig()
    pose_controls, posed = artist_poses(cm.key_shapes_, rig, CHARACTER_SCALE)
    cm.set_params(target_key_shapes=posed, rig=rig)
    plotting.save(figure_target(cm, rig, pose_controls), fig("4_target_key_shapes.png"))

    # 5. controls of every frame, bounded in [0, 1]
    log("5/7 bounded controls of every frame ...")
    ctl_train, ctl_test = cm.transform(cap_train), cm.transform(cap_test)
    plotting.save(figure_controls(ctl_train), fig("5_controls.png"))
    V = np.concatenate(cm.vertices(cap_train).trajectories)
    C = np.concatenate(ctl_train.trajectories)
    metrics["controls"] = {
        "min": float(C.min()),
        "max": float(C.max()),
        "vertex_fit_rmse": float(np.sqrt(((rig(C) - V) ** 2).mean())),
        "frames_at_a_bound_share": float(np.mean((C <= 1e-9) | (C >= 1 - 1e-9))),
    }

    # 6. a synthesizer trained on the controls, tested on held-out phrases; the rig takes controls in
    # [0, 1], so synthesized controls are clipped before scoring and driving it (the overshoot is recorded)
    log(f"6/7 fitting {args.model!r} on the controls and synthesizing {len(ctl_test)} held-out phrase(s) ...")
    preds, scores = {}, {}
    truth = np.concatenate(ctl_test.trajectories)
    for name in dict.fromkeys([args.model, "phone-mean"]):
        params = {"unknown_phone": "fallback"} if "unknown_phone" in dam.registry.get(name)._param_names() else {}
        if args.quick and name == "dam":
            params["max_iter"] = 3
        try:
            model = dam.make(name, **params)
        except (KeyError, ImportError) as exc:
            log(f"   {name} unavailable ({exc}); skipped")
            continue
        t1 = time.perf_counter()
        model.fit(ctl_train)
        raw = [model.predict(u.alignment)[: u.n_frames] for u in ctl_test]
        y = np.clip(np.concatenate(raw), 0.0, 1.0)
        preds[name] = np.clip(raw[0], 0.0, 1.0)
        scores[name] = {
            "rmse": float(np.sqrt(((y - truth) ** 2).mean())),
            "rmse_unclipped": float(np.sqrt(((np.concatenate(raw) - truth) ** 2).mean())),
            "outside_0_1_share": float(np.mean((np.concatenate(raw) < 0) | (np.concatenate(raw) > 1))),
            "rmse_per_control": dict(zip(ctl_test.channels, map(float, rmse_per_channel(truth, y)))),
            # NaN (a constant control) becomes null in JSON
            "pearson_per_control": {
                c: (None if np.isnan(r) else float(r)) for c, r in zip(ctl_test.channels, pearson_per_channel(truth, y))
            },
            "fit_seconds": round(time.perf_counter() - t1, 2),
        }
        log(
            f"   {name}: held-out RMSE {scores[name]['rmse']:.4f} (clipped to [0, 1]; "
            f"{100 * scores[name]['outside_0_1_share']:.1f}% of the values overshot)"
        )
    plotting.save(figure_synthesis(ctl_test[0], preds, rig), fig("6_synthesis.png"))
    plotting.save(figure_character(ctl_test[0], preds, rig), fig("6_character.png"))
    metrics["held_out"] = {"utterances": len(ctl_test), "frames": int(len(truth)), "scores": scores}

    # 7. rig-space retargeting of the synthesized animation to a second character
    log("7/7 rig-space retargeting to a second character ...")
    rig_b = character_rig(SECOND_SCALE, SECOND_CONTROLS)
    rt = RigSpaceRetargeter(n_modes=4).fit(ctl_train)
    # the artist poses the 8 reference shapes (and the mean) once on the second rig
    rig_poses, _ = artist_poses(
        rig(rt.reference_poses()) / np.tile(CHARACTER_SCALE, rig.n_dims // 2), rig_b, SECOND_SCALE
    )
    r0, _ = artist_poses(rig(rt.mean_[None]) / np.tile(CHARACTER_SCALE, rig.n_dims // 2), rig_b, SECOND_SCALE)
    rt.set_params(rig_poses=rig_poses, rig_neutral=r0[0], rig_names=list(rig_b.control_names))
    anim = ctl_test[0].replace(trajectory=preds[next(iter(preds))])
    retargeted = rt.transform(anim)
    # reference: fitting the second rig to every frame of the first character (what retargeting avoids)
    direct, _ = artist_poses(rig(anim.trajectory) / np.tile(CHARACTER_SCALE, rig.n_dims // 2), rig_b, SECOND_SCALE)
    f7a, f7b = figure_retarget(rt, rig, rig_b, retargeted, direct)
    plotting.save(f7a, fig("7_retarget_poses.png"))
    plotting.save(f7b, fig("7_retarget.png"))
    metrics["retarget"] = {
        "modes": 4,
        "explained_variance": float(rt.explained_variance_ratio_.sum()),
        "rmse_vs_per_frame_fit": float(np.sqrt(((retargeted.trajectory - direct) ** 2).mean())),
    }
    metrics["seconds"] = round(time.perf_counter() - t0, 1)
    from dam.corpus.atomic import atomic_write

    with atomic_write(fig("metrics.json")) as fh:
        json.dump(metrics, fh, indent=2)
    log(f"done in {metrics['seconds']} s; figures and metrics.json in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
