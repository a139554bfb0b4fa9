# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""bench-detours' tables: what each column counts, on rows made by hand."""
from trajplan_ros.tools.bench.detour_bench import _report, Row


def _row(status: str = 'not_reached', **values) -> Row:
    """Return a row of the arm 'arm' planned in 10 ms with detours off."""
    return Row('arm', 0, 1, [0.1, 0.2, 0.3], status, 0.01, **values)


def test_the_tables_count_blocked_reachable_planned_and_compare_with_ompl() -> None:
    rows = [_row(blocked=True, time_with_detours=0.05, detour_motion=1.0, detour_vias=1,
                 clear_goals=4, ompl_motion=2.0, ompl_time=0.2),          # ours 0.5x
            _row(blocked=True, time_with_detours=0.07, detour_motion=3.0, detour_vias=2,
                 clear_goals=3, ompl_motion=2.0, ompl_time=0.4),          # ours 1.5x
            _row(blocked=True, time_with_detours=0.2, clear_goals=2, ompl_motion=1.0,
                 ompl_time=0.1),                                          # reachable, missed
            _row(blocked=True, time_with_detours=0.3),                    # no clear pose
            _row('succeeded', same_with_detours=True, time_with_detours=0.011),
            _row('succeeded', same_with_detours=False, time_with_detours=0.009)]
    blocked, peer, free = (table.splitlines() for table in _report(rows).split('\n\n'))
    assert blocked[1].split() == ['arm', '6', '4', '3', '3', '2', '(', '66.7', '%)', '0', '/',
                                  '0', '0']
    # both 2, ours no slower on 1; ratios 0.5 and 1.5; to the best 1 and 1.5, 2 and 1; 5x and 7x
    assert peer[1].split() == ['arm', '2', '1', '(', '50.0', '%)', '1.000', '1.250', '/',
                               '1.500', '60', '300', '6.00']
    assert free[1].split() == ['arm', '2', '1', '10.0', '10.0', '1.000']
