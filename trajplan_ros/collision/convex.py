# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Certified lower bounds of the distance between convex sets, compiled: the hulls' level.

A link's shapes and each of its meshes are held by convex sets: boxes, spheres and cylinders as
themselves, a mesh by the hull of its vertices (``distances.convex_hull``). For convex sets A
and B and any unit direction u, every point x of A - B has |x| >= u.x, so their distance is at
least -(h_A(-u) + h_B(u)), h being the support function (the largest u.p over the set). That
bound holds for every u, whatever the iteration that proposes it: the kernels run GJK (the
Gilbert-Johnson-Keerthi iteration on A - B) to find good directions and keep the best bound
seen, so an inexact simplex step can only cost tightness, never safety. A hull's support is
the largest u.v over its vertices, found by climbing its vertex graph (a convex polytope has no
other local maximum) or, where that graph was not checked, over all vertices.

``ConvexSet`` gathers them as the arrays the kernels take (``arrays``): bodies are the links
(by index) and the obstacles (after them); each has a cover (the convex set that holds the whole
body) and its shapes' convex sets.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from trajplan_ros.kinematics.jit import inlined_kernel, kernel

__all__ = ['BOX', 'CYLINDER', 'ConvexArrays', 'ConvexSet', 'POINTS', 'SPHERE', 'body_bound',
           'GAP', 'pair_convex_bounds']

#: Kinds of convex sets (the first three as ``spheres`` numbers the obstacles' kinds).
BOX, SPHERE, CYLINDER, POINTS = 0, 1, 2, 3
#: GJK stops once its best bound is within this of the distance of its simplex point (m).
GAP = 1e-5
#: Taken off every bound (m): far more than the rounding of the supports and of qhull's hulls.
SLACK = 1e-5
#: Most GJK iterations (it ends in far fewer on polytopes).
ITERATIONS = 48
#: A hull of fewer vertices is searched vertex by vertex rather than climbed.
CLIMB_FROM = 48


class ConvexArrays(NamedTuple):
    """Convex sets of bodies as the kernels take them (C sets, N hull vertices)."""

    kinds: np.ndarray           # (C,) BOX, SPHERE, CYLINDER or POINTS
    dims: np.ndarray            # (C, 3) a primitive's dimensions, as shape_msgs orders them
    poses: np.ndarray           # (C, 4, 4) each set's pose in its body's frame
    first: np.ndarray           # (C + 1,) the range of each POINTS set in ``points``
    points: np.ndarray          # (N, 3) the hulls' vertices
    adjacent_first: np.ndarray  # (N + 1,) the range of each vertex's neighbours in ``adjacent``
    adjacent: np.ndarray        # the hulls' vertex graphs (global vertex indices)
    climb: np.ndarray           # (C,) whether a hull's graph is climbed
    cover: np.ndarray           # (bodies,) the set that holds each whole body
    shape_first: np.ndarray     # (bodies + 1,) the range of each body's shapes' sets in shapes
    shapes: np.ndarray          # the shapes' sets
    piece_first: np.ndarray     # (C + 1,) the range of each set's pieces in ``pieces``
    pieces: np.ndarray          # the pieces' sets (a mesh's hull: hulls of parts of it)
    centres: np.ndarray         # (C, 3) the centre of a ball that holds each set (body frame)
    radii: np.ndarray           # (C,) that ball's radius


@dataclass(frozen=True, eq=False)
class ConvexSet:
    """
    Convex sets of bodies: the kernels' arrays and what each set holds.

    ``origin`` (C, 3): (body, shape, piece) of each set, -1 for a body's cover and for a
    shape's whole hull.
    """

    arrays: ConvexArrays
    origin: np.ndarray

    @classmethod
    def build(cls, bodies: list[tuple[tuple | None, list[tuple]]]) -> ConvexSet:
        """
        Return the set of bodies given as (cover, shapes), each convex a tuple.

        A convex is (kind, dims, pose) for a primitive, or (POINTS, points, neighbours, pieces)
        for a hull: its vertices (in the body's frame), each vertex's neighbours on the hull
        (None: no graph, every vertex is tried) and its pieces, convexes (POINTS, points,
        neighbours) that hold parts of it (or ()). A cover None: the body's one shape covers it.
        """
        out = _Lists()
        for body, (body_cover, body_shapes) in enumerate(bodies):
            placed = [out.add(s, (body, n, -1)) for n, s in enumerate(body_shapes)]
            cover = placed[0] if body_cover is None else out.add(body_cover, (body, -1, -1))
            out.cover.append(cover)
            out.shapes.extend(placed)
            out.shape_first.append(len(out.shapes))
        count = len(out.kinds)
        owned = {index: [out.add(piece, (*out.origin[index][:2], n))
                         for n, piece in enumerate(pieces)] for index, pieces in out.later}
        for c in range(count):
            out.pieces.extend(owned.get(c, ()))
            out.piece_first.append(len(out.pieces))
        out.piece_first.extend([out.piece_first[-1]] * (len(out.kinds) - count))
        ints = {name: np.array(getattr(out, name), dtype=np.int64) for name in (
            'kinds', 'first', 'adjacent_first', 'adjacent', 'cover', 'shape_first', 'shapes',
            'piece_first', 'pieces')}
        return cls(ConvexArrays(
            dims=np.array(out.dims).reshape(-1, 3), poses=np.array(out.poses).reshape(-1, 4, 4),
            points=np.vstack(out.points) if out.points else np.zeros((0, 3)),
            climb=np.array(out.climb, dtype=np.bool_),
            centres=np.array(out.centres).reshape(-1, 3),
            radii=np.array(out.radii, dtype=float), **ints),
            origin=np.array(out.origin, dtype=np.int64).reshape(-1, 3))


