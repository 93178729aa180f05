"""Dynamic visemes: gesture units cut from data built of known gestures are found and clustered back."""

import numpy as np
import pytest
from sklearn.metrics import adjusted_rand_score

import dam
from baselines.dynamic_visemes import DynamicVisemes, cluster_units, gesture_boundaries, gesture_units, time_normalise

FR = 100.0
POSES = np.array([[0.0, 0.0], [3.0, 1.0], [-1.0, 3.0]])
PHONES = {0: ("aa", "p"), 1: ("iy", "m"), 2: ("uw", "f")}  # the phones of a gesture ending at each pose


def _smoothstep(n):
    s = (np.arange(n) + 0.5) / n
    return s * s * (3 - 2 * s)  # zero velocity at both ends, one speed peak


def _gesture_corpus(n_utts=12, seed=0):
    """Random walks over three poses; every move a->b is one gesture of known type (a, b).

    Each gesture lasts 10-25 frames and is one or two phones; gesture boundaries are phone boundaries.
    """
    rng = np.random.default_rng(seed)
    utts, truth = [], []
    for i in range(n_utts):
        pose, frames, labels, starts, ends, bounds, types, t = 0, [], [], [], [], [], [], 0
        for _ in range(10):
            nxt = int(rng.choice([p for p in range(3) if p != pose]))
            n = int(rng.integers(10, 26))
            frames.append(POSES[pose] + _smoothstep(n)[:, None] * (POSES[nxt] - POSES[pose]))
            if rng.random() < 0.5:
                labels.append(PHONES[nxt][0])
                starts.append(t)
                ends.append(t + n)
            else:
                half = n // 2
                labels += list(PHONES[nxt])
                starts += [t, t + half]
                ends += [t + half, t + n]
            types.append(pose * 3 + nxt)
            t += n
            bounds.append(t)
            pose = nxt
        y = np.concatenate(frames)
        utts.append(
            dam.Utterance(
                dam.Alignment(labels, np.array(starts) / FR, np.array(ends) / FR),
                y,
                FR,
                channels=("x", "y"),
                name=f"g{i}",
            )
        )
        truth.append((np.array(bounds[:-1]), types))
    return dam.Corpus(utts), truth


def test_gesture_boundaries_are_the_pauses_between_gestures():
    corpus, truth = _gesture_corpus()
    for u, (bounds, _) in zip(corpus, truth):
        found = gesture_boundaries(u.trajectory, FR, smoothing=0.02, min_gesture=0.06)
        assert len(found) == len(bounds)
        assert np.abs(found - bounds).max() <= 1


def test_units_are_clustered_back_to_their_gestures():
    corpus, truth = _gesture_corpus()
    shapes, types = [], []
    for u, (_, kinds) in zip(corpus, truth):
        cuts = gesture_boundaries(u.trajectory, FR, smoothing=0.02)
        units = gesture_units(cuts, u.alignment, FR, max_phones=4)
        assert len(units) == len(kinds)
        for (i, j), kind in zip(units, kinds):
            shapes.append(time_normalise(u.trajectory, FR, u.alignment.starts[i], u.alignment.ends[j - 1], 10))
            types.append(kind)
    labels, centroids = cluster_units(np.stack(shapes), n_clusters=6)
    assert adjusted_rand_score(types, labels) == 1.0
    assert centroids.shape == (6, 10, 2)


def test_gesture_units_snap_to_phone_boundaries_and_cover_every_phone():
    a = dam.Alignment(["a", "b", "c", "d", "e", "f"], [0, 0.1, 0.2, 0.3, 0.4, 0.5], [0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    units = gesture_units([19, 31], a, FR, max_phones=2)
    # cuts at frames 19 and 31 go to the boundaries at 0.2 s and 0.3 s; the last 3 phones are split in two
    assert units == [(0, 2), (2, 3), (3, 4), (4, 6)] or units == [(0, 2), (2, 3), (3, 5), (5, 6)]
    assert [i for u in units for i in range(*u)] == list(range(6))


def test_model_learns_the_gestures_and_synthesizes_held_out_walks():
    """The phones name only a gesture's end pose; its start must come from the join (smoothness) cost."""
    corpus, truth = _gesture_corpus()
    model = DynamicVisemes(n_clusters=6, smoothing=0.02, crossfade=0.0, join_weight=1.0).fit(corpus)
    types = [k for _, kinds in truth for k in kinds]
    assert adjusted_rand_score(types, model.unit_cluster_) == 1.0
    held_out, _ = _gesture_corpus(n_utts=3, seed=9)
    ev = dam.evaluate(model, held_out)
    ref = dam.evaluate(dam.make("phone-mean").fit(corpus), held_out)
    assert ev.rmse < 0.3 * ref.rmse, (ev.rmse, ref.rmse)
    # Without the join cost the start poses are guessed from the phones alone, and often wrong.
    model.set_params(join_weight=0.0)
    assert dam.evaluate(model, held_out).rmse > 2 * ev.rmse


def test_time_warp_follows_new_phone_boundaries():
    """A unit's instance stretched onto longer phones keeps its shape: the pose is reached at the phone end."""
    corpus, _ = _gesture_corpus()
    model = DynamicVisemes(n_clusters=6, smoothing=0.02, crossfade=0.0).fit(corpus)
    a = dam.Alignment(["iy", "uw", "aa"], [0.0, 0.4, 0.9], [0.4, 0.9, 1.2])  # slow moves to pose 1, 2, 0
    y = model.predict(a)
    np.testing.assert_allclose(y[38], POSES[1], atol=0.35)
    np.testing.assert_allclose(y[88], POSES[2], atol=0.35)


@pytest.mark.parametrize("bad", [{"n_clusters": 0}, {"crossfade": -0.1}, {"max_phones": 1.5}])
def test_bad_parameters_are_refused(bad):
    corpus, _ = _gesture_corpus(n_utts=2)
    with pytest.raises(ValueError, match=next(iter(bad))):
        DynamicVisemes(**bad).fit(corpus)


def test_registered():
    assert dam.registry.get("dynamic-visemes") is DynamicVisemes
