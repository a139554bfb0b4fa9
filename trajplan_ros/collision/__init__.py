# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Collisions: the arm's geometry, the pairs to skip, the scene and the distances."""
