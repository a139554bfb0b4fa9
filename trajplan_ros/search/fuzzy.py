# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Fuzzy rewards and punishment (Lv et al. 2019, section IV and VI.A), in SI units.

The paper works in millimetres; here every length is in metres, so its thresholds become
eps = 0.005 mm = 5e-6 m and s = 0.5e-6 mm = 5e-10 m. k = 10000 and j = 3 are dimensionless
gains on a term measured in seconds, exactly as in Table 4, so F values match Table 5.

Where the paper is silent or ill-posed, these are our choices (also listed in the README):

* err_max (eq. 15) is not defined in the paper. We take twice the arm's reach, the largest
  distance between a tool position and a goal inside the reach sphere.
* Eq. (15) is linear in err on the punishment side. With err_max reach-sized, lambda and so the
  punishment alpha (eq. 16) barely change between 2 mm and eps, and a swarm stalls millimetres
  from the goal (doc/paper.md). By default lambda is therefore log-scaled on that side,
  lambda = -ln(err/eps) / ln(err_max/eps): the same end points (0 at eps, -1 at err_max) and the
  same monotonic meaning, but alpha keeps a slope at every scale. ``lambda_scale="linear"`` is
  the literal eq. (15).
* Eq. (17) switches between its two reward pieces at lambda = 0.99, but the pieces only join
  at err = s (lambda = 1 - s/eps); Table 4's ranges (beta1 from 0 to -12, beta2 from -12 to -24)
  say the same. We switch at err = s, so the reward is continuous.
* Table 1's second input (High / Middle / Low) is not named in the paper. We read it as the
  particle's motion time relative to the longest possible one, tau = R / R_max, so that, as the
  table says, slow particles far from the goal are punished harder than fast ones.
* How the rule base's output acts is not stated either. The Table 1 rules are evaluated with
  Gaussian membership functions (Table 2), min for "and" (eq. 6) and a weighted mean of output
  singletons on [-1, 1]; the resulting degree lambda_R is averaged with lambda before eq. (16):
  lambda_eff = (lambda + lambda_R) / 2. Averaging keeps alpha strictly monotonic in the error
  (the table has flat runs such as VSP VSP VSP) while the table decides how hard to punish.
  The reward side uses eq. (17) unchanged, which keeps the paper's efficiency scalars
  (Table 5: F = R - 24 at zero error).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, NamedTuple

import numpy as np

from trajplan_ros.kinematics.jit import kernel

__all__ = ['RewardPunishment', 'RULE_TABLE', 'OUTPUT_LEVELS', 'Shaping', 'closeness_eq15',
           'gaussian', 'punishment_eq16', 'reward_eq17', 'rule_degree_table1', 'shaping_eq9']

#: Output levels of Table 1, as degrees of reward (+) or punishment (-) in [-1, 1].
OUTPUT_LEVELS: dict[str, float] = {
    'VSP': -1.0, 'VVP': -0.75, 'RSP': -0.5, 'RLP': -0.25,
    'NRP': 0.0, 'RLR': 0.25, 'RSR': 0.5, 'VSR': 1.0,
}
#: Table 1: rows are the second input (H, M, L), columns the closeness of the error
#: (VF, SF, LF, LC, BE, ZC, SC, VC). The paper prints "NPR" for NRP.
RULE_TABLE: dict[str, tuple[str, ...]] = {
    'H': ('VSP', 'VSP', 'VSP', 'RSP', 'NRP', 'RLR', 'RLR', 'RSR'),
    'M': ('VSP', 'VVP', 'VVP', 'RSP', 'NRP', 'RLR', 'RLR', 'RSR'),
    'L': ('VSP', 'VVP', 'RSP', 'RSP', 'NRP', 'RLR', 'RSR', 'VSR'),
}
#: Centres of the closeness sets VF..VC on lambda in [-1, 1] and of the H, M, L sets on tau,
#: and the output level of each rule (rows H, M, L). The rule base is evaluated in single
#: precision: seven digits are plenty for fuzzy degrees, and a membership one set away from a
#: narrow set's centre is then 0, not 1e-272.
_SINGLE = np.float32
_CLOSENESS_CENTRES = np.array([-1.0, -0.75, -0.5, -0.25, 0.0, 1 / 3, 2 / 3, 1.0], dtype=_SINGLE)
_TIME_CENTRES = {'L': 0.0, 'M': 0.5, 'H': 1.0}
_SINGLETONS = np.array([[OUTPUT_LEVELS[label] for label in RULE_TABLE[row]]
                        for row in ('H', 'M', 'L')], dtype=_SINGLE)
