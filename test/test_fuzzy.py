# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Fuzzy rewards and punishment (eq. 15-17, Tables 1, 2, 4) in metres."""
import numpy as np
import pytest

from trajplan_ros.search.fuzzy import gaussian, OUTPUT_LEVELS, RewardPunishment, RULE_TABLE

S = RewardPunishment()
ERR_MAX = 0.748


def test_reward_pieces_match_table4_ranges():
    np.testing.assert_allclose(S.reward_value(np.array([0.0, S.s, S.eps])), [-24.0, -12.0, 0.0],
                               atol=1e-12)


def test_reward_reproduces_the_papers_ga_row():
    # Table 5: GA error 3.06e-4 mm -> beta1 = -11.27, F = 7.7 - 11.27 = -3.57 (printed -3.59)
    assert S.reward_value(np.array(3.06e-7)) == pytest.approx(-11.2667, abs=1e-4)


def test_reward_is_continuous_and_monotonic():
    err = np.linspace(0, S.eps, 20001)
    beta = S.reward_value(err)
    assert np.all(np.diff(beta) > 0)
    joint = S.reward_value(np.array([S.s * (1 - 1e-9), S.s * (1 + 1e-9)]))
    assert abs(joint[1] - joint[0]) < 1e-6


@pytest.mark.parametrize('scale', ['log', 'linear'])
def test_closeness_end_points_and_monotonic(scale):
    rp = RewardPunishment(lambda_scale=scale)
    np.testing.assert_allclose(rp.closeness(np.array([0.0, rp.eps, ERR_MAX]), ERR_MAX), [1, 0, -1],
                               atol=1e-12)
    lam = rp.closeness(np.logspace(-12, np.log10(ERR_MAX), 500), ERR_MAX)
    assert np.all(np.diff(lam) < 0)


def test_punishment_is_eq16():
    np.testing.assert_allclose(S.punishment(np.array([-1.0, 0.0])), [1e4, 1e4 * np.exp(-5)])


@pytest.mark.parametrize('tau', [0.0, 0.3, 0.7, 1.0])
def test_shaping_grows_strictly_with_error_above_eps(tau):
    err = np.logspace(np.log10(S.eps) + 1e-9, np.log10(ERR_MAX), 400)
    value = S(err, np.full(err.shape, tau), ERR_MAX)
    assert np.all(np.diff(value) > 0)
    assert value.min() > 0          # any error above eps costs more than any reward


def test_log_scale_keeps_a_slope_where_the_literal_eq15_is_flat():
    literal = RewardPunishment(lambda_scale='linear', fuzzy_rules=False)
    logged = RewardPunishment(fuzzy_rules=False)
    err = np.array([2e-3, 1e-5])           # 2 mm and 10 um
    tau = np.zeros(2)
    flat = np.ptp(literal(err, tau, ERR_MAX))
    assert flat < 3.0                      # literal alpha barely changes (doc/paper.md)
    assert np.ptp(logged(err, tau, ERR_MAX)) > 100 * flat


#: Table 1 of the paper as printed (columns VF SF LF LC BE ZC SC VC); it prints NPR for NRP.
TABLE1_AS_PRINTED = """
H VSP VSP VSP RSP NPR RLR RLR RSR
M VSP VVP VVP RSP NPR RLR RLR RSR
L VSP VVP RSP RSP NPR RLR RSR VSR
"""
#: Centres of the closeness sets VF..VC on lambda and of the H, M, L sets on tau.
CLOSENESS_CENTRES = [-1.0, -0.75, -0.5, -0.25, 0.0, 1 / 3, 2 / 3, 1.0]
TIME_CENTRES = {'H': 1.0, 'M': 0.5, 'L': 0.0}


def test_rule_table_is_table1():
    printed = {}
    for line in TABLE1_AS_PRINTED.strip().splitlines():
        row, *cells = line.split()
        printed[row] = tuple('NRP' if cell == 'NPR' else cell for cell in cells)
    assert RULE_TABLE == printed


@pytest.mark.parametrize('row', ['H', 'M', 'L'])
def test_sharp_rules_give_each_cells_output_level_at_its_centre(row):
    sharp = RewardPunishment(sigma=0.01)       # memberships vanish one set away from a centre
    lam = np.array(CLOSENESS_CENTRES)
    degree = sharp.rule_degree(lam, np.full(lam.shape, TIME_CENTRES[row]))
    np.testing.assert_array_equal(degree, [OUTPUT_LEVELS[cell] for cell in RULE_TABLE[row]])


def test_table1_punishes_less_as_the_error_closes_and_harder_when_slow():
    sharp = RewardPunishment(sigma=0.01)
    lam = np.array(CLOSENESS_CENTRES)
    degree = {row: sharp.rule_degree(lam, np.full(lam.shape, tau))
              for row, tau in TIME_CENTRES.items()}
    for row in degree.values():
        assert np.all(np.diff(row) >= 0)                  # VF -> VC: never more punishment
    assert np.all(degree['H'] <= degree['M']) and np.all(degree['M'] <= degree['L'])
    assert np.any(degree['H'] < degree['L'])


def test_rules_punish_slow_particles_harder():
    lam = np.full(3, -0.45)           # "little far"
    degree = S.rule_degree(lam, np.array([0.0, 0.5, 1.0]))
    assert degree[2] < degree[1] < degree[0]          # H: VSP, M: VVP, L: RSP
    slow, fast = S(np.full(2, 1e-3), np.array([1.0, 0.0]), ERR_MAX)
    assert slow > fast


def test_without_reward_nothing_is_given_below_eps():
    rp = RewardPunishment(reward=False)
    np.testing.assert_array_equal(rp(np.array([0.0, rp.eps]), np.zeros(2), ERR_MAX), [0.0, 0.0])


def test_gaussian_membership_of_table2():
    x = np.array([0.0, 1.0, 2.0])
    np.testing.assert_allclose(gaussian(x, 1.0, 2.0), [np.exp(-0.25), 1.0, np.exp(-0.25)])


@pytest.mark.parametrize('bad', [{'eps': -1.0}, {'s': 1e-3}, {'err_max': 1e-9},
                                 {'lambda_scale': 'cubic'}, {'k': np.nan}])
def test_invalid_settings_are_refused(bad):
    with pytest.raises(ValueError):
        RewardPunishment(**bad)


def test_empty_batches_are_fine():
    assert S(np.empty(0), np.empty(0), ERR_MAX).shape == (0,)
