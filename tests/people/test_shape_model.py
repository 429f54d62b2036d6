"""Point-distribution model: Procrustes, PCA, Mahalanobis constraint, save/load, training."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.errors import InputError
from motiontrack.people.shape_model import (
    ShapeModel,
    apply_similarity,
    fit_similarity,
    invert_similarity,
    load_default_model,
)
from motiontrack.people.training import (
    control_points_from_mask,
    generalized_procrustes,
    outline_from_mask,
    outlines_from_synth,
    save_model,
    train_shape_model,
)


def _ellipse(a: float, b: float, n: int = 16) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.stack([a * np.cos(t), b * np.sin(t)], axis=1)


def _training_set(seed: int = 0, count: int = 60) -> list[np.ndarray]:
    """Ellipses with random aspect, placed with random similarity transforms."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        shape = _ellipse(1.0, rng.uniform(1.5, 3.0))
        ang, s = rng.uniform(-0.3, 0.3), rng.uniform(20, 60)
        pose = np.array([s * np.cos(ang), s * np.sin(ang), *rng.uniform(0, 300, 2)])
        out.append(apply_similarity(pose, shape) + rng.normal(0, 0.01, shape.shape))
    return out


@pytest.fixture(scope="module")
def model() -> ShapeModel:
    return train_shape_model(_training_set(), xi=0.95)


@pytest.mark.parametrize("pose", [(1.0, 0.0, 0.0, 0.0), (2.0, 0.5, -3.0, 7.0), (0.3, -0.2, 10.0, 1.0)])
def test_similarity_fit_recovers_the_transform_and_inverts(pose):
    src = _ellipse(3, 5, 12)
    dst = apply_similarity(np.array(pose), src)
    est = fit_similarity(src, dst)
    assert np.allclose(est, pose, atol=1e-9)
    assert np.allclose(apply_similarity(invert_similarity(est), dst), src, atol=1e-9)


def test_similarity_with_too_few_points_is_identity():
    assert np.allclose(fit_similarity(np.zeros((1, 2)), np.ones((1, 2))), [1, 0, 0, 0])
    assert np.allclose(fit_similarity(np.zeros((0, 2)), np.zeros((0, 2))), [1, 0, 0, 0])


def test_procrustes_removes_pose():
    base = _ellipse(1.0, 2.0)
    shapes = np.stack([apply_similarity(np.array([s * np.cos(a), s * np.sin(a), 5, -2]), base)
                       for s, a in [(1, 0), (3, 0.4), (10, -0.7)]])
    aligned, mean = generalized_procrustes(shapes)
    assert np.allclose(aligned, aligned[0], atol=1e-9)
    assert np.linalg.norm(mean) == pytest.approx(1.0)
    assert np.allclose(mean.mean(axis=0), 0, atol=1e-12)


def test_pca_keeps_the_one_real_mode(model):
    # The training set varies in aspect only (plus tiny noise): one mode explains >= 95 %.
    assert model.n_modes == 1
    assert model.meta["explained"] >= 0.95
    assert model.meta["samples"] == 60


def test_shape_within_the_bound_reproduces_itself(model):
    b = np.array([1.5 * np.sqrt(model.variances[0])])  # D = 1.5 < 3
    x = model.shape(b)
    b2 = model.project(x)
    assert np.allclose(b2, b)
    assert np.allclose(model.constrain(b2), b)
    assert np.allclose(model.shape(model.constrain(b2)), x)


@pytest.mark.parametrize("factor", [4.0, 10.0, -25.0])
def test_shape_far_outside_is_pulled_onto_the_hyper_ellipsoid(model, factor):
    b = np.array([factor * np.sqrt(model.variances[0])])
    c = model.constrain(b)
    assert model.mahalanobis(b) == pytest.approx(abs(factor))
    assert model.mahalanobis(c) == pytest.approx(model.dmax)  # Dmax = 3
    assert np.sign(c[0]) == np.sign(b[0])                     # rescaled, same direction


def test_constraint_on_several_modes_is_a_rescaling():
    rng = np.random.default_rng(1)
    modes = np.linalg.qr(rng.normal(size=(16, 3)))[0]
    m = ShapeModel(mean=_ellipse(1, 2, 8) / np.linalg.norm(_ellipse(1, 2, 8)), modes=modes,
                   variances=np.array([0.04, 0.01, 0.0025]))
    b = np.array([1.0, -1.0, 0.5])
    d = np.sqrt(1 / 0.04 + 1 / 0.01 + 0.25 / 0.0025)
    assert m.mahalanobis(b) == pytest.approx(d)
    assert np.allclose(m.constrain(b), b * 3 / d)
    assert m.mahalanobis(m.constrain(b)) == pytest.approx(3.0)


