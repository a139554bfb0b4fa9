# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""Tools around the library: the ``trajplan`` command, benchmarks, figures and the demo."""
