"""Planar-arm forward kinematics: hand-made poses, and agreement with MuJoCo's fingertip site."""

from __future__ import annotations

import numpy as np
import pytest

from somarm.tasks import arms, kinematics


def test_hand_made_poses_of_the_two_link_arm():
    lengths = [0.4, 0.4]
    angles = np.array([[0.0, 0.0], [np.pi / 2, 0.0], [0.0, np.pi / 2], [np.pi / 2, -np.pi / 2], [np.pi, np.pi]])
    expected = np.array([[1.3, 0.0], [0.5, 0.8], [0.9, 0.4], [0.9, 0.4], [0.5, 0.0]])
    np.testing.assert_allclose(kinematics.forward(angles, lengths), expected, atol=1e-15)


def test_joint_positions_start_at_the_base_and_end_at_the_tip():
    rng = np.random.default_rng(0)
    angles = rng.uniform(-np.pi, np.pi, (3, 4, 20))
    lengths = arms.LINK_LENGTHS[20]
    points = kinematics.joint_positions(angles, lengths)
    assert points.shape == (3, 4, 21, 2)
    np.testing.assert_allclose(points[..., 0, :], np.broadcast_to([0.5, 0.0], (3, 4, 2)))
    np.testing.assert_allclose(points[..., -1, :], kinematics.forward(angles, lengths), atol=1e-14)
    segment = np.linalg.norm(np.diff(points, axis=-2), axis=-1)
    np.testing.assert_allclose(segment, np.broadcast_to(lengths, segment.shape), atol=1e-14)


@pytest.mark.parametrize("n_links", [2, 20])
def test_forward_equals_mujoco_fingertip_site(n_links):
    rng = np.random.default_rng(n_links)
    angles = rng.uniform(-np.pi, np.pi, (300, n_links))
    analytic = kinematics.forward(angles, arms.LINK_LENGTHS[n_links])
    np.testing.assert_allclose(arms.fingertips(angles, n_links), analytic, rtol=0, atol=1e-9)
    physics = arms.load_physics(n_links)  # the single model of models/armN.xml, too
    for a, tip in zip(angles[:20], analytic[:20], strict=True):
        physics.set_angles(a)
        np.testing.assert_allclose(physics.fingertip(), tip, rtol=0, atol=1e-9)


def test_joint_positions_equal_mujoco_body_origins():
    rng = np.random.default_rng(3)
    physics = arms.load_physics(20)
    angles = rng.uniform(-np.pi, np.pi, 20)
    physics.set_angles(angles)
    points = kinematics.joint_positions(angles, arms.LINK_LENGTHS[20])
    origins = np.array([physics.named.data.xpos[f"link{i + 1}", :2] for i in range(20)])
    np.testing.assert_allclose(points[:-1], origins, atol=1e-12)


def test_batched_fingertips_in_threads_equal_one_thread():
    rng = np.random.default_rng(4)
    angles = rng.uniform(-np.pi, np.pi, (2000, 2))
    np.testing.assert_array_equal(arms.fingertips(angles, 2, n_threads=2), arms.fingertips(angles, 2, n_threads=1))


@pytest.mark.parametrize("n_links", [2, 20])
def test_a_batch_runs_in_a_model_of_its_size_and_each_arm_lands_as_alone(n_links):
    rng = np.random.default_rng(5)
    angles = rng.uniform(-np.pi, np.pi, (300, n_links))
    whole = arms.fingertips(angles, n_links)  # in models of the most arms, chunk by chunk
    for n in (1, 5, 20, 100):
        if n <= 20:  # a training step's few arms: a model of exactly that many
            assert arms._batch(n_links, n).copies == n
        np.testing.assert_array_equal(arms.fingertips(angles[:n], n_links), whole[:n])
    np.testing.assert_array_equal(arms.fingertips(angles[7], n_links), whole[7])


@pytest.mark.parametrize("angles, lengths, match", [
    (np.zeros((4, 3)), [0.4, 0.4], r"shape \(\.\.\., 2\)"),
    (np.zeros(2), [[0.4, 0.4]], "1-D"),
    (0.0, [0.4], r"shape \(\.\.\., 1\)"),
])
def test_forward_rejects_mismatched_shapes(angles, lengths, match):
    with pytest.raises(ValueError, match=match):
        kinematics.forward(angles, lengths)


def test_fingertips_reject_unknown_arm_and_bad_shape():
    with pytest.raises(ValueError, match="n_links must be one of 2, 20"):
        arms.fingertips(np.zeros((1, 3)), 3)
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 20\)"):
        arms.fingertips(np.zeros((1, 2)), 20)
