# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Arm model: DH forward kinematics, Jacobians and validation (eq. 1-2, Tables 3-4)."""
import numpy as np
import pytest

from trajplan_ros.kinematics import ArmModel, InvalidArmModel, paper_arm
from trajplan_ros.tools.bench.cases import PAPER_TARGET


def random_arm(rng: np.random.Generator, n: int) -> ArmModel:
    return ArmModel.from_dh(
        a=rng.uniform(0, 0.2, n), alpha=rng.choice([0, np.pi / 2, -np.pi / 2, 0.3], n),
        d=rng.uniform(0, 0.1, n), sign=rng.choice([-1, 1], n),
        offset=rng.uniform(-1, 1, n), lower=-np.full(n, 2.5), upper=np.full(n, 2.5))


def rotation(rng: np.random.Generator) -> np.ndarray:
    """Return a random rotation matrix (determinant +1)."""
    q = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    return q * np.linalg.det(q)


def general_arm(rng: np.random.Generator, n: int) -> ArmModel:
    """Return a chain as a URDF gives it: any link rotations, a moved base, an offset tool."""
    base = np.eye(4)
    base[:3, :3], base[:3, 3] = rotation(rng), rng.uniform(-0.1, 0.1, 3)
    return ArmModel([rotation(rng) for _ in range(n)], rng.uniform(-0.15, 0.15, (n, 3)),
                    base=base, tool_point=rng.uniform(-0.05, 0.05, 3),
                    tool_axis=rng.normal(size=3), sign=rng.choice([-1, 1], n),
                    offset=rng.uniform(-1, 1, n), lower=-np.full(n, 2.5), upper=np.full(n, 2.5),
                    planned=n - 1)


def test_paper_arm_upright_pose_is_the_papers_initial_position():
    p, u = paper_arm().tool(np.zeros((1, 5)))
    np.testing.assert_allclose(p[0], [0.037, 0.0, 0.337], atol=1e-15)
    np.testing.assert_allclose(u[0], [0.0, 0.0, 1.0], atol=1e-15)


def test_table5_iepso_row_lands_on_the_papers_target():
    p, _ = paper_arm().tool(np.array([[0.9, 1.49, -0.23, 1.17, 0.0]]))
    # Table 5 rounds to 0.01 rad, which leaves 0.8 mm (doc/paper.md)
    assert np.linalg.norm(p[0] - PAPER_TARGET) == pytest.approx(0.805e-3, abs=0.01e-3)


@pytest.mark.parametrize('n', [2, 5, 7, 6])
def test_chain_walk_matches_homogeneous_transforms(n):
    _, arm, q = arm_and_configurations(n, n)
    p, u = arm.tool(q)
    frames = arm.frames(q)
    np.testing.assert_allclose(p, frames[:, -1, :3, 3], atol=1e-14)
    np.testing.assert_allclose(u, frames[:, -1, :3, :3] @ arm.tool_axis, atol=1e-14)


def arm_and_configurations(n: int, seed: int) -> tuple[np.random.Generator, ArmModel, np.ndarray]:
    """
    Return an arm and 20 in-limit configurations.

    The paper's arm for n = 5, a general chain (``general_arm``) for n = 6, else a random DH arm.
    """
    rng = np.random.default_rng(seed)
    arm = {5: paper_arm, 6: lambda: general_arm(rng, 6)}.get(n, lambda: random_arm(rng, n))()
    return rng, arm, rng.uniform(arm.lower, arm.upper, (20, arm.n_joints))


def test_a_held_tail_walks_the_planned_joints_only():
    _, arm, q = arm_and_configurations(6, 1)
    for start in q[:3]:
        here = np.concatenate((q[:, : arm.planned], np.broadcast_to(start[arm.planned:], (20, 1))),
                              axis=1)
        tail = arm.held_tail(start)
        np.testing.assert_allclose(arm.tool(q[:, : arm.planned], tail=tail), arm.tool(here),
                                   atol=1e-15)
        d, full = arm.tool_jacobian(q[:, : arm.planned], tail=tail), arm.tool_jacobian(here)
        np.testing.assert_allclose(d.jp, full.jp, atol=1e-15)
        np.testing.assert_allclose(d.ju, full.ju, atol=1e-15)


