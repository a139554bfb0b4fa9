# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The compiled linearisation of the polish, against independent numpy computations."""
import numpy as np
import pytest

from trajplan_ros import ArmModel, paper_arm
from trajplan_ros.kinematics.rotations import quaternions
from trajplan_ros.search.goal import Goal
from trajplan_ros.search.linearisation import (complete_null_basis, invert_symmetric,
                                               line_minimax, line_searches)
from trajplan_ros.search.objective import Objective
from trajplan_ros.search.polish import Linearisation


def random_arm(rng: np.random.Generator, n: int) -> ArmModel:
    return ArmModel.from_dh(
        a=rng.uniform(0.05, 0.2, n), alpha=rng.choice([np.pi / 2, -np.pi / 2, 0.3], n),
        d=rng.uniform(0, 0.1, n), lower=-np.full(n, 2.5), upper=np.full(n, 2.5),
        velocity=rng.uniform(0.1, 0.5, n))


#: The objectives' names: 0 to 4 null directions, free and radial, on a few arms; poses on six
#: and seven joints (the second tool axis in the residuals).
NAMES = [f'{arm}-{mode}' for arm in ('paper', 'dh5', 'dh6', 'dh7') for mode in ('free', 'radial')
         ] + ['dh6-pose', 'dh7-pose']


def objective(name: str) -> Objective:
    """Return the objective ``name`` (built in the test: no kernel runs at collection)."""
    rng = np.random.default_rng(11)
    arms = {'paper': paper_arm(), **{f'dh{n}': random_arm(rng, n) for n in (5, 6, 7)}}
    arm_name, mode = name.split('-')
    arm = arms[arm_name]
    rng = np.random.default_rng([11, list(arms).index(arm_name)])
    frame = arm.frames(rng.uniform(arm.lower, arm.upper, (1, arm.n_joints)))[0, -1]
    start = rng.uniform(arm.lower, arm.upper, arm.n_joints)
    orientation = quaternions(frame[None, :3, :3])[0] if mode == 'pose' else None
    return Objective(arm, Goal(frame[:3, 3], mode=mode, orientation=orientation), start)


def residuals(obj: Objective, x: np.ndarray) -> np.ndarray:
    return obj.residuals(obj.tool(x))


@pytest.mark.parametrize('name', NAMES)
def test_linearisation_matches_numpy(name: str) -> None:
    obj = objective(name)
    rng = np.random.default_rng(3)
    x = rng.uniform(obj.lower, obj.upper, (12, obj.arm.planned))
    here = Linearisation.at(obj, x, 7.0)
    c = residuals(obj, x)
    np.testing.assert_allclose(here.c, c, rtol=0, atol=1e-15)
    np.testing.assert_allclose(here.time, obj.motion_time(x), rtol=1e-15)
    travel = np.abs(x - obj.planned_start).sum(axis=1)
    merit = here.time * obj.omega + 1e-6 * travel + 7.0 * np.linalg.norm(c, axis=1)
    np.testing.assert_allclose(here.merit, merit, rtol=1e-14)
    h = 1e-7                                            # the Jacobian by central differences
    jac = np.stack([(residuals(obj, x + h * e) - residuals(obj, x - h * e)) / (2 * h)
                    for e in np.eye(x.shape[1])], axis=2)
    d = obj.tool_jacobian(x)                            # the Jacobian the kernels use
    exact = np.swapaxes(obj.linear_residuals(*(np.swapaxes(j, 1, 2) for j in d.jacobians())),
                        1, 2)
    np.testing.assert_allclose(exact, jac, rtol=0, atol=1e-7)
    jac = exact
    gram = jac @ np.swapaxes(jac, 1, 2)                 # J^T (J J^T + mu I)^-1, the damped J^+
    damp = 1e-12 * np.trace(gram, axis1=1, axis2=2)[:, None, None] * np.eye(gram.shape[1])
    pinv = np.swapaxes(jac, 1, 2) @ np.linalg.inv(gram + damp)
    np.testing.assert_allclose(here.pinv, pinv, rtol=0, atol=1e-6 * np.abs(pinv).max())
    free = max(x.shape[1] - c.shape[1], 0)
    assert here.null.shape == (12, free, x.shape[1])
    assert here.quad.shape == (12, free, free, x.shape[1])
    if not free:
        return
    # an orthonormal basis of the null space; with 2+ directions, numpy's complete QR's
    np.testing.assert_allclose(here.null @ np.swapaxes(here.null, 1, 2),
                               np.broadcast_to(np.eye(free), (12, free, free)), atol=1e-12)
    np.testing.assert_allclose(jac @ np.swapaxes(here.null, 1, 2), 0.0, atol=1e-6)
    if free > 1:
        q = np.linalg.qr(np.swapaxes(jac, 1, 2), mode='complete')[0][:, :, c.shape[1]:]
        np.testing.assert_allclose(here.null, np.swapaxes(q, 1, 2), atol=1e-6)
    # quad: -J^+ c''_ab / 2, c''_ab = n_a^T (d2c / dx2) n_b by central differences
    h = 1e-4
    for a in range(free):
        for b in range(free):
            na, nb = here.null[:, a], here.null[:, b]
            second = (residuals(obj, x + h * (na + nb)) - residuals(obj, x + h * (na - nb))
                      - residuals(obj, x - h * (na - nb)) + residuals(obj, x - h * (na + nb))
                      ) / (4 * h * h)
            expect = -0.5 * np.einsum('kir,kr->ki', pinv, second)
            np.testing.assert_allclose(here.quad[:, a, b], expect, rtol=0,
                                       atol=5e-5 * max(np.abs(expect).max(), 1.0))


