# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Motion in time: the servo law (eq. 10), the profiles, rest-to-rest phases, trajectories."""
