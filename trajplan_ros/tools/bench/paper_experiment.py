# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The paper's experiment (Lv et al. 2019, section VI.B): its target and Table 5 as printed."""
from __future__ import annotations

import numpy as np

__all__ = ['PAPER_TARGET', 'PAPER_TABLE5']

#: The target of section VI.B, m (the paper's (151.171, 191.62, 172.124) mm), reached from the
#: upright pose q = 0.
PAPER_TARGET = np.array([0.151171, 0.19162, 0.172124])
PAPER_TARGET.flags.writeable = False

#: Table 5 as printed: algorithm -> (q1..q4 in rad, efficiency scalar F, error in mm).
PAPER_TABLE5: dict[str, tuple[tuple[float, ...], float, float]] = {
    'pso': ((-2.24, -1.31, 1.06, -1.11), 8.71e4, 10.41),
    'spso': ((0.89, 0.12, 1.47, -0.67), 5.52e2, 5.46),
    'iepso': ((0.9, 1.49, -0.23, 1.17), -16.56, 6.96e-14),
    'ga': ((0.9, 0.92, 0.84, -1.54), -3.59, 3.06e-4),
    'de': ((0.9, 0.09, 1.13, -0.09), -2.57, 0.12),
}