class _Lists:
    """The growing lists of ``ConvexSet.build``, one per array, and the hulls' pieces to add."""

    def __init__(self) -> None:
        for name in ('kinds', 'dims', 'poses', 'points', 'adjacent', 'climb', 'cover', 'shapes',
                     'pieces', 'centres', 'radii', 'origin'):
            setattr(self, name, [])
        self.first, self.adjacent_first, self.shape_first, self.piece_first = [0], [0], [0], [0]
        self.later: list[tuple[int, list]] = []     # (index, pieces) of the hulls with pieces

    def add(self, convex: tuple, origin: tuple[int, int, int] = (-1, -1, -1)) -> int:
        """Append one convex (see ``ConvexSet.build``); return its index."""
        kind, index = convex[0], len(self.kinds)
        self.kinds.append(kind)
        self.origin.append(origin)
        if kind == POINTS:
            self._add_points(index, convex)
            return index
        dims = np.pad(np.asarray(convex[1], dtype=float), (0, 3 - len(convex[1])))
        pose = np.asarray(convex[2], dtype=float)
        self.first.append(self.first[-1])
        self.climb.append(False)
        self.dims.append(dims)
        self.poses.append(pose)
        self.centres.append(pose[:3, 3])
        self.radii.append(float({BOX: 0.5 * np.linalg.norm(dims), SPHERE: dims[0],
                                 CYLINDER: np.hypot(0.5 * dims[0], dims[1])}[kind]))
        return index

    def _add_points(self, index: int, convex: tuple) -> None:
        """Append a hull: its vertices, their graph, a ball that holds them, its pieces."""
        vertices, neighbours = np.asarray(convex[1], dtype=float), convex[2]
        base = self.first[-1]
        self.points.append(vertices)
        self.first.append(base + len(vertices))
        for n in range(len(vertices)):
            near = [] if neighbours is None else neighbours[n]
            self.adjacent.extend(base + int(i) for i in near)
            self.adjacent_first.append(len(self.adjacent))
        self.climb.append(neighbours is not None and _climbs(vertices, neighbours))
        self.dims.append(np.zeros(3))
        self.poses.append(np.eye(4))
        middle = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
        self.centres.append(middle)
        self.radii.append(float(np.max(np.linalg.norm(vertices - middle, axis=1))))
        if len(convex) > 3 and len(convex[3]):
            self.later.append((index, list(convex[3])))


def _climbs(vertices: np.ndarray, neighbours: list) -> bool:
    """
    Return True when climbing the graph is worth it and finds the support in test directions.

    Climbing a hull's vertex graph finds the largest u.v (a polytope's graph has no other
    local maximum); the test directions check that the graph given is a hull's.
    """
    if len(vertices) < CLIMB_FROM:
        return False
    directions = np.random.default_rng(0).normal(size=(8, 3))
    for u in directions:
        values = vertices @ u
        at = 0
        while True:
            step = max(neighbours[at], key=lambda i: values[i], default=at)
            if values[step] <= values[at]:
                break
            at = step
        if values[at] < np.max(values):
            return False
    return True


