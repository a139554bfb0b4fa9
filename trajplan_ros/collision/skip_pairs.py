# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The link pairs never checked against each other: from an SRDF, or computed as MoveIt does.

An SRDF's ``<disable_collisions link1= link2= reason=/>`` elements name them (``read_srdf``;
the text is untrusted and read by defusedxml). Without one, ``computed_skip_pairs`` finds them
once per arm as MoveIt Setup Assistant does, deterministically (fixed seed): links that are
adjacent (one's parent joint hangs from the other, or no planned joint moves one against the
other), pairs in contact at the default pose (every joint at 0, or the limit nearest it), and
pairs in contact in at least ``ALWAYS`` of ``SAMPLES`` random configurations (a pair is no longer
sampled once it has missed contact too often to get there). Unlike MoveIt it does not skip
pairs that were never seen in contact: a rare contact is a real one.
"""
from __future__ import annotations

from typing import Callable

import defusedxml.ElementTree
import numpy as np

from trajplan_ros.collision.arm_geometry import ArmGeometry
from trajplan_ros.collision.errors import InvalidCollisionInput

__all__ = ['ALWAYS', 'SAMPLES', 'SEED', 'SkipPairs', 'computed_skip_pairs', 'read_srdf']

#: Random configurations of the computed list.
SAMPLES = 10_000
#: Share of those in which a pair in contact counts as always in contact.
ALWAYS = 0.95
#: The fixed seed of those samples.
SEED = 29
#: Largest SRDF accepted, bytes.
MAX_SRDF_BYTES = 10 * 1024 * 1024

#: Unordered link-name pairs, each as a sorted tuple.
SkipPairs = frozenset


def _pair(a: str, b: str) -> tuple[str, str]:
    return (a, b) if a <= b else (b, a)


def read_srdf(srdf: str | bytes) -> SkipPairs:
    """Return the pairs an SRDF document (text) disables, or refuse it with the reason."""
    data = srdf.encode() if isinstance(srdf, str) else srdf
    if len(data) > MAX_SRDF_BYTES:
        raise InvalidCollisionInput(f'the SRDF is {len(data)} bytes, over the {MAX_SRDF_BYTES} '
                                    'byte limit')
    try:
        root = defusedxml.ElementTree.fromstring(data, forbid_dtd=True)
    except defusedxml.DTDForbidden:
        raise InvalidCollisionInput('the SRDF declares a DTD (refused: untrusted text)') from None
    except (defusedxml.DefusedXmlException, SyntaxError) as exc:
        raise InvalidCollisionInput(f'the SRDF is not well-formed XML: {exc}') from None
    if root.tag != 'robot':
        raise InvalidCollisionInput(f'the SRDF root element is <{root.tag}>, not <robot>')
    pairs = set()
    for element in root.iter('disable_collisions'):
        a, b = element.get('link1'), element.get('link2')
        if not a or not b:
            raise InvalidCollisionInput('an SRDF <disable_collisions> lacks link1 or link2')
        pairs.add(_pair(a, b))
    return frozenset(pairs)


def adjacent_pairs(geometry: ArmGeometry, parent_of: Callable[[str], str | None]
                   ) -> set[tuple[str, str]]:
    """Return pairs of links joined by a joint, or moved by the same chain joints (rigid)."""
    names = [link.name for link in geometry.links]
    out = set()
    for i, a in enumerate(geometry.links):
        for b in geometry.links[i + 1:]:
            if a.joint == b.joint or parent_of(a.name) == b.name or parent_of(b.name) == a.name:
                out.add(_pair(a.name, b.name))
    # a link joined to a geometry-less link that is joined to another (a flange between two)
    for name in names:
        up = parent_of(name)
        if up is not None and up not in names and parent_of(up) in names:
            out.add(_pair(name, parent_of(up)))
    return out


def computed_skip_pairs(geometry: ArmGeometry, parent_of: Callable[[str], str | None],
                        in_contact: Callable[[np.ndarray, np.ndarray], np.ndarray],
                        samples: int = SAMPLES) -> tuple[SkipPairs, dict[str, int]]:
    """
    Return the skip pairs computed as the module says, and how many each reason gave.

    ``in_contact(q, pairs)``: for joint angles q (N, n_joints), which of the link pairs (P, 2)
    are in contact, (N, P) booleans (``ArmCollision.contacts``).
    """
    arm = geometry.arm
    names = [link.name for link in geometry.links]
    adjacent = adjacent_pairs(geometry, parent_of)
    pairs = np.array([(i, j) for i in range(len(names)) for j in range(i + 1, len(names))
                      if _pair(names[i], names[j]) not in adjacent], dtype=np.int64).reshape(-1, 2)
    default = np.clip(np.zeros(arm.n_joints), arm.lower, arm.upper)
    at_default = in_contact(default[None], pairs)[0]
    touching = {_pair(names[i], names[j]) for i, j in pairs[at_default]}
    pairs = pairs[~at_default]
    rng = np.random.default_rng(SEED)
    lower = np.where(np.isfinite(arm.lower), arm.lower, -np.pi)
    upper = np.where(np.isfinite(arm.upper), arm.upper, np.pi)
    misses = np.zeros(len(pairs))             # samples without contact, per pair
    for chunk in np.array_split(np.arange(samples), max(1, samples // 1000)):
        q = rng.uniform(lower, upper, (len(chunk), arm.n_joints))
        undecided = np.flatnonzero(misses <= (1.0 - ALWAYS) * samples)   # others: never always
        if undecided.size:
            misses[undecided] += len(chunk) - in_contact(q, pairs[undecided]).sum(axis=0)
    always = {_pair(names[i], names[j]) for i, j in pairs[misses <= (1.0 - ALWAYS) * samples]}
    reasons = {'adjacent': len(adjacent), 'default': len(touching),
               'always': len(always - touching)}
    return frozenset(adjacent | touching | always), reasons
