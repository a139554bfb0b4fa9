# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The search for the joint goal.

The objective F = R + S (eq. 9-14), the fuzzy term, IEPSO and its peers, the polish, the
solution curves, and the search for a free joint goal.
"""
