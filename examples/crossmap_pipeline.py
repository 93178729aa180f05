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

Run::

    python examples/crossmap_pipeline.py                 # figures in examples/out/crossmap/
    python examples/crossmap_pipeline.py --out /tmp/cm --model phone-mean --minutes 0.3
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import dam  # noqa: E402
from dam.crossmap.crossmapping import CrossMapper, blend_weights, fit_controls  # noqa: E402
from dam.corpus.data import Corpus  # noqa: E402
from dam.evaluation.metrics import pearson_per_channel, rmse_per_channel  # noqa: E402
from dam.crossmap.outlines import outline_corpus, plot_outline, toy_tract_rig  # noqa: E402
from dam.crossmap.retarget import RigSpaceRetargeter  # noqa: E402
from dam.crossmap.rig import LinearRig  # noqa: E402

CONTOURS = ("upper", "lower", "tongue")
N_POINTS = 12
#: The character's proportions: a longer, flatter vocal tract than the speaker's.
CHARACTER_SCALE = (1.25, 0.85)
#: The second character (step 7): other proportions and only five controls.
SECOND_SCALE = (0.9, 1.1)
SECOND_CONTROLS = ("jaw_open", "tongue_front", "lip_round", "lip_close", "tip_up")


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


# -- 1. captured motion ---------------------------------------------------------
def tract_corpora(minutes: float, cache: str, seed: int = 0) -> tuple[Corpus, Corpus]:
    """(train, test) corpora of VTL tract parameters with disjoint words."""
    from dam import datasets
    try:
        train, test = datasets.load("vtl", "train"), datasets.load("vtl", "test")
    except (KeyError, dam.DataError):   # not bundled (yet) in this install
        train = None
    if train is not None:
        n, total = 0, 0.0
        while n < len(train) and total < 60 * minutes:
            total += train[n].duration
            n += 1
        log(f"captured motion: bundled vtl corpus, {n} training phrases ({total:.0f} s)")
        return train[:n], test[:1]
    from dam.datasets.vtl import generate_vtl_corpus
    from dam.corpus.io import load_corpus
    root = os.path.join(cache, f"vtl-{minutes:g}min-seed{seed}")
    paths = [os.path.join(root, s) for s in ("train", "test")]
    if all(os.path.exists(os.path.join(p, "corpus.json")) for p in paths):
        log(f"captured motion: cached VTL phrases in {root}")
        return load_corpus(paths[0]), load_corpus(paths[1])[:1]
    os.makedirs(cache, exist_ok=True)
    with open(os.path.join(cache, ".gitignore"), "w") as fh:   # a cache, not a result: keep it out of git
        fh.write("*\n")
    log(f"captured motion: synthesizing {minutes:g} min of phrases with VocalTractLab into {root} ...")
    corpora = generate_vtl_corpus(root, seed=seed, n_train_minutes=minutes, n_test_minutes=0.05,
                                  audio_fraction=0.0, overwrite=True)
    return corpora["train"], corpora["test"][:1]


def phone_axis(ax, utt, *, every: int = 1) -> None:
    """Phone boundaries and labels along the time axis."""
    al = utt.alignment
    for k, (lab, s, e) in enumerate(zip(al.labels, al.starts, al.ends)):
        ax.axvline(s, color="0.85", lw=0.6, zorder=0)
        if k % every == 0 and lab != al.silence:
            ax.text(0.5 * (s + e), 1.0, lab, transform=ax.get_xaxis_transform(), ha="center", va="bottom",
                    fontsize=7)


def frame_phones(utt):
    return [utt.alignment.labels[i] for i in utt.alignment.segment_index(utt.frame_rate, utt.n_frames)]


