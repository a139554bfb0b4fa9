# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The license, stated the same way everywhere (ament_copyright is not on PyPI).

Every Python source file starts with a copyright line and an SPDX identifier; the LICENSE
file, package.xml and setup.py all name Apache-2.0.
"""
from pathlib import Path
import re
import xml.etree.ElementTree as ET

import pytest

REPO = Path(__file__).resolve().parents[1]
HEADER = re.compile(r'# Copyright \d{4} The trajplan_ros Authors\n'
                    r'# SPDX-License-Identifier: Apache-2\.0\n')
SOURCES = sorted([*REPO.joinpath('trajplan_ros').rglob('*.py'),
                  *REPO.joinpath('test').glob('*.py'), REPO / 'setup.py'])


@pytest.mark.linter
@pytest.mark.parametrize('path', SOURCES, ids=lambda p: str(p.relative_to(REPO)))
def test_source_file_has_the_spdx_header(path: Path) -> None:
    text = path.read_text(encoding='utf-8')
    assert HEADER.match(text), f'{path.relative_to(REPO)}: no copyright and SPDX header'


@pytest.mark.linter
def test_license_is_apache_2_everywhere() -> None:
    license_text = (REPO / 'LICENSE').read_text(encoding='utf-8')
    assert 'Apache License' in license_text and 'Version 2.0, January 2004' in license_text
    package = ET.parse(REPO / 'package.xml').getroot()
    assert [e.text for e in package.findall('license')] == ['Apache-2.0']
    setup = (REPO / 'setup.py').read_text(encoding='utf-8')
    assert re.search(r"license='Apache-2\.0'", setup)