def test_fit_places_model_on_image_points(model):
    b = np.array([-1.0 * np.sqrt(model.variances[0])])
    pose = np.array([40.0, 3.0, 120.0, 80.0])
    target = apply_similarity(pose, model.shape(b))
    est_pose, est_b = model.fit(target)
    assert np.allclose(apply_similarity(est_pose, model.shape(est_b)), target, atol=1e-6)


def test_save_load_round_trip(tmp_path, model):
    path = save_model(model, tmp_path / "m.npz")
    back = ShapeModel.load(path)
    assert back.n_control == model.n_control and back.n_modes == model.n_modes
    assert np.allclose(back.mean, model.mean, atol=1e-6)
    assert np.allclose(back.variances, model.variances)
    assert back.dmax == 3.0 and back.meta["samples"] == 60


@pytest.mark.parametrize("content", [b"", b"not a zip at all"])
def test_load_of_a_bad_file_is_an_input_error(tmp_path, content):
    p = tmp_path / "bad.npz"
    p.write_bytes(content)
    with pytest.raises(InputError, match="not a shape model"):
        ShapeModel.load(p)


def test_model_validates_itself():
    with pytest.raises(ValueError, match="modes must have shape"):
        ShapeModel(mean=np.zeros((8, 2)), modes=np.zeros((10, 1)), variances=np.ones(1))
    with pytest.raises(ValueError, match="> 0"):
        ShapeModel(mean=np.zeros((8, 2)), modes=np.zeros((16, 1)), variances=np.zeros(1))
    with pytest.raises(ValueError, match="at least 2"):
        train_shape_model([np.zeros((8, 2))])


def test_outline_from_mask_starts_at_the_top_and_runs_with_positive_area():
    mask = np.zeros((60, 40), np.uint8)
    mask[10:50, 12:28] = 255
    mask[4:10, 17:23] = 255  # a "head"
    c = outline_from_mask(mask)
    assert c[0, 1] == 4 and 17 <= c[0, 0] <= 22
    from motiontrack.people.bspline import signed_area

    assert signed_area(c) > 0
    assert outline_from_mask(np.zeros((5, 5), np.uint8)) is None
    ctrl = control_points_from_mask(mask, 16)
    assert ctrl.shape == (16, 2)
    assert 12 <= ctrl[:, 0].mean() <= 28


def test_shipped_default_model_is_small_and_sane():
    from motiontrack.people.shape_model import default_model_path

    assert default_model_path().stat().st_size < 50_000
    m = load_default_model()
    assert m.n_control == 32 and 1 <= m.n_modes <= 20 and m.dmax == 3.0
    assert "synth" in m.meta["source"]
    # the mean outline is a standing person: much taller than wide
    span = m.mean.max(axis=0) - m.mean.min(axis=0)
    assert span[1] > 2 * span[0]


def test_training_from_synthetic_figures():
    shapes = list(outlines_from_synth("walker", seeds=(0,), n_control=16, every=10))
    assert len(shapes) >= 5
    m = train_shape_model(shapes, xi=0.9)
    assert m.n_control == 16 and m.n_modes >= 1


def test_cli_shape_train_and_info(tmp_path, capsys):
    from motiontrack.cli import main

    out = tmp_path / "m.npz"
    rc = main(["shape", "train", "synth:walker", "--seeds", "0", "--every", "6",
               "--control-points", "16", "-o", str(out)])
    assert rc == 0 and out.exists()
    assert ShapeModel.load(out).n_control == 16
    assert main(["shape", "info", str(out)]) == 0
    assert "16 control points" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv, message",
    [
        (["shape", "train", "synth:nope", "-o", "{tmp}/x.npz"], "unknown synthetic scene"),
        (["shape", "train", "video.avi", "-o", "{tmp}/x.npz"], "needs --gt"),
        (["shape", "train", "synth:walker", "--xi", "2", "-o", "{tmp}/x.npz"], "--xi"),
        (["shape", "train", "synth:walker", "--seeds", "a-b", "-o", "{tmp}/x.npz"], "--seeds"),
    ],
)
def test_cli_shape_train_errors_are_one_line(tmp_path, capsys, argv, message):
    from motiontrack.cli import main

    rc = main([a.replace("{tmp}", str(tmp_path)) for a in argv])
    assert rc != 0
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