_ROW_CENTRES = np.array([_TIME_CENTRES[row] for row in ('H', 'M', 'L')], dtype=_SINGLE)


@kernel
def gaussian(x: np.ndarray, c: float, sigma: float) -> np.ndarray:
    """Return the Gaussian membership of Table 2, exp(-(x - c)^2 / sigma^2)."""
    return np.exp(-((x - c) ** 2) / sigma ** 2)


@kernel
def closeness_eq15(err: float, eps: float, err_max: float, log_scale: bool) -> float:
    """Return lambda of eq. (15) in [-1, 1] (log-scaled on the punishment side by default)."""
    if err <= eps:
        lam = 1.0 - err / eps
    elif log_scale:
        lam = -np.log(err / eps) / np.log(err_max / eps)
    else:
        lam = -(err - eps) / (err_max - eps)
    return min(max(lam, -1.0), 1.0)


@kernel
def rule_degree_table1(lam: float, tau: float, sigma: float) -> float:
    """
    Return the Table 1 inference, the degree lambda_R in [-1, 1] (0 where no rule fires).

    Rule strength min(mu_row(tau), mu_col(lambda)) (eq. 6), Gaussian memberships (Table 2),
    the strength-weighted mean of the rules' output levels, in single precision.
    """
    lam32, tau32, sigma32 = np.float32(lam), np.float32(tau), np.float32(sigma)
    total = weighted = np.float32(0.0)
    for r in range(_ROW_CENTRES.size):
        row = gaussian(tau32, _ROW_CENTRES[r], np.float32(2.0) * sigma32)
        for c in range(_CLOSENESS_CENTRES.size):
            strength = min(row, gaussian(lam32, _CLOSENESS_CENTRES[c], sigma32))
            total += strength
            weighted += strength * _SINGLETONS[r, c]
    return float(weighted / total) if total > 0.0 else 0.0


@kernel
def punishment_eq16(lam: float, k: float) -> float:
    """Return the punishment alpha of eq. (16), k exp(-5 (lambda + 1)^2)."""
    return k * np.exp(-5.0 * (lam + 1.0) ** 2)


@kernel
def reward_eq17(err: float, eps: float, s: float, j: float) -> float:
    """
    Return the reward of eq. (17): beta1 above s, beta2 at or below it.

    beta1 runs from 0 (err = eps) to -12 (err = s), beta2 from -12 to -24 (err = 0). The paper's
    0.02 / (eps - s) is 4 eps / (eps - s) with eps = 0.005 mm; written in eps it holds in any
    unit: beta1 = -j (-4 err + 4 eps) / (eps - s).
    """
    if err <= s:
        return -j * ((-4.0 / s) * err + 8.0)
    return -j * 4.0 * (eps - err) / (eps - s)


class Shaping(NamedTuple):
    """``RewardPunishment``'s settings as the kernels take them (``RewardPunishment.settings``)."""

    err_max: float          # lambda reaches -1 here (m), eq. (15)
    eps: float              # reward and punishment waken threshold (m)
    s: float                # reward waken threshold (m), eq. (17)
    k: float                # punishment gain, eq. (16)
    j: float                # reward gain, eq. (17)
    sigma: float            # width of the Gaussian memberships, Table 2
    log_scale: bool         # lambda on the log of the error (module docstring)
    rules: bool             # Table 1's rule base on the punishment
    rewarded: bool          # the reward of eq. (17) at all


@kernel
def shaping_eq9(err: np.ndarray, tau: np.ndarray, shaping: Shaping) -> np.ndarray:
    """
    Return S of eq. (9) for each error and time fraction: punishment above eps, else reward.

    With ``rules`` the punishment's lambda is averaged with Table 1's degree (module docstring).
    """
    sh = shaping
    out = np.empty(err.size)
    for i in range(err.size):
        if err[i] <= sh.eps:
            out[i] = reward_eq17(err[i], sh.eps, sh.s, sh.j) if sh.rewarded else 0.0
            continue
        lam = closeness_eq15(err[i], sh.eps, sh.err_max, sh.log_scale)
        if sh.rules:
            lam = 0.5 * (lam + rule_degree_table1(lam, min(max(tau[i], 0.0), 1.0), sh.sigma))
        out[i] = punishment_eq16(lam, sh.k)
    return out


