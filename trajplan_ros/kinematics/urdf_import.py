# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
A serial chain from a URDF document (``ArmModel.from_urdf``).

The text is untrusted (it may come from the network as ``robot_description``): it is refused
above 10 MB, read first by defusedxml, which refuses any DTD (so no entity expansion, no
external entity, no file or URL is read), and refused above 1000 links; only then does yourdfpy
parse it into links and joints, without meshes (``package://`` URIs need not exist here).

The chain runs from ``base_link`` to ``tip_link``, through the URDF tree's joints. Fixed joints
are folded into the link transforms; revolute and continuous joints are the chain's joints, all
planned, with the URDF's names, limits (none for a continuous joint) and velocity limits. Joint
i's frame is its URDF joint frame (the parent link's frame moved by the joint origin) turned so
that z is the joint axis: child = parent * origin * A Rz(q) A^T with A z = axis, so the URDF
joint value is q. Links off the chain (grippers, fingers, sensors) are ignored. A prismatic,
floating, planar or mimic joint on the chain is refused, as are chains with fewer than 2 or more
than 7 joints, cycles, unusable axes and origins, and velocity limits below 1e-6 rad/s (a limit
of 0, a placeholder in many files, means none).

With no ``base_link`` the URDF's root is the base; with no ``tip_link`` the tip is the child
link of the last revolute joint of the only longest-reaching chain of revolute joints below the
base (ignoring fixed links after it); when there are several, the refusal lists them. When that
chain's last joint moves a leaf link whose parent carries another link too (a gripper's jaw
beside the tool frame, as on the SO-101), the tip is not guessed either: the refusal names both.
"""
from __future__ import annotations

from dataclasses import dataclass
import io
import os

import defusedxml.ElementTree
import numpy as np

from trajplan_ros.kinematics.errors import InvalidArmModel
from trajplan_ros.kinematics.lazy_modules import lazy

yourdfpy = lazy('yourdfpy')

__all__ = ['MAX_BYTES', 'MAX_LINKS', 'UrdfChain', 'joints_between', 'read_chain', 'read_urdf',
           'to_axis']

#: Largest URDF accepted, bytes.
MAX_BYTES = 10 * 1024 * 1024
#: Most links accepted.
MAX_LINKS = 1000
_MOVING = ('revolute', 'continuous')


def _text(urdf: str | os.PathLike | bytes) -> bytes:
    """
    Return the document's bytes, from XML text or a file path (size checked first).

    Bytes are always the document itself, never a path (the node passes untrusted text so).
    """
    if isinstance(urdf, bytes):
        data = urdf
    elif isinstance(urdf, str) and urdf.lstrip('\ufeff \t\r\n').startswith('<'):
        data = urdf.encode()
    else:
        try:
            size = os.path.getsize(urdf)
            if size > MAX_BYTES:
                raise InvalidArmModel(f'the URDF file {os.fspath(urdf)} is {size} bytes, over '
                                      f'the {MAX_BYTES} byte limit')
            with open(urdf, 'rb') as stream:
                data = stream.read(MAX_BYTES + 1)
        except (OSError, TypeError, ValueError) as exc:
            shown = repr(os.fspath(urdf) if isinstance(urdf, os.PathLike) else urdf)
            shown = shown if len(shown) <= 80 else shown[:77] + '...'
            raise InvalidArmModel(f'cannot read the URDF {shown}: '
                                  f'{getattr(exc, "strerror", None) or exc}') from None
    if len(data) > MAX_BYTES:
        raise InvalidArmModel(f'the URDF is {len(data)} bytes, over the {MAX_BYTES} byte limit')
    return data


def read_urdf(urdf: str | os.PathLike | bytes) -> yourdfpy.Robot:
    """Return the links and joints of a URDF (XML text, bytes or a path), checked as above."""
    data = _text(urdf)
    try:
        root = defusedxml.ElementTree.fromstring(data, forbid_dtd=True)
    except defusedxml.DTDForbidden:
        raise InvalidArmModel('the URDF declares a DTD (entities are refused: untrusted '
                              'text)') from None
    except (defusedxml.DefusedXmlException, SyntaxError) as exc:
        raise InvalidArmModel(f'the URDF is not well-formed XML: {exc}') from None
    if root.tag != 'robot' or not root.get('name'):
        raise InvalidArmModel(f'the URDF root element is <{root.tag}>, not <robot name="...">')
    links = len(root.findall('link'))
    if links > MAX_LINKS:
        raise InvalidArmModel(f'the URDF has {links} links, over the limit of {MAX_LINKS}')
    try:
        model = yourdfpy.URDF.load(io.BytesIO(data), build_scene_graph=False,
                                   build_collision_scene_graph=False, load_meshes=False,
                                   load_collision_meshes=False)
    except Exception as exc:                       # yourdfpy raises plain errors on bad values
        raise InvalidArmModel(f'the URDF is not valid: {type(exc).__name__}: {exc}') from None
    return model.robot


def _parents(robot: yourdfpy.Robot) -> dict[str, yourdfpy.Joint]:
    """Return each link's parent joint, refusing links that are not a tree."""
    names = {link.name for link in robot.links}
    parents: dict[str, yourdfpy.Joint] = {}
    for joint in robot.joints:
        for end in (joint.parent, joint.child):
            if end not in names:
                raise InvalidArmModel(f'joint {joint.name!r} names link {end!r}, which the URDF '
                                      'does not define')
        if joint.child in parents:
            raise InvalidArmModel(f'link {joint.child!r} has two parent joints: '
                                  f'{parents[joint.child].name!r} and {joint.name!r}')
        parents[joint.child] = joint
    for link in parents:                       # a tree has no cycle: every walk up ends
        seen = {link}
        while link in parents:
            link = parents[link].parent
            if link in seen:
                raise InvalidArmModel(f'the URDF joints form a cycle through link {link!r}')
            seen.add(link)
    return parents


