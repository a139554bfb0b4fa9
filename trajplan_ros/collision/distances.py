# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Distances between the arm's links and to the scene: exact ones with coal, bounds on spheres.

``ArmCollision`` is built once per arm: its geometry (``arm_geometry``), its spheres
(``spheres``), the pairs to skip (``skip_pairs``) and coal's geometry of every shape (meshes as
bounding-volume hierarchies of their triangles, primitives as themselves), with convex hulls of
each mesh and of each link. ``CollisionWorld`` adds a scene and the padding: the pairs to check
are the links' pairs not skipped, and every link a planned joint moves against every obstacle it
may not touch (the arm stands on its table: the base and what is fixed to it are not checked
against the world).

The exact distance of a pair is coal's least distance over their shapes (negative or zero in
contact); the sphere bound (``pair_lower_bounds``) is never above it. Between the two, a convex
hull holds its shape, so the distance of two hulls (GJK on a few hundred vertices, far cheaper
than the triangles' hierarchies of a detailed mesh) is never above the shapes' either:
``CollisionWorld.bounded`` asks the triangles only for the shape pairs whose hulls come within
the distance that matters (the link's hull first, then each shape's).
"""
from __future__ import annotations

from dataclasses import dataclass, field
import os
from typing import Any

import numpy as np
from trajplan_ros.collision.arm_geometry import ArmGeometry
from trajplan_ros.collision.convex import ConvexSet, pair_convex_bounds, POINTS
from trajplan_ros.collision.errors import InvalidCollisionInput
from trajplan_ros.collision.scene import Scene
from trajplan_ros.collision.shapes import MeshSource, Shape
from trajplan_ros.collision.skip_pairs import computed_skip_pairs, read_srdf, SAMPLES, SkipPairs
from trajplan_ros.collision.spheres import pair_lower_bounds, SphereModel
from trajplan_ros.kinematics import ArmModel, InvalidArmModel
from trajplan_ros.kinematics.lazy_modules import lazy
from trajplan_ros.kinematics.urdf_import import read_urdf

coal = lazy('coal')
trimesh = lazy('trimesh')

__all__ = ['ArmCollision', 'Body', 'CollisionWorld', 'convex_hull', 'DEFAULT_PADDING',
           'HULL_SLACK', 'PairTable']

#: Least clearance (m) a motion keeps, unless the caller says otherwise.
DEFAULT_PADDING = 0.01
#: Taken off every distance between convex hulls (m): it covers GJK's tolerance and qhull's
#: rounding (both far below it), so that a hull's distance stays below its shapes' own.
HULL_SLACK = 1e-5
#: ``pair_convex_bounds``' notes, where none are wanted.
_NO_NOTES = (np.empty((0, 4)), np.zeros(1, dtype=np.int64))
#: Primitive kinds as the kernels number them.
SHAPE_KINDS = {'box': 0, 'sphere': 1, 'cylinder': 2}
#: A point set thinner than this share of its extent is thickened before qhull (which fails on
#: flat input): the thicker hull still holds the points.
_FLAT = 1e-3
#: A pair table's entries are this far apart in the far link's sweep (m): between two entries
#: its bound is at most half of it below theirs.
TABLE_SWEEP = 5e-4
#: Most entries of one pair table.
TABLE_ENTRIES = 4096
#: A mesh's triangles are split into this many pieces (by halves along their longest extent),
#: each held by its own hull: tighter than the mesh's hull where the mesh is concave.
PIECES = 16
#: Fewest triangles of a piece.
PIECE_TRIANGLES = 8


def _transform(pose: np.ndarray) -> coal.Transform3s:
    return coal.Transform3s(np.ascontiguousarray(pose[:3, :3]), np.ascontiguousarray(pose[:3, 3]))


def convex_hull(points: np.ndarray) -> coal.ConvexBase | None:
    """
    Return coal's convex hull (qhull) of points (N, 3), or None for a point or nearly one.

    Points flat or on a line along some direction are first copied a little (``_FLAT`` of their
    extent) to both sides of it: the hull is then a thin solid, and still holds every point.
    """
    points = np.unique(np.asarray(points, dtype=float), axis=0)
    centred = points - points.mean(axis=0)
    axes = np.linalg.eigh(centred.T @ centred)[1].T          # principal directions, (3, 3)
    extents = np.ptp(centred @ axes.T, axis=0)
    if not np.max(extents) > 1e-9:
        return None
    for axis, extent in zip(axes, extents):
        if extent < _FLAT * np.max(extents):
            offset = _FLAT * np.max(extents) * axis
            points = np.vstack((points + offset, points - offset))
    vector = coal.StdVec_Vec3s()
    vector.extend(list(points))
    return coal.ConvexBase.convexHull(vector, True, 'Qt')


def _ball(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Return the centre and radius of a ball that holds points (N, 3)."""
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    return centre, float(np.max(np.linalg.norm(points - centre, axis=1)))


def _mesh_geometry(vertices: np.ndarray, faces: np.ndarray) -> coal.BVHModelOBBRSS:
    """Return coal's hierarchy of a mesh's triangles."""
    model = coal.BVHModelOBBRSS()
    model.beginModel(len(faces), len(vertices))
    model.addVertices(np.ascontiguousarray(vertices, dtype=float))
    model.addTriangles(np.ascontiguousarray(faces, dtype=np.int32))
    model.endModel()
    return model


@dataclass(frozen=True, eq=False)
class Piece:
    """A part of a mesh's triangles, in the shape's frame: their hull, hierarchy and ball."""

    hull: coal.CollisionGeometry
    geometry: coal.CollisionGeometry
    centre: np.ndarray
    radius: float


def _pieces(vertices: np.ndarray, faces: np.ndarray) -> tuple[Piece, ...]:
    """
    Return parts of a mesh's triangles that together are all of them, each with its hull.

    The triangles are halved by their centres along the longest extent, again and again, into
    ``PIECES`` groups of at least ``PIECE_TRIANGLES``; each group's hull holds its triangles.
    """
    triangles = vertices[faces]
    centres = triangles.mean(axis=1)
    groups = [np.arange(len(faces))]
    while len(groups) < PIECES and max(len(g) for g in groups) >= 2 * PIECE_TRIANGLES:
        split = []
        for group in groups:
            if len(group) < 2 * PIECE_TRIANGLES:
                split.append(group)
                continue
            axis = int(np.argmax(np.ptp(centres[group], axis=0)))
            order = group[np.argsort(centres[group, axis], kind='stable')]
            split += [order[:len(order) // 2], order[len(order) // 2:]]
        groups = split
    hulls = [convex_hull(triangles[g].reshape(-1, 3)) for g in groups]
    if len(groups) < 2 or any(h is None for h in hulls):
        return ()
    return tuple(Piece(h, _mesh_geometry(vertices, faces[g]), *_ball(triangles[g].reshape(-1, 3)))
                 for h, g in zip(hulls, groups))


@dataclass(frozen=True, eq=False)
class Solid:
    """One shape for coal, in its frame: itself, its convex hull (None if convex) and its pose."""

    geometry: coal.CollisionGeometry
    hull: coal.CollisionGeometry | None
    pose: np.ndarray
    pieces: tuple[Piece, ...]          # a mesh's parts (``_pieces``), or the shape alone

    @classmethod
    def of(cls, shape: Shape) -> Solid:
        """Return a shape's solid (a mesh's hull from its vertices, and its pieces')."""
        geometry = shape.coal_geometry()
        if shape.kind != 'mesh':
            points = trimesh.Trimesh(*_untransformed(shape), process=False).vertices
            return cls(geometry, None, shape.pose, (Piece(geometry, geometry, *_ball(points)),))
        hull = convex_hull(shape.vertices)
        pieces = _pieces(shape.vertices, shape.faces)
        if not pieces:
            pieces = (Piece(geometry if hull is None else hull, geometry,
                            *_ball(shape.vertices)),)
        return cls(geometry, hull, shape.pose, pieces)

    @property
    def cover(self) -> coal.CollisionGeometry:
        """Return the convex geometry that holds the shape: its hull, or itself."""
        return self.geometry if self.hull is None else self.hull


def _untransformed(shape: Shape) -> tuple[np.ndarray, np.ndarray]:
    """Return the vertices and faces of a mesh that holds a shape, in the shape's own frame."""
    mesh = shape.enclosing_mesh()
    inverse = np.linalg.inv(shape.pose)
    return mesh.vertices @ inverse[:3, :3].T + inverse[:3, 3], mesh.faces


def _hull_convex(hull: coal.ConvexBase, pose: np.ndarray, pieces: tuple = ()) -> tuple:
    """Return a coal hull as a ``ConvexSet`` convex: its vertices placed by pose, its graph."""
    vertices = hull.points() @ pose[:3, :3].T + pose[:3, 3]
    return (POINTS, vertices, [list(hull.neighbors(i)) for i in range(hull.num_points)],
            [_hull_convex(piece.hull, pose) for piece in pieces if len(pieces) > 1])


def _convex(shape: Shape, solid: Solid) -> tuple:
    """Return the ``ConvexSet`` convex that holds a shape, in its link's frame."""
    if shape.kind != 'mesh':
        return (SHAPE_KINDS[shape.kind], shape.dimensions, shape.pose)
    if solid.hull is not None:
        return _hull_convex(solid.hull, shape.pose, solid.pieces)
    vertices = np.unique(shape.vertices, axis=0)            # too flat for a hull: every vertex
    return (POINTS, vertices @ shape.pose[:3, :3].T + shape.pose[:3, 3], None)


@dataclass(frozen=True, eq=False)
class Body:
    """
    A link's or an obstacle's solids, and the hull of them all (``hull``, in the body's frame).

    A body of one solid has no hull of its own: its solid's cover stands for it.
    """

    solids: tuple[Solid, ...]
    hull: coal.CollisionGeometry | None

    @classmethod
    def of(cls, shapes: tuple[Shape, ...]) -> Body:
        """Return the body of shapes in one frame."""
        solids = tuple(Solid.of(s) for s in shapes)
        if len(solids) < 2:
            return cls(solids, None)
        # a hull holds its mesh, so the hull of the meshes' hulls' vertices holds the link
        points = [shape.enclosing_mesh().vertices if solid.hull is None else
                  solid.hull.points() @ shape.pose[:3, :3].T + shape.pose[:3, 3]
                  for shape, solid in zip(shapes, solids)]
        return cls(solids, convex_hull(np.vstack(points)))

    def placed(self, pose: np.ndarray) -> Placed:
        """Return the body placed by its frame's pose, for coal."""
        if self.hull is not None:
            return Placed(self, pose, self.hull, _transform(pose), False)
        only = self.solids[0]
        return Placed(self, pose, only.cover, _transform(pose @ only.pose), only.hull is None)


class Placed:
    """A body placed for coal: its cover's transform, and its solids' when first asked."""

    def __init__(self, body: Body, pose: np.ndarray, cover: coal.CollisionGeometry,
                 where: Any, exact: bool) -> None:
        self.body, self.pose = body, pose
        self.cover, self.where = cover, where
        self.exact = exact                 # the cover is the body itself (one convex solid)
        self._solids: list[tuple[Solid, Any, np.ndarray]] | None = None

    @property
    def solids(self) -> list[tuple[Solid, Any, np.ndarray]]:
        """Return the body's solids with their transforms and poses in the world."""
        if self._solids is None:
            if len(self.body.solids) == 1 and self.body.hull is None:
                only = self.body.solids[0]
                self._solids = [(only, self.where, self.pose @ only.pose)]
            else:
                self._solids = [(s, _transform(self.pose @ s.pose), self.pose @ s.pose)
                                for s in self.body.solids]
        return self._solids


def _coal_distance(g1: coal.CollisionGeometry, t1: Any, g2: coal.CollisionGeometry,
                   t2: Any) -> float:
    return coal.distance(g1, t1, g2, t2, coal.DistanceRequest(), coal.DistanceResult())


def _pieces_bound(one: tuple[Solid, Any, np.ndarray], other: tuple[Solid, Any, np.ndarray],
                  needed: float, decide: bool = False) -> float:
    """
    Return a lower bound of two placed shapes' distance, exact where it is at most ``needed``.

    Over their pieces' pairs, in the order of their balls' bound (branch and bound): a pair
    whose ball or hull bound is above ``needed``, or no lower than the least exact distance
    found, is not measured on its triangles. ``decide``: only whether it is at most
    ``needed`` matters; the first distance found at most that is returned.
    """
    (s1, t1, w1), (s2, t2, w2) = one, other
    centres1 = np.array([p.centre for p in s1.pieces]) @ w1[:3, :3].T + w1[:3, 3]
    centres2 = np.array([p.centre for p in s2.pieces]) @ w2[:3, :3].T + w2[:3, 3]
    balls = (np.linalg.norm(centres1[:, None] - centres2[None], axis=2)
             - np.array([p.radius for p in s1.pieces])[:, None]
             - np.array([p.radius for p in s2.pieces])[None]).ravel()
    best = bound = np.inf
    for n in np.argsort(balls, kind='stable'):
        if balls[n] >= best or balls[n] > needed:
            bound = min(bound, balls[n])
            break
        p1, p2 = s1.pieces[n // len(s2.pieces)], s2.pieces[n % len(s2.pieces)]
        if p1.hull is not p1.geometry or p2.hull is not p2.geometry:
            hull = _coal_distance(p1.hull, t1, p2.hull, t2) - HULL_SLACK
            if hull >= best:
                continue
            if hull > needed:
                bound = min(bound, hull)
                continue
        best = min(best, _coal_distance(p1.geometry, t1, p2.geometry, t2))
        if decide and best <= needed:
            break
    return min(best, bound)


def _bound(one: Placed, other: Placed, needed: float, tight: bool = False,
           decide: bool = False) -> tuple[float, bool]:
    """
    Return a lower bound of two placed bodies' distance, exact where it is at most ``needed``.

    Also returns whether the value is the exact distance. Each level asks the next only where
    its bound is at most ``needed``: the bodies' covers, then each shape pair's covers, then
    that pair's pieces (``_pieces_bound``: their hulls, then their triangles). ``tight``:
    always go down to the shapes' covers (the least bound short of the triangles).
    ``decide``: a value at most ``needed`` need not be the least (``_pieces_bound``).
    """
    d = _coal_distance(one.cover, one.where, other.cover, other.where)
    if one.exact and other.exact:
        return d, True
    alone = len(one.body.solids) == 1 and len(other.body.solids) == 1   # covers just asked
    if d - HULL_SLACK > needed and (alone or not tight):
        return d - HULL_SLACK, False
    best = np.inf
    for first in one.solids:
        for second in other.solids:
            s1, t1, _ = first
            s2, t2, _ = second
            if s1.hull is None and s2.hull is None:
                value = _coal_distance(s1.geometry, t1, s2.geometry, t2)
            else:
                value = (d if alone else _coal_distance(s1.cover, t1, s2.cover, t2)
                         ) - HULL_SLACK
                if value <= needed:
                    value = _pieces_bound(first, second, needed, decide)
            if value < best:
                best = value
            if decide and best <= needed:
                return best, True
    return best, bool(best <= needed) or (one.exact and other.exact)


def _within(one: Placed, other: Placed, margin: float) -> bool:
    """Return True when two placed bodies come closer than ``margin`` (exact verdict)."""
    return _bound(one, other, margin, decide=True)[0] < margin


def _contact(one: Placed, other: Placed) -> bool:
    """Return True when two placed bodies touch: coal's test, where their hulls meet."""
    if _coal_distance(one.cover, one.where, other.cover, other.where) - HULL_SLACK > 0.0:
        return False
    request, result = coal.CollisionRequest(), coal.CollisionResult()
    for s1, t1, _ in one.solids:
        for s2, t2, _ in other.solids:
            if _coal_distance(s1.cover, t1, s2.cover, t2) - HULL_SLACK > 0.0:
                continue
            result.clear()
            if coal.collide(s1.geometry, t1, s2.geometry, t2, request, result):
                return True
    return False


@dataclass(frozen=True, eq=False)
class PairTable:
    """
    Lower bounds of a pair of links' distance over the one joint that moves them apart.

    Links a joint apart on the chain (a jaw that hangs from the last frame and the link before
    it) move against each other by that joint alone, so their distance is a function of one
    angle. ``bounds[i]`` bounds it (the shapes' hulls) at angle ``lower + i * step``; a turn by
    dq moves them closer by at most ``slope`` |dq|, so over cell i (between entries i and i + 1)
    it is at least ``cells[i]`` = (bounds[i] + bounds[i + 1] - slope step) / 2. A joint without
    limits has one turn of entries, repeated.
    """

    pair: int                     # index in ArmCollision.self_pairs
    joint: int
    lower: float
    step: float
    slope: float
    cells: np.ndarray
    periodic: bool

    def least(self, start: float, end: float) -> float:
        """Return a lower bound of the distance while the joint turns from ``start`` to ``end``."""
        low, high = sorted(((start - self.lower) / self.step, (end - self.lower) / self.step))
        first, last = int(np.floor(low)), int(np.floor(high))
        count = len(self.cells)
        if self.periodic:
            if last - first + 1 >= count:
                return float(np.min(self.cells))
            return float(np.min(self.cells[np.arange(first, last + 1) % count]))
        if low < -1e-9 or high > count + 1e-9:           # beyond the joint's limits: no claim
            return -np.inf
        return float(np.min(self.cells[max(first, 0):min(last, count - 1) + 1]))

    def lowest(self, start: float, end: float) -> float:
        """Return the middle of the cell of the least bound on that turn (where it may be)."""
        low, high = sorted((start, end))
        middles = self.lower + self.step * (np.arange(len(self.cells)) + 0.5)
        if self.periodic:
            middles = low + np.mod(middles - low, 2 * np.pi)
        inside = (middles >= low - self.step) & (middles <= high + self.step)
        if not inside.any():
            return 0.5 * (low + high)
        return float(middles[inside][np.argmin(self.cells[inside])])


def _pair_tables(geometry: ArmGeometry, convexes: ConvexSet, pairs: np.ndarray
                 ) -> tuple[PairTable, ...]:
    """Return the tables of the pairs whose links one joint moves apart (``PairTable``)."""
    arm, links, out = geometry.arm, geometry.links, []
    for p, (a, b) in enumerate(pairs):
        near, far = sorted((a, b), key=lambda i: links[i].joint)
        joint = links[far].joint
        if joint != links[near].joint + 1:
            continue
        slope = float(geometry.reach[joint, far])
        periodic = not (np.isfinite(arm.lower[joint]) and np.isfinite(arm.upper[joint]))
        lower, upper = (-np.pi, np.pi) if periodic else (arm.lower[joint], arm.upper[joint])
        steps = np.ceil((upper - lower) * slope / TABLE_SWEEP)
        count = int(min(TABLE_ENTRIES, max(2, steps + 1)))
        angles = np.linspace(lower, upper, count)
        q = np.zeros((count, arm.n_joints))
        q[:, joint] = angles
        bounds = np.empty(count)
        tight, need, which = np.ones(1, dtype=bool), np.full(1, -np.inf), pairs[p:p + 1]
        for n, poses in enumerate(geometry.link_poses(q)):
            bounds[n] = pair_convex_bounds(convexes.arrays, poses, which, need, tight,
                                           *_NO_NOTES)[0]
        step = float(angles[1] - angles[0])
        cells = 0.5 * (bounds[:-1] + bounds[1:] - slope * step)
        out.append(PairTable(p, joint, float(lower), step, slope, cells, periodic))
    return tuple(out)


@dataclass(frozen=True, eq=False)
class ArmCollision:
    """An arm's collision model: geometry, spheres, pairs to skip and where they come from."""

    geometry: ArmGeometry
    spheres: SphereModel
    skip: SkipPairs
    skip_source: str                  # 'SRDF' or what the computed list found
    self_pairs: np.ndarray            # (P, 2) link indices of the pairs checked
    bodies: tuple[Body, ...] = field(repr=False)
    tables: tuple[PairTable, ...] = field(default=(), repr=False)
    #: each link's (cover, shapes) convexes for ``ConvexSet.build``
    convexes: tuple = field(default=(), repr=False)

    @classmethod
    def from_urdf(cls, urdf: str | os.PathLike | bytes, arm: ArmModel, *,
                  meshes: MeshSource | None = None, srdf: str | bytes | None = None,
                  samples: int = SAMPLES) -> ArmCollision:
        """
        Return the collision model of ``arm`` from its URDF (``ArmGeometry.from_urdf``).

        ``srdf``: an SRDF document (text) whose disabled pairs are skipped; without one the
        pairs are computed (``computed_skip_pairs``, ``samples`` configurations).
        """
        geometry = ArmGeometry.from_urdf(urdf, arm, meshes)
        bodies = tuple(Body.of(link.shapes) for link in geometry.links)
        model = cls(geometry, SphereModel.of(geometry), frozenset(), '', np.empty((0, 2), int),
                    bodies)
        if srdf is not None:
            skip, source = read_srdf(srdf), 'SRDF'
        else:
            try:
                robot = read_urdf(urdf)
            except InvalidArmModel as exc:
                raise InvalidCollisionInput(str(exc)) from None
            parents = {j.child: j.parent for j in robot.joints}
            skip, reasons = computed_skip_pairs(geometry, parents.get, model.contacts, samples)
            source = 'computed: ' + ', '.join(f'{v} {k}' for k, v in reasons.items())
        names, links = [link.name for link in geometry.links], geometry.links
        # links on one frame of the chain never move against each other: never checked
        pairs = [(i, j) for i in range(len(names)) for j in range(i + 1, len(names))
                 if tuple(sorted((names[i], names[j]))) not in skip
                 and links[i].joint != links[j].joint]
        pairs = np.array(pairs, dtype=np.int64).reshape(-1, 2)
        convexes = tuple(
            (None if body.hull is None else _hull_convex(body.hull, np.eye(4)),
             [_convex(shape, solid) for shape, solid in zip(link.shapes, body.solids)])
            for link, body in zip(geometry.links, bodies))
        return cls(geometry, model.spheres, skip, source, pairs, bodies,
                   _pair_tables(geometry, ConvexSet.build(list(convexes)), pairs), convexes)

    @property
    def link_names(self) -> tuple[str, ...]:
        """Return the names of the links with geometry, in order."""
        return tuple(link.name for link in self.geometry.links)

    def contacts(self, q: np.ndarray, pairs: np.ndarray) -> np.ndarray:
        """Return which link pairs (P, 2) are in contact at each q (N, n_joints), (N, P)."""
        out = np.zeros((len(q), len(pairs)), dtype=bool)
        bounds = self.spheres.bounds()
        for n, poses in enumerate(self.geometry.link_poses(q)):
            near = np.flatnonzero(pair_lower_bounds(poses, bounds, pairs) <= 0.0)
            for p in near:
                i, j = pairs[p]
                out[n, p] = _contact(self.bodies[i].placed(poses[i]),
                                     self.bodies[j].placed(poses[j]))
        return out


@dataclass(frozen=True, eq=False)
class CollisionWorld:
    """An arm's collision model with a scene and a padding (m): what a motion must keep clear."""

    arm: ArmCollision
    scene: Scene = field(default_factory=Scene)
    padding: float = DEFAULT_PADDING

    def __post_init__(self) -> None:
        if not (np.isfinite(self.padding) and self.padding >= 0.0):
            raise InvalidCollisionInput(f'padding must be finite and at least 0 m, got '
                                        f'{self.padding}')
        links = self.arm.geometry.links
        moving = self.arm.geometry.moving
        world = [(i, len(links) + o) for o, obstacle in enumerate(self.scene.obstacles)
                 for i, link in enumerate(links)
                 if moving[i] and link.name not in obstacle.touch_links]
        put = object.__setattr__
        put(self, 'pairs', np.vstack((self.arm.self_pairs,
                                      np.array(world, dtype=np.int64).reshape(-1, 2))))
        shapes = [o.shape for o in self.scene.obstacles]
        #: The links' spheres and the obstacles' primitives, as ``pair_lower_bounds`` takes them.
        put(self, 'sphere_bounds', self.arm.spheres.bounds(
            np.array([SHAPE_KINDS[s.kind] for s in shapes], dtype=np.int64),
            np.array([s.dimensions + (0.0,) * (3 - len(s.dimensions))
                      for s in shapes]).reshape(-1, 3),
            np.array([np.linalg.inv(s.pose) for s in shapes]).reshape(-1, 4, 4)))
        put(self, '_obstacles', [Body.of((s,)).placed(np.eye(4)) for s in shapes])
        put(self, 'convexes', ConvexSet.build(
            list(self.arm.convexes)
            + [(None, [(SHAPE_KINDS[s.kind], s.dimensions, s.pose)]) for s in shapes]))
        #: (P, n_joints): a turn dq moves pair p's links towards each other by at most
        #: sum_j |dq_j| sweep[p, j] (the continuous check, ``free_motion``)
        put(self, 'sweep', np.array([self._sweep(a, b) for a, b in self.pairs]
                                    ).reshape(len(self.pairs), -1))

    def _sweep(self, a: int, b: int) -> np.ndarray:
        """
        Return how far a unit turn of each joint can move link a towards b.

        b is an obstacle if b >= links. Against the world, reach[j, a]; between two links,
        the joints up to the nearer one's frame move both as one, so only the joints after
        it count, by the farther link's reach.
        """
        geometry = self.arm.geometry
        if b >= len(geometry.links):
            return geometry.reach[:, a]
        near, far = sorted((a, b), key=lambda i: geometry.links[i].joint)
        out = geometry.reach[:, far].copy()
        out[:geometry.links[near].joint + 1] = 0.0
        return out

    def lower_bounds(self, poses: np.ndarray, which: np.ndarray) -> np.ndarray:
        """Return sphere bounds of the distances of pairs ``which`` at link poses (links, 4, 4)."""
        return pair_lower_bounds(poses, self.sphere_bounds, self.pairs[which])

    def exact(self, poses: np.ndarray, which: np.ndarray) -> np.ndarray:
        """Return coal's distances of pairs ``which`` at link poses (links, 4, 4)."""
        return self.bounded(poses, which, np.full(len(which), np.inf))[0]

    def bounded(self, poses: np.ndarray, which: np.ndarray, needed: np.ndarray,
                tight: bool = False, decide: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """
        Return lower bounds of pairs ``which``'s distances, exact where at most ``needed``.

        So a pair's value is at most its ``needed`` exactly when its distance is. Also returns
        which values are the exact distances (the others: hulls' distances, less ``HULL_SLACK``).
        ``tight``: a bound is the least over the shapes' own hulls, not the link's hull.
        ``decide``: a value at most ``needed`` is a distance of two of their parts, not
        necessarily the least.
        """
        needed = np.asarray(needed, dtype=float)
        out = pair_convex_bounds(self.convexes.arrays, poses, self.pairs[which], needed,
                                 np.full(len(which), tight), *_NO_NOTES)
        exact = np.zeros(len(which), dtype=bool)
        placed: dict[int, Placed] = {}
        for n in np.flatnonzero(out <= needed):           # the hulls leave it open: coal
            out[n], exact[n] = _bound(*self._bodies_of(poses, which[n], placed),
                                      float(needed[n]), tight, decide)
        return out, exact

    def decide(self, poses: np.ndarray, pair: int, notes: np.ndarray, needed: float) -> float:
        """
        Return pair ``pair``'s distance if at most ``needed``, else a bound just above it.

        ``notes`` are ``pair_convex_bounds``' notes on the pair (pair, convex sets, bound): the
        piece pairs that may come within ``needed``, and bounds of the rest (sets -1). coal
        measures the pieces' triangles in the order of their bounds until one is within
        ``needed``, or the next bound is above it or the least measured: the least of those is
        the bound returned.
        """
        best, placed = np.inf, {}
        for _, one, other, bound in notes[np.argsort(notes[:, 3], kind='stable')]:
            if bound >= best or bound > needed:
                return float(max(min(best, bound), np.nextafter(needed, np.inf)))
            (g1, t1), (g2, t2) = (self._piece(int(c), poses, placed) for c in (one, other))
            best = min(best, _coal_distance(g1, t1, g2, t2))
            if best <= needed:
                return best
        return float(max(best, np.nextafter(needed, np.inf)))

    def _piece(self, convex: int, poses: np.ndarray, placed: dict[tuple[int, int], Any]
               ) -> tuple[coal.CollisionGeometry, Any]:
        """Return the triangles (or primitive) a convex set of ``convexes`` holds, placed."""
        body, shape, piece = self.convexes.origin[convex]
        links = len(self.arm.geometry.links)
        solid = (self.arm.bodies[body] if body < links
                 else self._obstacles[body - links].body).solids[shape]
        if (body, shape) not in placed:
            pose = (poses[body] if body < links else np.eye(4)) @ solid.pose
            placed[body, shape] = _transform(pose)
        return solid.pieces[max(piece, 0)].geometry, placed[body, shape]

    def within(self, poses: np.ndarray, pair: int, margin: float) -> bool:
        """Return True when pair ``pair`` is closer than ``margin`` (m) at link poses (exact)."""
        if pair_convex_bounds(self.convexes.arrays, poses, self.pairs[pair:pair + 1],
                              np.array([margin]), np.zeros(1, dtype=bool), *_NO_NOTES
                              )[0] >= margin:
            return False                              # the hulls keep it
        if margin < 0.0:                  # coal takes no negative margin: compare the distance
            return bool(self.bounded(poses, np.array([pair]), np.array([margin]))[0][0]
                        < margin)
        return _within(*self._bodies_of(poses, pair, {}), margin)

    def _bodies_of(self, poses: np.ndarray, pair: int, placed: dict[int, Placed]
                   ) -> tuple[Placed, Placed]:
        """Return pair ``pair``'s two placed bodies; links placed once into ``placed``."""
        links = len(self.arm.geometry.links)
        for link in (n for n in self.pairs[pair] if n < links and n not in placed):
            placed[link] = self.arm.bodies[link].placed(poses[link])
        a, b = self.pairs[pair]
        return placed[a], placed[b] if b < links else self._obstacles[b - links]

    def pair_name(self, pair: int) -> str:
        """Return a pair as 'link with link' or "link with 'obstacle'"."""
        names = self.arm.link_names
        a, b = self.pairs[pair]
        other = names[b] if b < len(names) else repr(self.scene.obstacles[b - len(names)].id)
        return f'{names[a]} with {other}'

    def obstacle_at(self, point: np.ndarray) -> str | None:
        """Return the id of an obstacle that holds ``point``, if any."""
        return next((o.id for o in self.scene.obstacles if o.contains(point)), None)