def test_newton_only_leaves_the_null_space_out():
    obj = objective(NAMES[0])
    x = np.random.default_rng(4).uniform(obj.lower, obj.upper, (5, obj.arm.planned))
    full, newton = Linearisation.at(obj, x, 1.0), Linearisation.at(obj, x, 1.0, newton_only=True)
    assert newton.null.shape == (5, 0, 4) and newton.quad.shape == (5, 0, 0, 4)
    np.testing.assert_array_equal(newton.pinv, full.pinv)
    np.testing.assert_allclose(newton.newton(newton.c),
                               -np.einsum('kir,kr->ki', full.pinv, full.c), rtol=1e-15)


@pytest.mark.parametrize('size', [2, 3, 4, 5, 7])
def test_symmetric_inverse_matches_numpy(size):
    rng = np.random.default_rng(size)
    for _ in range(20):
        a = rng.normal(size=(size, size + 2))
        m = a @ a.T + 1e-3 * np.eye(size)
        inverse = np.empty((size, size))
        invert_symmetric(m.copy(), inverse)
        np.testing.assert_allclose(inverse, np.linalg.inv(m), rtol=1e-9,
                                   atol=1e-9 * np.abs(np.linalg.inv(m)).max())


@pytest.mark.parametrize('rows, dim', [(3, 5), (3, 7), (5, 7), (1, 4)])
def test_null_basis_is_numpys_complete_qr(rows, dim):
    rng = np.random.default_rng(rows * dim)
    for _ in range(20):
        a = rng.normal(size=(dim, rows))
        q = np.linalg.qr(a, mode='complete')[0]
        out = np.empty((dim - rows, dim))
        complete_null_basis(a.copy(), np.empty(rows), out)
        np.testing.assert_allclose(out, q[:, rows:].T, atol=1e-13)


def test_line_minimax_is_the_least_on_a_fine_grid():
    rng = np.random.default_rng(7)
    grid = np.linspace(0.0, 1.0, 20001)
    for _ in range(300):
        m = rng.integers(2, 8)
        b, n, a = rng.normal(size=m), rng.normal(size=m), rng.normal(size=m) * rng.choice(
            [0.0, 0.1, 1.0])
        zlo, zhi = -rng.uniform(0, 2), rng.uniform(0, 2)
        z = line_minimax(b, n, a, zlo, zhi, 1e-12)
        assert zlo <= z <= zhi
        zs = zlo + (zhi - zlo) * grid
        worst = np.abs(b + (n + a * zs[:, None]) * zs[:, None]).max(axis=1)
        assert np.abs(b + (n + a * z) * z).max() <= worst.min() + 1e-12


def test_line_minimax_breaks_ties_by_the_least_travel():
    # joint 0 sets the time (|1 + 0 z|), joint 1 moves from 0.5 to 0 at z = 0.5 and back
    z = line_minimax(np.array([1.0, 0.5]), np.array([0.0, -1.0]), np.array([0.0, 0.0]),
                     -1.0, 1.0, 1e-12)
    assert z == 0.5


def test_line_searches_lower_the_largest_displacement_within_the_radius():
    rng = np.random.default_rng(8)
    k, m = 200, 4
    null = rng.normal(size=(k, 1, m))
    null /= np.linalg.norm(null, axis=2, keepdims=True)
    quad = rng.normal(size=(k, 1, 1, m)) * 0.1
    base = rng.uniform(-0.9, 0.9, (k, m))
    start, scale = rng.uniform(-1, 1, m), rng.uniform(0.5, 2.0, m)
    radius = rng.uniform(0.01, 0.5, k)
    per_candidate = np.ascontiguousarray(np.broadcast_to(scale, (k, m)))
    out = line_searches(null, quad, base, start, per_candidate, -np.ones(m), np.ones(m), radius,
                        1e-12)
    # the step is (n + a z) z for one z with |z| <= radius, and z = 0 is among the candidates
    n, a = null[:, 0], quad[:, 0, 0]
    z = np.array([np.roots([a_k @ n_k, 1.0, -(o - b) @ n_k]) for a_k, n_k, o, b
                  in zip(a, n, out, base)])
    z = np.where(np.abs(z.real) <= np.abs(z.real).min(axis=1, keepdims=True), z.real, 0).sum(1)
    np.testing.assert_allclose(out, base + (n + a * z[:, None]) * z[:, None], atol=1e-12)
    assert np.all(np.abs(z) <= radius + 1e-12)
    linear = base + n * z[:, None]
    assert np.all((linear >= -1 - 1e-12) & (linear <= 1 + 1e-12))
    assert np.all(np.abs((out - start) * scale).max(axis=1)
                  <= np.abs((base - start) * scale).max(axis=1) + 1e-15)
