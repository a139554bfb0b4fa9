# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The ROS 2 side: the planner node, its settings, its work queue and message conversion."""
