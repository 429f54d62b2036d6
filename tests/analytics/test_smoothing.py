"""The smoothed trajectories the rules measure: a constant-velocity Kalman filter per track, its
noises in box heights, outliers skipped, a filter that starts again after a jump, and the ground
plane through the camera's Jacobian."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.analytics.smoothing import (GATE, JUMP, NOISE, SPEED0, Smoother, jacobians)

FPS = 10.0
H = 20.0          # box height, pixels: the anchor's noise is NOISE * H = 1 px


def _step(sm: Smoother, frame: int, points, rows=(0,), heights=None, jac=None):
    z = np.asarray(points, float).reshape(-1, 2)
    h = np.full(len(z), H) if heights is None else np.asarray(heights, float)
    return sm.step(frame, np.asarray(rows), z, h, jac)


def test_a_new_track_starts_where_it_is_measured_at_rest_its_speed_unknown():
    out = _step(Smoother(FPS), 1, [[50, 60]])
    assert out.position.tolist() == [[50.0, 60.0]] and out.velocity.tolist() == [[0.0, 0.0]]
    # position: the measurement's noise (1 px); speed: SPEED0 heights a second in each axis
    assert np.allclose(out.position_cov[0], np.eye(2) * (NOISE * H) ** 2)
    assert np.allclose(out.velocity_cov[0], np.eye(2) * (SPEED0 * H) ** 2)
    speed, sigma = out.speed()
    assert speed[0] == 0.0 and sigma[0] == pytest.approx(SPEED0 * H)


def test_a_still_track_stays_put_and_its_speed_becomes_certain():
    sm = Smoother(FPS)
    sigmas = []
    for f in range(1, 51):
        out = _step(sm, f, [[50, 60]])
        sigmas.append(out.speed()[1][0])
    assert out.position.tolist() == [[50.0, 60.0]] and out.speed()[0][0] == 0.0
    assert all(b < a for a, b in zip(sigmas[:10], sigmas[1:10]))   # more certain, frame by frame
    # until the walker's possible acceleration (ACCEL) balances what a frame tells: about a
    # quarter of a height a second
    assert sigmas[-1] == pytest.approx(sigmas[-10], rel=1e-6) and sigmas[-1] < 0.25 * H


def test_a_steady_walk_is_followed_at_its_own_speed():
    sm = Smoother(FPS)
    for f in range(1, 41):                                     # 3 px a frame = 30 px/s
        out = _step(sm, f, [[3.0 * f, 100.0]])
    speed, sigma = out.speed()
    assert speed[0] == pytest.approx(30.0, rel=0.01) and sigma[0] < 5.0
    assert out.position[0] == pytest.approx([120.0, 100.0], abs=0.5)


def test_one_jump_of_the_box_is_skipped_as_an_outlier():
    sm = Smoother(FPS)
    for f in range(1, 21):
        _step(sm, f, [[50, 60]])
    out = _step(sm, 21, [[50 + 10 * NOISE * H, 60]])          # 10 sigma: chi2 100 > GATE
    assert 100 > GATE
    assert out.position[0, 0] == 50.0 and out.updates[0] == 20   # not taken
    assert sm.outliers[0] == 1
    out = _step(sm, 22, [[50, 60]])
    assert out.position[0, 0] == pytest.approx(50.0) and sm.outliers[0] == 0


def test_jumps_in_a_row_start_the_filter_again_at_the_new_place():
    sm = Smoother(FPS)
    for f in range(1, 21):
        _step(sm, f, [[50, 60]])
    for f in range(21, 21 + JUMP):
        out = _step(sm, f, [[200, 60]])
    # the third outlier in a row restarts it there: one measurement, speed unknown again
    assert out.updates[0] == 1 and out.position.tolist() == [[200.0, 60.0]]
    assert out.speed()[1][0] == pytest.approx(SPEED0 * H)


def test_a_track_not_measured_is_carried_on_by_its_velocity():
    sm = Smoother(FPS)
    for f in range(1, 41):
        _step(sm, f, [[3.0 * f, 100.0]])
    out = _step(sm, 45, [[np.nan, np.nan]])                    # unseen from frame 41 to 45
    assert out.position[0, 0] == pytest.approx(135.0, abs=1.0)  # 5 frames on at 3 px
    assert out.updates[0] == 40


def test_rows_are_independent_and_a_row_never_measured_has_no_position():
    sm = Smoother(FPS)
    out = _step(sm, 1, [[10, 10], [np.nan, np.nan], [30, 30]], rows=(0, 40, 2))
    assert out.updates.tolist() == [1, 0, 1]
    assert np.isnan(out.position[1]).all() and out.position[2].tolist() == [30.0, 30.0]
    sm.clear(np.array([0]))
    assert _step(sm, 2, [[99, 99]]).updates.tolist() == [1]    # a new track took row 0
    assert Smoother(FPS).step(1, np.zeros(0, int), np.zeros((0, 2)), np.zeros(0)).position.shape \
        == (0, 2)


class _Camera:
    """A ground plane seen from above at 10 px a metre: world = (pixel - 100) / 10."""

    @staticmethod
    def world_of(boxes: np.ndarray) -> np.ndarray:
        b = np.asarray(boxes, float)
        return np.column_stack([(b[:, 0] + b[:, 2] / 2 - 100) / 10, (b[:, 1] + b[:, 3] - 100) / 10])


def test_on_the_ground_the_pixel_noises_are_carried_by_the_cameras_jacobian():
    boxes = np.array([[95.0, 80.0, 10.0, H]])
    J = jacobians(_Camera.world_of, boxes)
    assert np.allclose(J, np.eye(2)[None] / 10)                # 0.1 m a pixel in both axes
    out = Smoother(FPS).step(1, np.array([0]), _Camera.world_of(boxes), np.array([H]), J)
    assert out.position.tolist() == [[0.0, 0.0]]
    # 1 px of noise is 0.1 m; SPEED0 heights a second is 20 px/s = 2 m/s
    assert np.allclose(out.position_cov[0], np.eye(2) * 0.1 ** 2)
    assert out.speed()[1][0] == pytest.approx(SPEED0 * H / 10)


def test_above_the_horizon_a_track_has_no_ground_position():
    J = np.full((1, 2, 2), np.nan)
    out = Smoother(FPS).step(1, np.array([0]), np.array([[np.nan, np.nan]]), np.array([H]), J)
    assert out.updates.tolist() == [0] and np.isnan(out.position).all()