def figure_captured(outlines: Corpus, path: str) -> None:
    utt = outlines[0]
    labels = frame_phones(utt)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.2), gridspec_kw={"width_ratios": [1, 1.6]})
    picks = [i for i in range(0, utt.n_frames, max(1, utt.n_frames // 6))][:6]
    for j, i in enumerate(picks):
        plot_outline(utt.trajectory[i], contours=CONTOURS, n_points=N_POINTS, ax=a1, color=f"C{j}",
                     label=f"t={i / utt.frame_rate:.2f}s /{labels[i]}/")
    a1.legend(fontsize=7, loc="lower left")
    a1.set_title("captured: VTL outlines (cm) of six frames")
    t = np.arange(utt.n_frames) / utt.frame_rate
    names = list(outlines.channels)
    for ch in ("tongue11_y", "tongue06_y", "lower11_y"):
        a2.plot(t, utt.trajectory[:, names.index(ch)], label=ch)
    phone_axis(a2, utt)
    a2.set_xlabel("time (s)")
    a2.set_ylabel("cm")
    a2.legend(fontsize=7)
    a2.set_title(f"captured point trajectories of {utt.name}", pad=14)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_key_shapes(cm: CrossMapper, outlines: Corpus, path: str) -> None:
    frames_phone = [p for u in outlines for p in frame_phones(u)]
    K = len(cm.key_shapes_)
    cols = min(K, 7)
    rows = int(np.ceil(K / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(1.9 * cols, 1.7 * rows), squeeze=False)
    for k, ax in enumerate(axes.ravel()):
        ax.axis("off")
        if k < K:
            plot_outline(cm.key_shapes_[k], contours=CONTOURS, n_points=N_POINTS, ax=ax, color="k", lw=1)
            ax.set_title(f"key {k}: /{frames_phone[cm.key_frame_indices_[k]]}/", fontsize=8)
    fig.suptitle(f"{K} key shapes found by affinity propagation over {sum(u.n_frames for u in outlines)} frames")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_weights(cm: CrossMapper, utt, path: str) -> float:
    W = blend_weights(utt.trajectory, cm.key_shapes_)
    err = np.sqrt(((W @ cm.key_shapes_ - utt.trajectory) ** 2).mean(axis=1))
    t = np.arange(utt.n_frames) / utt.frame_rate
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(11, 5), sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    a1.imshow(W.T, aspect="auto", origin="lower", cmap="magma",
              extent=(0, utt.n_frames / utt.frame_rate, -0.5, W.shape[1] - 0.5))
    a1.set_ylabel("key shape")
    phone_axis(a1, utt)
    a1.set_title(f"NNLS blend weights of {utt.name} (alpha >= 0)", pad=14)
    a2.plot(t, err, color="C3")
    a2.set_ylabel("RMSE (cm)")
    a2.set_xlabel("time (s)")
    a2.set_title("error of the blend sum_k alpha_k L_k against the captured outline", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return float(np.sqrt((err ** 2).mean()))


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


def figure_target(cm: CrossMapper, rig: LinearRig, pose_controls, path: str) -> None:
    K = min(len(cm.key_shapes_), 6)
    fig, axes = plt.subplots(2, K, figsize=(2.2 * K, 4.6), squeeze=False)
    for k in range(K):
        plot_outline(cm.key_shapes_[k], contours=CONTOURS, n_points=N_POINTS, ax=axes[0, k], color="k", lw=1)
        plot_outline(cm.target_key_shapes[k], contours=CONTOURS, n_points=N_POINTS, ax=axes[1, k], color="C0", lw=1)
        axes[0, k].set_title(f"captured key {k}", fontsize=8)
        top = np.argsort(pose_controls[k])[::-1][:2]
        axes[1, k].set_title(", ".join(f"{rig.control_names[j]}={pose_controls[k, j]:.2f}" for j in top), fontsize=7)
        for ax in axes[:, k]:
            ax.axis("off")
    fig.suptitle("key shapes (top) posed on the character's 7-control rig (bottom)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_controls(controls: Corpus, path: str) -> None:
    utt = controls[0]
    t = np.arange(utt.n_frames) / utt.frame_rate
    fig, ax = plt.subplots(figsize=(11, 4))
    for j, name in enumerate(controls.channels):
        ax.plot(t, utt.trajectory[:, j], label=name, lw=1.2)
    phone_axis(ax, utt)
    ax.set_ylim(-0.05, 1.05)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("control value")
    ax.legend(fontsize=7, ncol=4, loc="upper right")
    ax.set_title(f"cross-mapped rig controls of {utt.name} (bounded in [0, 1])", pad=14)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_synthesis(truth, preds: dict, rig: LinearRig, path: str) -> None:
    names = list(truth.channels)
    t = np.arange(truth.n_frames) / truth.frame_rate
    n = len(names)
    fig = plt.figure(figsize=(12, 2.0 * ((n + 1) // 2) + 2.6))
    gs = fig.add_gridspec((n + 1) // 2 + 1, 2)
    for j, name in enumerate(names):
        ax = fig.add_subplot(gs[j // 2, j % 2])
        ax.plot(t, truth.trajectory[:, j], color="k", lw=1.4, label="cross-mapped (held out)")
        for k, (m, y) in enumerate(preds.items()):
            ax.plot(t, y[:, j], lw=1.1, color=f"C{k}", label=m)
        phone_axis(ax, truth)
        ax.set_ylabel(name, fontsize=8)
        ax.set_ylim(-0.05, 1.05)
        if j == 0:
            ax.legend(fontsize=7, loc="upper right")
    al = truth.alignment
    mids = [i for i, lab in enumerate(al.labels) if lab != al.silence][:: max(1, len(al) // 5)][:4]
    sub = gs[-1, :].subgridspec(1, len(mids))
    first = next(iter(preds))
    for k, i in enumerate(mids):
        ax = fig.add_subplot(sub[0, k])
        f = min(int(0.5 * (al.starts[i] + al.ends[i]) * truth.frame_rate), truth.n_frames - 1)
        plot_outline(rig(truth.trajectory[f]), contours=CONTOURS, n_points=N_POINTS, ax=ax, color="k", lw=1)
        plot_outline(rig(np.clip(preds[first][f], 0, 1)), contours=CONTOURS, n_points=N_POINTS, ax=ax,
                     color="C0", lw=1)
        ax.set_title(f"/{al.labels[i]}/ at {f / truth.frame_rate:.2f}s", fontsize=8)
        ax.axis("off")
    fig.suptitle(f"held-out phrase {truth.name}: synthesized controls vs cross-mapped; "
                 f"bottom: the character ({first}: blue, cross-mapped: black)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_retarget(rt: RigSpaceRetargeter, rig_a: LinearRig, rig_b: LinearRig, utt_b, direct_b, path: str) -> None:
    poses = rt.reference_poses()
    K = len(poses)
    fig = plt.figure(figsize=(12, 6.4))
    gs = fig.add_gridspec(3, K)
    for k in range(K):
        ax = fig.add_subplot(gs[0, k])
        plot_outline(rig_a(poses[k]), contours=CONTOURS, n_points=N_POINTS, ax=ax, color="k", lw=0.8)
        ax.set_title(f"mode {k // 2 + 1} {'-+'[k % 2]}3 sd", fontsize=8)
        ax.axis("off")
        ax = fig.add_subplot(gs[1, k])
        plot_outline(rig_b(rt.rig_poses[k]), contours=CONTOURS, n_points=N_POINTS, ax=ax, color="C2", lw=0.8)
        ax.axis("off")
    ax = fig.add_subplot(gs[2, :])
    t = np.arange(utt_b.n_frames) / utt_b.frame_rate
    for j, name in enumerate(rig_b.control_names):
        ax.plot(t, utt_b.trajectory[:, j], color=f"C{j}", lw=1.3, label=name)
        ax.plot(t, direct_b[:, j], color=f"C{j}", lw=0.8, ls=":")
    phone_axis(ax, utt_b)
    ax.set_xlabel("time (s)")
    ax.legend(fontsize=7, ncol=5, loc="upper right")
    ax.set_title("second character's controls: rig-space retargeted (solid) vs fitted frame by frame (dotted)",
                 fontsize=9, pad=14)
    fig.suptitle("rig-space retargeting: reference poses on the first character (top), posed once on the "
                 "second (middle)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "out", "crossmap"),
                    help="directory for the figures and metrics.json (default: examples/out/crossmap)")
    ap.add_argument("--model", default="dam", help="registered synthesizer to train on the controls (default: dam)")
    ap.add_argument("--minutes", type=float, default=0.5, help="minutes of training phrases (default: 0.5)")
    ap.add_argument("--step", type=int, default=2, help="outline every STEP-th frame, spline the rest (default: 2)")
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    fig = lambda name: os.path.join(args.out, name)  # noqa: E731
    metrics: dict = {"model": args.model}
    t0 = time.perf_counter()

    # 1. captured motion: outlines of the tract trajectories
    tract_train, tract_test = tract_corpora(args.minutes, os.path.join(args.out, "cache"))
    log("1/7 outlines of every frame ...")
    cap_train = outline_corpus(tract_train, contours=CONTOURS, n_points=N_POINTS, step=args.step, verbose=1)
    cap_test = outline_corpus(tract_test, contours=CONTOURS, n_points=N_POINTS, step=args.step)
    figure_captured(cap_train, fig("1_captured_outlines.png"))
    metrics["captured"] = {"train_utterances": len(cap_train), "train_frames": cap_train.n_frames,
                           "channels": cap_train.n_channels, "outline_sd_cm": float(
                               np.concatenate(cap_train.trajectories).std(0).mean())}

    # 2. key shapes by affinity propagation
    log("2/7 key shapes (affinity propagation) ...")
    cm = CrossMapper(preference="min", max_frames=1500).fit(cap_train)
    figure_key_shapes(cm, cap_train, fig("2_key_shapes.png"))
    metrics["key_shapes"] = len(cm.key_shapes_)

    # 3. blend weights (NNLS)
    log("3/7 NNLS blend weights ...")
    metrics["blend_rmse_cm"] = figure_weights(cm, cap_train[0], fig("3_blend_weights.png"))

    # 4. the character: the artist poses the key shapes on its rig
    log("4/7 posing the key shapes on the character ...")
    rig = character_rig()
    pose_controls, posed = artist_poses(cm.key_shapes_, rig, CHARACTER_SCALE)
    cm.set_params(target_key_shapes=posed, rig=rig)
    figure_target(cm, rig, pose_controls, fig("4_target_key_shapes.png"))

    # 5. controls of every frame, bounded in [0, 1]
    log("5/7 bounded controls of every frame ...")
    ctl_train, ctl_test = cm.transform(cap_train), cm.transform(cap_test)
    figure_controls(ctl_train, fig("5_controls.png"))
    V = np.concatenate(cm.vertices(cap_train).trajectories)
    C = np.concatenate(ctl_train.trajectories)
    metrics["controls"] = {"min": float(C.min()), "max": float(C.max()),
                           "vertex_fit_rmse": float(np.sqrt(((rig(C) - V) ** 2).mean())),
                           "frames_at_a_bound_share": float(np.mean((C <= 1e-9) | (C >= 1 - 1e-9)))}

    # 6. a synthesizer trained on the controls, tested on a held-out phrase
    log(f"6/7 fitting {args.model!r} on the controls and synthesizing the held-out phrase ...")
    preds, scores = {}, {}
    for name in dict.fromkeys([args.model, "phone-mean"]):
        try:
            model = dam.make(name, **({"unknown_phone": "fallback"} if "unknown_phone" in
                                      dam.registry.get(name)._param_names() else {}))
        except (KeyError, ImportError) as exc:
            log(f"   {name} unavailable ({exc}); skipped")
            continue
        t1 = time.perf_counter()
        model.fit(ctl_train)
        y = model.predict(ctl_test[0].alignment)[: ctl_test[0].n_frames]
        preds[name] = y
        truth = ctl_test[0].trajectory[: len(y)]
        scores[name] = {"rmse": float(np.sqrt(((y - truth) ** 2).mean())),
                        "rmse_per_control": dict(zip(ctl_test.channels, map(float, rmse_per_channel(truth, y)))),
                        # NaN (a constant control) becomes null in JSON
                        "pearson_per_control": {c: (None if np.isnan(r) else float(r)) for c, r in
                                                zip(ctl_test.channels, pearson_per_channel(truth, y))},
                        "fit_seconds": round(time.perf_counter() - t1, 2)}
        log(f"   {name}: held-out RMSE {scores[name]['rmse']:.4f}")
    figure_synthesis(ctl_test[0], preds, rig, fig("6_synthesis.png"))
    metrics["held_out"] = {"utterance": ctl_test[0].name, "frames": ctl_test[0].n_frames, "scores": scores}

    # 7. rig-space retargeting of the synthesized animation to a second character
    log("7/7 rig-space retargeting to a second character ...")
    rig_b = character_rig(SECOND_SCALE, SECOND_CONTROLS)
    rt = RigSpaceRetargeter(n_modes=4).fit(ctl_train)
    # the artist poses the 8 reference shapes (and the mean) once on the second rig
    rig_poses, _ = artist_poses(rig(rt.reference_poses()) / np.tile(CHARACTER_SCALE, rig.n_dims // 2), rig_b,
                                SECOND_SCALE)
    r0, _ = artist_poses(rig(rt.mean_[None]) / np.tile(CHARACTER_SCALE, rig.n_dims // 2), rig_b, SECOND_SCALE)
    rt.set_params(rig_poses=rig_poses, rig_neutral=r0[0], rig_names=list(rig_b.control_names))
    anim = ctl_test[0].replace(trajectory=np.clip(preds[next(iter(preds))], 0, 1))
    retargeted = rt.transform(anim)
    # reference: fitting the second rig to every frame of the first character (what retargeting avoids)
    direct, _ = artist_poses(rig(anim.trajectory) / np.tile(CHARACTER_SCALE, rig.n_dims // 2), rig_b, SECOND_SCALE)
    figure_retarget(rt, rig, rig_b, retargeted, direct, fig("7_retarget.png"))
    metrics["retarget"] = {"modes": 4, "explained_variance": float(rt.explained_variance_ratio_.sum()),
                           "rmse_vs_per_frame_fit": float(np.sqrt(((retargeted.trajectory - direct) ** 2).mean()))}
    metrics["seconds"] = round(time.perf_counter() - t0, 1)
    with open(fig("metrics.json"), "w") as fh:
        json.dump(metrics, fh, indent=2)
    log(f"done in {metrics['seconds']} s; figures and metrics.json in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