def _each(kernel_of_one: Callable[..., float], *args: Any) -> np.ndarray:
    """Apply a kernel of scalars to every element of its broadcast arguments."""
    return np.vectorize(kernel_of_one, otypes=[float])(*args)


@dataclass(frozen=True)
class RewardPunishment:
    """The S term of eq. (9) with Table 4's defaults in metres."""

    #: Reward and punishment waken threshold (m); errors above it are punished.
    eps: float = 5e-6
    #: Reward waken threshold (m) between the two reward pieces of eq. (17).
    s: float = 5e-10
    #: Punishment gain (eq. 16).
    k: float = 10000.0
    #: Reward gain (eq. 17).
    j: float = 3.0
    #: Error at which lambda reaches -1 (m); None means twice the arm's reach.
    err_max: float | None = None
    #: "log" (default, see the module docstring) or "linear" (the literal eq. 15).
    lambda_scale: str = 'log'
    #: Apply the Table 1 rule base to the punishment.
    fuzzy_rules: bool = True
    #: Apply the reward (eq. 17); False gives the "no reward" curve of Fig. 10.
    reward: bool = True
    #: Width of the Gaussian membership functions.
    sigma: float = 0.15

    def __post_init__(self) -> None:
        values = (self.eps, self.s, self.k, self.j, self.sigma)
        if not all(np.isfinite(v) and v > 0 for v in values):
            raise ValueError('eps, s, k, j and sigma must be finite and positive')
        if not self.s < self.eps:
            raise ValueError(f's ({self.s}) must be below eps ({self.eps})')
        usable = self.err_max is None or (np.isfinite(self.err_max) and self.err_max > self.eps)
        if not usable:
            raise ValueError(f'err_max must be finite and above eps, got {self.err_max}')
        if self.lambda_scale not in ('log', 'linear'):
            raise ValueError(f"lambda_scale must be 'log' or 'linear', got {self.lambda_scale!r}")

    def closeness(self, err: np.ndarray, err_max: float) -> np.ndarray:
        """Return lambda of eq. (15), the degree in [-1, 1] to which the error approaches zero."""
        return _each(closeness_eq15, np.asarray(err, dtype=float), self.eps, err_max,
                     self.lambda_scale == 'log')

    def rule_degree(self, lam: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Return the Table 1 inference: degree lambda_R in [-1, 1] from closeness and time tau."""
        return _each(rule_degree_table1, np.asarray(lam, dtype=float),
                     np.asarray(tau, dtype=float), self.sigma)

    def punishment(self, lam: np.ndarray) -> np.ndarray:
        """Return the punishment alpha of eq. (16), k exp(-5 (lambda + 1)^2)."""
        return _each(punishment_eq16, np.asarray(lam, dtype=float), self.k)

    def reward_value(self, err: np.ndarray) -> np.ndarray:
        """Return the reward of eq. (17): beta1 above s, beta2 at or below it."""
        return _each(reward_eq17, np.asarray(err, dtype=float), self.eps, self.s, self.j)

    def settings(self, err_max: float) -> Shaping:
        """Return the settings as the kernels take them, lambda reaching -1 at ``err_max``."""
        return Shaping(float(err_max), float(self.eps), float(self.s), float(self.k),
                       float(self.j), float(self.sigma), self.lambda_scale == 'log',
                       bool(self.fuzzy_rules), bool(self.reward))

    def __call__(self, err: np.ndarray, tau: np.ndarray, err_max: float) -> np.ndarray:
        """Return S(err) of eq. (9): punishment above eps, reward at or below it."""
        err = np.asarray(err, dtype=float)
        tau = np.broadcast_to(np.asarray(tau, dtype=float), err.shape)
        return shaping_eq9(np.ascontiguousarray(err.ravel()), np.ascontiguousarray(tau.ravel()),
                           self.settings(err_max)).reshape(err.shape)