@inlined_kernel
def _support(convexes: ConvexArrays, c: int, pose: np.ndarray, d: np.ndarray, start: int,
             out: np.ndarray) -> int:
    """
    Write the support point of convex ``c`` placed by ``pose`` in world direction d into out.

    Returns the vertex found (POINTS: where the next climb starts; ``start`` this one's).
    """
    kinds, dims, first, points = convexes.kinds, convexes.dims, convexes.first, convexes.points
    adjacent_first, adjacent, climb = convexes.adjacent_first, convexes.adjacent, convexes.climb
    local = np.empty(3)
    for r in range(3):
        local[r] = pose[0, r] * d[0] + pose[1, r] * d[1] + pose[2, r] * d[2]
    kind, found = kinds[c], start
    p = np.zeros(3)
    if kind == BOX:
        for r in range(3):
            p[r] = 0.5 * dims[c, r] if local[r] >= 0.0 else -0.5 * dims[c, r]
    elif kind == SPHERE:
        norm = np.sqrt(local[0] ** 2 + local[1] ** 2 + local[2] ** 2)
        if norm > 0.0:
            for r in range(3):
                p[r] = dims[c, 0] * local[r] / norm
        else:
            p[0] = dims[c, 0]
    elif kind == CYLINDER:                                   # height, radius; axis z
        radial = np.sqrt(local[0] ** 2 + local[1] ** 2)
        if radial > 0.0:
            p[0] = dims[c, 1] * local[0] / radial
            p[1] = dims[c, 1] * local[1] / radial
        else:
            p[0] = dims[c, 1]
        p[2] = 0.5 * dims[c, 0] if local[2] >= 0.0 else -0.5 * dims[c, 0]
    else:
        if found < first[c] or found >= first[c + 1]:
            found = first[c]
        best = _dot(local, points[found])
        if climb[c]:
            while True:
                step = found
                for e in range(adjacent_first[found], adjacent_first[found + 1]):
                    i = adjacent[e]
                    value = _dot(local, points[i])
                    if value > best:
                        best, step = value, i
                if step == found:
                    break
                found = step
        else:
            for i in range(first[c], first[c + 1]):
                value = _dot(local, points[i])
                if value > best:
                    best, found = value, i
        for r in range(3):
            p[r] = points[found, r]
    _transform(pose, p, out)
    return found


@inlined_kernel
def _transform(pose: np.ndarray, p: np.ndarray, out: np.ndarray) -> None:
    """Write the point p placed by ``pose`` (4, 4) into out."""
    for r in range(3):
        out[r] = pose[r, 0] * p[0] + pose[r, 1] * p[1] + pose[r, 2] * p[2] + pose[r, 3]


@inlined_kernel
def _dot(a: np.ndarray, b: np.ndarray) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@inlined_kernel
def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.array((a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]))


@inlined_kernel
def _on_triangle(a: np.ndarray, b: np.ndarray, c: np.ndarray, v: np.ndarray) -> int:
    """
    Write the point of triangle abc nearest the origin into v; return the feature it lies on.

    The feature is a bit mask of the corners kept (1: a, 2: b, 4: c), as in Ericson's
    closest point on a triangle (Real-Time Collision Detection, 5.1.5).
    """
    ab, ac = b - a, c - a
    d1, d2 = -_dot(ab, a), -_dot(ac, a)
    if d1 <= 0.0 and d2 <= 0.0:
        v[:] = a
        return 1
    d3, d4 = -_dot(ab, b), -_dot(ac, b)
    if d3 >= 0.0 and d4 <= d3:
        v[:] = b
        return 2
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v[:] = a + ab * (d1 / (d1 - d3))
        return 3
    d5, d6 = -_dot(ab, c), -_dot(ac, c)
    if d6 >= 0.0 and d5 <= d6:
        v[:] = c
        return 4
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        v[:] = a + ac * (d2 / (d2 - d6))
        return 5
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
        v[:] = b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))
        return 6
    total = va + vb + vc
    if total == 0.0:                                     # a flat triangle: its first corner
        v[:] = a
        return 1
    v[:] = a + ab * (vb / total) + ac * (vc / total)
    return 7