def _path(parents: dict[str, yourdfpy.Joint], base: str, tip: str) -> list[yourdfpy.Joint]:
    """Return the joints from ``base`` down to ``tip``; refuse when tip is not below base."""
    path, link = [], tip
    while link != base:
        if link not in parents:
            raise InvalidArmModel(f'link {tip!r} is not below link {base!r} in the URDF tree')
        path.append(parents[link])
        link = parents[link].parent
    return path[::-1]


def joints_between(robot: yourdfpy.Robot, base: str, tip: str) -> list[yourdfpy.Joint]:
    """Return the joints from link ``base`` down to link ``tip`` (InvalidArmModel if none)."""
    return _path(_parents(robot), base, tip)


def _default_base(robot: yourdfpy.Robot, parents: dict[str, yourdfpy.Joint]) -> str:
    roots = [link.name for link in robot.links if link.name not in parents]
    if len(roots) != 1:
        raise InvalidArmModel(f'the URDF has {len(roots)} root links ({", ".join(roots)}); '
                              'name the base link')
    return roots[0]


def _default_tip(robot: yourdfpy.Robot, parents: dict[str, yourdfpy.Joint], base: str) -> str:
    """Return the child of the last revolute joint of the only maximal revolute chain."""
    chains = set()
    for link in robot.links:
        try:
            path = _path(parents, base, link.name)
        except InvalidArmModel:
            continue
        moving = tuple(j for j in path if j.type in _MOVING)
        if moving:
            chains.add(tuple(j.name for j in moving))
    ends = sorted({c[-1] for c in chains if not any(o[:len(c)] == c and o != c for o in chains)})
    by_name = {j.name: j for j in robot.joints}
    tips = [by_name[name].child for name in ends]
    if len(tips) != 1:
        raise InvalidArmModel(
            f'no revolute joint below link {base!r}' if not tips else
            f'the tip link is ambiguous: the revolute chains below {base!r} end at '
            f'{", ".join(tips)}; name the tip link')
    _refuse_a_jaw(robot, by_name[ends[0]])
    return tips[0]


def _refuse_a_jaw(robot: yourdfpy.Robot, last: yourdfpy.Joint) -> None:
    """
    Refuse to guess when the chain's last joint may be a gripper's jaw.

    That is when its child is a leaf and its parent link carries another link too (the SO-101:
    the jaw beside ``gripper_frame_link``): either may be the tip that is meant.
    """
    children: dict[str, list[str]] = {}
    for joint in robot.joints:
        children.setdefault(joint.parent, []).append(joint.child)
    siblings = [c for c in children.get(last.parent, []) if c != last.child]
    if last.child not in children and siblings:
        raise InvalidArmModel(
            f'the tip link is ambiguous: the last revolute joint {last.name!r} moves the leaf '
            f'link {last.child!r} (a gripper jaw?) beside {", ".join(map(repr, siblings))} on '
            f'link {last.parent!r}; name the tip link, one of '
            f'{", ".join(map(repr, [last.child, *siblings]))}')