@pytest.mark.parametrize('n', [3, 5, 7, 6])
def test_jacobian_matches_finite_differences(n):
    _, arm, q = arm_and_configurations(n, 10 + n)
    d = arm.tool_jacobian(q)
    p, jp, ju = d.p, d.jp, d.ju
    np.testing.assert_allclose(p, arm.tool(q)[0], atol=1e-15)
    np.testing.assert_allclose(d.u, arm.tool(q)[1], atol=1e-15)
    h = 1e-6
    for i in range(arm.planned):
        dq = np.zeros(arm.n_joints)
        dq[i] = h
        (pp, up), (pm, um) = arm.tool(q + dq), arm.tool(q - dq)
        np.testing.assert_allclose(jp[:, :, i], (pp - pm) / (2 * h), atol=1e-8)
        np.testing.assert_allclose(ju[:, :, i], (up - um) / (2 * h), atol=1e-8)


@pytest.mark.parametrize('n', [3, 5, 7, 6])
def test_hessian_matches_finite_differences(n):
    rng, arm, q = arm_and_configurations(n, 20 + n)
    d = arm.tool_jacobian(q)
    hessian = d.hessian()                                   # (20, planned, planned, 2, 3)
    assert hessian.shape == (20, arm.planned, arm.planned, 2, 3)
    np.testing.assert_array_equal(hessian, hessian.transpose(0, 2, 1, 3, 4))
    h = 1e-6                # each column of the Jacobian differentiated by each joint
    for j in range(arm.planned):
        dq = np.zeros(arm.n_joints)
        dq[j] = h
        plus, minus = arm.tool_jacobian(q + dq), arm.tool_jacobian(q - dq)
        np.testing.assert_allclose(hessian[:, :, j, 0], np.swapaxes(plus.jp - minus.jp, 1, 2)
                                   / (2 * h), atol=1e-8)
        np.testing.assert_allclose(hessian[:, :, j, 1], np.swapaxes(plus.ju - minus.ju, 1, 2)
                                   / (2 * h), atol=1e-8)
    # along a direction n the second derivative is n^T H n: against second differences of p, u
    direction = np.zeros_like(q)
    direction[:, : arm.planned] = rng.normal(size=(20, arm.planned))
    n_p = direction[:, : arm.planned]
    pdd, udd = np.einsum('ki,kijtc,kj->tkc', n_p, hessian, n_p)
    h = 1e-4
    (pp, up), (p0, u0), (pm, um) = (arm.tool(q + t * direction) for t in (h, 0.0, -h))
    np.testing.assert_allclose(pdd, (pp - 2 * p0 + pm) / h ** 2, atol=1e-6)
    np.testing.assert_allclose(udd, (up - 2 * u0 + um) / h ** 2, atol=1e-6)


def test_reach_bounds_every_tool_position():
    arm = paper_arm()
    q = np.random.default_rng(3).uniform(arm.lower, arm.upper, (5000, 5))
    assert np.linalg.norm(arm.tool(q)[0], axis=1).max() <= arm.reach


@pytest.mark.parametrize('change, reason', [
    ({'a': [0.1, np.nan]}, 'non-finite'),
    ({'lower': [0.0, 1.0], 'upper': [1.0, 0.5]}, 'lower limit'),
    ({'sign': [1, 2]}, 'sign'),
    ({'joint_names': ['j', 'j']}, 'distinct'),
    ({'joint_names': ['j', '']}, 'distinct'),
    ({'planned': 1}, 'planned'),
    ({'d': [0.0]}, 'needs 2 values'),
])
def test_invalid_models_are_refused_with_a_reason(change, reason):
    spec = {'a': [0.1, 0.1], 'alpha': [0, 0], 'd': [0, 0], 'lower': [-1, -1], 'upper': [1, 1]}
    spec.update(change)
    with pytest.raises(InvalidArmModel, match=reason):
        ArmModel.from_dh(**spec)


def test_an_arm_without_joints_is_refused():
    with pytest.raises(InvalidArmModel, match='no joints'):
        ArmModel.from_dh(a=[], alpha=[], d=[], lower=[], upper=[])
