# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""``trajplan figures`` writes every figure as a valid, non-blank PNG of the promised size."""
from __future__ import annotations

from pathlib import Path
import struct
import sys
import zlib

import numpy as np
import pytest

from trajplan_ros.tools.cli import main
from trajplan_ros.tools.figures import FIGURES

PNG_SIGNATURE = b'\x89PNG\r\n\x1a\n'


def _png_chunks(data: bytes) -> list[tuple[bytes, bytes]]:
    """(type, payload) of every chunk, each CRC checked."""
    assert data[:8] == PNG_SIGNATURE
    chunks, pos = [], 8
    while pos < len(data):
        length, kind = struct.unpack('>I4s', data[pos:pos + 8])
        payload = data[pos + 8:pos + 8 + length]
        (crc,) = struct.unpack('>I', data[pos + 8 + length:pos + 12 + length])
        assert crc == zlib.crc32(kind + payload), f'bad CRC in {kind!r}'
        chunks.append((kind, payload))
        pos += 12 + length
    return chunks


def check_png(path: Path, width: int, height: int) -> None:
    """Check for a complete PNG of width x height pixels whose data inflates to that size."""
    chunks = _png_chunks(path.read_bytes())
    assert chunks[0][0] == b'IHDR' and chunks[-1][0] == b'IEND'
    w, h, depth, colour, _, _, interlace = struct.unpack('>IIBBBBB', chunks[0][1])
    assert (w, h) == (width, height)
    assert depth == 8 and colour in (2, 6) and interlace == 0          # 8-bit RGB(A)
    pixels = zlib.decompress(b''.join(p for k, p in chunks if k == b'IDAT'))
    assert len(pixels) == h * (1 + w * (4 if colour == 6 else 3))      # a filter byte per row


@pytest.fixture(scope='module')
def figures(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Write every figure once for this module's tests, into a folder the command creates."""
    pytest.importorskip('matplotlib')
    out = tmp_path_factory.mktemp('figures') / 'new'          # created by the command
    assert main(['figures', str(out), '--runs', '2', '--dpi', '50']) == 0
    return out


def test_every_figure_is_a_valid_png_of_its_size(figures: Path) -> None:
    assert sorted(p.name for p in figures.iterdir()) == sorted(FIGURES)
    for name, (width_in, height_in) in FIGURES.items():
        check_png(figures / name, round(width_in * 50), round(height_in * 50))


def test_figures_are_not_blank(figures: Path) -> None:
    from matplotlib.image import imread

    for name in FIGURES:
        rgb = imread(figures / name)[..., :3]
        ink = np.mean(np.any(rgb < 0.9, axis=-1))                # share of non-white pixels
        coloured = np.mean(np.ptp(rgb, axis=-1) > 0.2)             # share of coloured pixels
        assert ink > 0.02 and coloured > 0.002, name


def test_cli_lists_the_files(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip('matplotlib')
    assert main(['figures', str(tmp_path), '--runs', '1', '--dpi', '20']) == 0
    printed = capsys.readouterr().out.split()
    assert printed == [str(tmp_path / name) for name in FIGURES]


def test_without_matplotlib_says_how_to_install(monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setitem(sys.modules, 'matplotlib', None)    # import matplotlib -> ImportError
    assert main(['figures', str(tmp_path)]) == 1
    assert 'pip install matplotlib' in capsys.readouterr().err
    assert not any(tmp_path.iterdir())