def to_axis(axis: np.ndarray) -> np.ndarray:
    """Return a rotation A with A z = axis (unit): about z x axis, by the angle between them."""
    cross = np.array([-axis[1], axis[0], 0.0])
    s, c = np.linalg.norm(cross), axis[2]
    if s < 1e-12:
        return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    k = cross / s
    skew = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + s * skew + (1.0 - c) * skew @ skew


def _joint_values(joint: yourdfpy.Joint) -> tuple[np.ndarray, float, float, float]:
    """Return a revolute joint's rotation A, its limits and velocity limit."""
    axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), dtype=float)
    size = float(np.linalg.norm(axis)) if axis.shape == (3,) else np.nan
    if not np.isfinite(size) or size < 1e-9:
        raise InvalidArmModel(f'joint {joint.name!r} has no usable axis: {axis.tolist()}')
    limit = joint.limit
    lower, upper = -np.inf, np.inf
    if joint.type == 'revolute':
        if limit is None or limit.lower is None or limit.upper is None:
            raise InvalidArmModel(f'revolute joint {joint.name!r} has no lower and upper limit')
        lower, upper = float(limit.lower), float(limit.upper)
    # a velocity limit of 0 (or none) is a placeholder in many files: no limit
    velocity = float(limit.velocity) if limit is not None and limit.velocity else np.inf
    if not velocity >= 1e-6:
        raise InvalidArmModel(f'joint {joint.name!r} has velocity limit {velocity} rad/s: too '
                              'slow to plan with')
    return to_axis(axis / size), lower, upper, velocity


@dataclass(frozen=True)
class UrdfChain:
    """The parts of an ``ArmModel`` read from a URDF (see ``ArmModel.__init__``)."""

    rotations: np.ndarray
    translations: np.ndarray
    base: np.ndarray
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    velocity: tuple[float, ...]
    joint_names: tuple[str, ...]
    base_link: str
    tip_link: str


def read_chain(urdf: str | os.PathLike | bytes, base_link: str | None = None,
               tip_link: str | None = None) -> UrdfChain:
    """Return the chain of a URDF (see the module docstring; ``ArmModel.from_urdf``)."""
    robot = read_urdf(urdf)
    parents = _parents(robot)
    known = [link.name for link in robot.links]
    for name in (base_link, tip_link):
        if name is not None and name not in known:
            shown = ', '.join(known[:20]) + (f' and {len(known) - 20} more'
                                             if len(known) > 20 else '')
            raise InvalidArmModel(f'unknown link {name!r}; the URDF has {len(known)} links: '
                                  f'{shown}')
    base = base_link if base_link is not None else _default_base(robot, parents)
    tip = tip_link if tip_link is not None else _default_tip(robot, parents, base)
    pending, links, values = np.eye(4), [], []
    for joint in _path(parents, base, tip):
        origin = np.eye(4) if joint.origin is None else np.asarray(joint.origin, dtype=float)
        if origin.shape != (4, 4) or not np.all(np.abs(origin) <= 1e3):
            raise InvalidArmModel(f'joint {joint.name!r} has an unusable origin (finite, '
                                  'within 1 km)')
        pending = pending @ origin
        if joint.type == 'fixed':
            continue
        if joint.type not in _MOVING:
            raise InvalidArmModel(f'joint {joint.name!r} on the chain is {joint.type}: only '
                                  'revolute, continuous and fixed joints are supported')
        if joint.mimic is not None:
            raise InvalidArmModel(f'joint {joint.name!r} on the chain mimics '
                                  f'{joint.mimic.joint!r}: mimic joints are not supported')
        turn, lower, upper, velocity = _joint_values(joint)
        align = np.eye(4)
        align[:3, :3] = turn
        links.append(pending @ align)
        values.append((joint.name, lower, upper, velocity))
        pending = align.T
    if not 2 <= len(values) <= 7:
        raise InvalidArmModel(f'the chain {base} -> {tip} has {len(values)} revolute joints; '
                              'between 2 and 7 are supported')
    links.append(pending)
    after = np.stack(links[1:])
    names, lower, upper, velocity = zip(*values)
    return UrdfChain(after[:, :3, :3], after[:, :3, 3], links[0], lower, upper, velocity, names,
                     base, tip)