@inlined_kernel
def _nearest(simplex: np.ndarray, n: int, v: np.ndarray) -> int:
    """
    Write the point of the simplex (its first n rows) nearest the origin into v.

    Keeps only the corners of the feature it lies on (rows moved to the front) and returns
    their count (0: the origin is inside a tetrahedron).
    """
    mask = 1
    if n == 1:
        v[:] = simplex[0]
    elif n == 2:
        a, b = simplex[0], simplex[1]
        ab = b - a
        length = _dot(ab, ab)
        t = -_dot(a, ab) / length if length > 0.0 else 1.0
        if t <= 0.0:
            v[:] = a
            mask = 1
        elif t >= 1.0:
            v[:] = b
            mask = 2
        else:
            v[:] = a + ab * t
            mask = 3
    elif n == 3:
        mask = _on_triangle(simplex[0], simplex[1], simplex[2], v)
    else:
        best, mask, w = np.inf, 0, np.empty(3)
        faces = ((0, 1, 2, 3), (0, 1, 3, 2), (0, 2, 3, 1), (1, 2, 3, 0))
        for f in faces:
            a, b, c, d = simplex[f[0]], simplex[f[1]], simplex[f[2]], simplex[f[3]]
            normal = _cross(b - a, c - a)
            side_origin, side_d = -_dot(normal, a), _dot(normal, d - a)
            if side_origin * side_d < 0.0 or side_d == 0.0:        # the origin is beyond it
                kept = _on_triangle(a, b, c, w)
                distance = _dot(w, w)
                if distance < best:
                    best = distance
                    v[:] = w
                    mask = (((kept & 1) << f[0]) | (((kept >> 1) & 1) << f[1])
                            | (((kept >> 2) & 1) << f[2]))
        if mask == 0:
            v[:] = 0.0
            return 0
    count = 0
    for i in range(n):
        if mask & (1 << i):
            simplex[count] = simplex[i]
            count += 1
    return count


@inlined_kernel
def _placed(convexes: ConvexArrays, c: int, body_pose: np.ndarray, out: np.ndarray) -> None:
    """Write convex c's pose in the world (its body placed by ``body_pose``) into out."""
    pose = convexes.poses[c]
    for r in range(3):
        for k in range(4):
            out[r, k] = (body_pose[r, 0] * pose[0, k] + body_pose[r, 1] * pose[1, k]
                         + body_pose[r, 2] * pose[2, k])
        out[r, 3] += body_pose[r, 3]
    out[3, :3] = 0.0
    out[3, 3] = 1.0


@kernel
def convex_bound(convexes: ConvexArrays, one: int, one_pose: np.ndarray, other: int,
                 other_pose: np.ndarray) -> float:
    """
    Return a lower bound of the distance of convex sets ``one`` and ``other`` (placed).

    It is the best separating bound of GJK's directions, less ``SLACK``.
    """
    v = one_pose[:3, 3] - other_pose[:3, 3]
    if _dot(v, v) == 0.0:
        v[0] = 1.0
    simplex = np.empty((4, 3))
    a, b, minus = np.empty(3), np.empty(3), np.empty(3)
    at_one, at_other, n = -1, -1, 0
    lower = -np.inf
    for iteration in range(ITERATIONS):
        length = np.sqrt(_dot(v, v))
        minus[:] = -v
        at_one = _support(convexes, one, one_pose, minus, at_one, a)
        at_other = _support(convexes, other, other_pose, v, at_other, b)
        w = a - b
        bound = _dot(v, w) / length                   # the least of v/|v| . x over one - other
        lower = max(lower, bound)
        if iteration > 0 and length - lower <= GAP:  # v is a point of one - other: |v| >= d
            break
        simplex[n] = w
        n = _nearest(simplex, n + 1, v)
        if n == 0 or _dot(v, v) == 0.0:               # the sets meet
            break
    return lower - SLACK


@inlined_kernel
def _note(found: np.ndarray, count: np.ndarray, pair: int, one: int, other: int,
          bound: float) -> None:
    """Add a row (pair, convex one, convex other, bound) to ``found`` (count[0] rows so far)."""
    if count[0] < len(found):
        found[count[0], 0], found[count[0], 1] = pair, one
        found[count[0], 2], found[count[0], 3] = other, bound
    count[0] += 1


