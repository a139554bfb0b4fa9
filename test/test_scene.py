# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The scene (issue 29): its file, and its checks with one-line reasons."""
from pathlib import Path

import numpy as np
import pytest
from trajplan_ros.collision.errors import InvalidCollisionInput
from trajplan_ros.collision.scene import MAX_OBSTACLES, Scene

TABLE = {'id': 'table', 'type': 'box', 'dimensions': [1.2, 0.8, 0.04],
         'position': [0.3, 0.0, -0.02], 'orientation': [0, 0, 0, 1], 'touch_links': []}


def test_a_scene_file_reads_boxes_spheres_and_cylinders(tmp_path: Path) -> None:
    path = tmp_path / 'scene.yaml'
    path.write_text("""obstacles:
  - id: table
    type: box
    dimensions: [1.2, 0.8, 0.04]
    position: [0.3, 0.0, -0.02]
    orientation: [0, 0, 0, 1]
    touch_links: [link1]
  - {id: ball, type: sphere, dimensions: [0.05], position: [0.2, 0.2, 0.3]}
  - {id: post, type: cylinder, dimensions: [0.5, 0.02], position: [0.0, 0.3, 0.25]}
""")
    scene = Scene.from_file(path)
    assert [o.id for o in scene.obstacles] == ['table', 'ball', 'post']
    assert scene.obstacles[0].touch_links == {'link1'}
    assert scene.obstacles[0].contains(np.array([0.8, 0.3, -0.03]))
    assert not scene.obstacles[0].contains(np.array([0.3, 0.0, 0.01]))
    assert scene.obstacles[1].contains(np.array([0.2, 0.2, 0.34]))
    assert scene.obstacles[2].contains(np.array([0.0, 0.31, 0.49]))
    assert not scene.obstacles[2].contains(np.array([0.0, 0.33, 0.25]))


@pytest.mark.parametrize('change, reason', [
    ({'type': 'cone'}, "unknown type 'cone'"),
    ({'dimensions': [1.0, 2.0]}, 'a box has 3 dimensions'),
    ({'type': 'sphere'}, 'a sphere has 1 dimensions'),
    ({'dimensions': [1.0, -2.0, 1.0]}, 'finite and positive'),
    ({'dimensions': [1.0, float('nan'), 1.0]}, 'finite'),
    ({'position': [0.0, 0.0]}, 'position must be 3 finite numbers'),
    ({'orientation': [0, 0, 0, 2]}, 'unit quaternion'),
    ({'id': ''}, 'id must be a non-empty string'),
    ({'colour': 'red'}, "unknown keys \\['colour'\\]"),
    ({'touch_links': 'link1'}, 'touch_links must be a list'),
])
def test_a_bad_entry_refuses_the_scene_with_its_reason(change: dict, reason: str) -> None:
    with pytest.raises(InvalidCollisionInput, match=reason) as caught:
        Scene.from_dict({'obstacles': [TABLE, {**TABLE, 'id': 'other', **change}]})
    assert '\n' not in str(caught.value) and 'obstacle 2' in str(caught.value)


def test_too_many_or_repeated_obstacles_and_bad_files_are_refused(tmp_path: Path) -> None:
    many = [{**TABLE, 'id': f'box{i}'} for i in range(MAX_OBSTACLES + 1)]
    with pytest.raises(InvalidCollisionInput, match='over the limit of 1000'):
        Scene.from_dict({'obstacles': many})
    with pytest.raises(InvalidCollisionInput, match='unique'):
        Scene.from_dict({'obstacles': [TABLE, TABLE]})
    bad = tmp_path / 'bad.yaml'
    bad.write_text('obstacles: [\n  - id: x\n')
    with pytest.raises(InvalidCollisionInput, match='not YAML at line'):
        Scene.from_file(bad)
    with pytest.raises(InvalidCollisionInput, match='cannot read scene file'):
        Scene.from_file(tmp_path / 'missing.yaml')