@kernel
def _shape_bound(convexes: ConvexArrays, i: int, a_pose: np.ndarray, j: int, b_pose: np.ndarray,
                 bound: float, need: float, pair: int, found: np.ndarray,
                 count: np.ndarray) -> float:
    """
    Return the least bound over the pieces of convexes i and j (``bound``: the sets' own).

    A set without pieces is its own one piece. Piece pairs are taken in the order of their
    balls' bound while that is below the least found (branch and bound) or within ``need``;
    the result is the larger of that least and ``bound``. Every piece pair whose hulls come
    within ``need`` is noted in ``found`` (``_note``) with their bound, and the least bound of
    all the others as a pair of no pieces (-1, -1).
    """
    piece_first, pieces = convexes.piece_first, convexes.pieces
    centres, radii = convexes.centres, convexes.radii
    one = np.arange(piece_first[i], piece_first[i + 1])
    other = np.arange(piece_first[j], piece_first[j + 1])
    if len(one) == 0 and len(other) == 0:
        _note(found, count, pair, i, j, bound)
        return bound
    mine = pieces[one] if len(one) else np.array([i])
    theirs = pieces[other] if len(other) else np.array([j])
    balls = np.empty(len(mine) * len(theirs))
    at_a, at_b = np.empty((len(mine), 3)), np.empty((len(theirs), 3))
    for m in range(len(mine)):
        _transform(a_pose, centres[mine[m]], at_a[m])
    for t in range(len(theirs)):
        _transform(b_pose, centres[theirs[t]], at_b[t])
    for m in range(len(mine)):
        for t in range(len(theirs)):
            gap = at_a[m] - at_b[t]
            balls[m * len(theirs) + t] = (np.sqrt(_dot(gap, gap)) - radii[mine[m]]
                                          - radii[theirs[t]])
    least = rest = np.inf
    one_pose, other_pose = np.empty((4, 4)), np.empty((4, 4))
    for n in np.argsort(balls):
        m, t = n // len(theirs), n % len(theirs)
        if balls[n] >= least and balls[n] > need:
            rest = min(rest, balls[n])
            break
        _placed(convexes, mine[m], a_pose, one_pose)
        _placed(convexes, theirs[t], b_pose, other_pose)
        value = convex_bound(convexes, mine[m], one_pose, theirs[t], other_pose)
        least = min(least, value)
        if value <= need:
            _note(found, count, pair, mine[m], theirs[t], value)
        else:
            rest = min(rest, value)
    if rest < np.inf:
        _note(found, count, pair, -1, -1, max(bound, rest))
    return max(bound, least)


@kernel
def body_bound(convexes: ConvexArrays, a: int, a_pose: np.ndarray, b: int, b_pose: np.ndarray,
               need: float, tight: bool, pair: int, found: np.ndarray,
               count: np.ndarray) -> float:
    """
    Return a lower bound of bodies a and b's distance (placed by their poses), from convexes.

    Their covers first; where that bound is at most ``need`` (or ``tight``), the least over
    their shapes' pairs, each from their hulls and, where those are at most ``need``, their
    pieces (``_shape_bound``, which notes the piece pairs that may be within ``need`` as pair
    ``pair`` in ``found``; a shape pair left at its hulls is noted as (-1, -1) with their
    bound). Each level's bound is the larger of its own and the level above's.
    """
    cover, shape_first, shapes = convexes.cover, convexes.shape_first, convexes.shapes
    one, other = np.empty((4, 4)), np.empty((4, 4))
    _placed(convexes, cover[a], a_pose, one)
    _placed(convexes, cover[b], b_pose, other)
    bound = convex_bound(convexes, cover[a], one, cover[b], other)
    if bound > need and not tight:
        return bound
    single = (shape_first[a + 1] - shape_first[a] == 1 and shape_first[b + 1] - shape_first[b] == 1
              and shapes[shape_first[a]] == cover[a] and shapes[shape_first[b]] == cover[b])
    least = np.inf
    for i in range(shape_first[a], shape_first[a + 1]):
        _placed(convexes, shapes[i], a_pose, one)
        for j in range(shape_first[b], shape_first[b + 1]):
            _placed(convexes, shapes[j], b_pose, other)
            value = bound if single else convex_bound(convexes, shapes[i], one, shapes[j],
                                                      other)
            if value <= need:
                value = _shape_bound(convexes, shapes[i], a_pose, shapes[j], b_pose, value,
                                     need, pair, found, count)
            else:
                _note(found, count, pair, -1, -1, max(bound, value))
            least = min(least, value)
    return max(bound, least)


@kernel
def pair_convex_bounds(convexes: ConvexArrays, poses: np.ndarray, pairs: np.ndarray,
                       need: np.ndarray, tight: np.ndarray, found: np.ndarray,
                       count: np.ndarray) -> np.ndarray:
    """
    Return ``body_bound`` of each pair (P, 2) of bodies at link poses (links, 4, 4).

    A body b >= links is obstacle b - links, placed where its convex sets say; ``need`` and
    ``tight`` are each pair's. The piece pairs that may be within ``need`` are noted in
    ``found`` (rows: the pair's position in ``pairs``, the pieces' convex sets, their bound),
    as many as it holds; ``count`` counts them all.
    """
    links = len(poses)
    identity = np.eye(4)
    out = np.empty(len(pairs))
    for p in range(len(pairs)):
        a, b = pairs[p, 0], pairs[p, 1]
        out[p] = body_bound(convexes, a, poses[a] if a < links else identity, b,
                            poses[b] if b < links else identity, need[p], tight[p], p, found,
                            count)
    return out
