# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The conservative model: spheres that hold each link's geometry, for pruning only.

As cuRobo and VAMP do, each link is covered by a few spheres; here they are fitted so that the
whole geometry lies inside them, not only its vertices: the link's triangles (of the meshes
that hold its shapes, ``Shape.enclosing_mesh``) are split into ``SPHERES_PER_LINK`` groups
along the link's longest axis, and each group's sphere holds all of its triangles' vertices,
hence (a ball being convex) the triangles. A distance computed on the spheres is therefore a
lower bound of the true one: a pair whose spheres keep the clearance keeps it; a pair whose
spheres come near is left to the exact distances (``distances``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from trajplan_ros.collision.arm_geometry import ArmGeometry, LinkGeometry
from trajplan_ros.kinematics.jit import inlined_kernel, kernel

__all__ = ['SPHERES_PER_LINK', 'SphereBounds', 'SphereModel', 'fit_spheres', 'pair_lower_bounds']

#: How many spheres cover a link.
SPHERES_PER_LINK = 8
#: Obstacle kinds as the kernel takes them (the order of shape_msgs/SolidPrimitive's names).
BOX, SPHERE, CYLINDER = 0, 1, 2


def fit_spheres(link: LinkGeometry, count: int = SPHERES_PER_LINK
                ) -> tuple[np.ndarray, np.ndarray]:
    """Return centres (S, 3) in the link's frame and radii (S,) of spheres holding the link."""
    triangles = np.concatenate([m.triangles for m in (s.enclosing_mesh() for s in link.shapes)])
    centroids = triangles.mean(axis=1)
    middle = centroids.mean(axis=0)
    axis = np.linalg.svd(centroids - middle, full_matrices=False)[2][0] \
        if len(centroids) > 1 else np.array([1.0, 0.0, 0.0])
    order = np.argsort((centroids - middle) @ axis, kind='stable')
    centres, radii = [], []
    for group in np.array_split(order, min(count, len(order))):
        points = triangles[group].reshape(-1, 3)
        centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
        centres.append(centre)
        radii.append(float(np.max(np.linalg.norm(points - centre, axis=1))))
    return np.array(centres), np.array(radii)


@dataclass(frozen=True, eq=False)
class SphereModel:
    """Every link's spheres: ``centres`` (S, 3) in their link's frame, ``radii``, ``first``."""

    centres: np.ndarray
    radii: np.ndarray
    first: np.ndarray            # (links + 1,) link l's spheres are first[l]:first[l + 1]

    @classmethod
    def of(cls, geometry: ArmGeometry) -> SphereModel:
        """Return the spheres of every link of ``geometry``."""
        fitted = [fit_spheres(link) for link in geometry.links]
        first = np.cumsum([0] + [len(r) for _, r in fitted])
        return cls(np.vstack([c for c, _ in fitted]), np.concatenate([r for _, r in fitted]),
                   first.astype(np.int64))

    def bounds(self, kinds: np.ndarray | None = None, dims: np.ndarray | None = None,
               inverse: np.ndarray | None = None) -> SphereBounds:
        """Return the spheres with the obstacles' primitives (none: no obstacles) as bounded."""
        if kinds is None:
            kinds, dims, inverse = np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 4, 4))
        return SphereBounds(self.centres, self.radii, self.first, kinds, dims, inverse)


class SphereBounds(NamedTuple):
    """What ``pair_lower_bounds`` takes besides the poses and pairs."""

    centres: np.ndarray          # (S, 3) the links' spheres' centres, in their link's frame
    radii: np.ndarray            # (S,)
    first: np.ndarray            # (links + 1,) link l's spheres are first[l]:first[l + 1]
    kinds: np.ndarray            # (O,) each obstacle's primitive (convex.BOX, SPHERE, CYLINDER)
    dims: np.ndarray             # (O, 3) its dimensions, as shape_msgs orders them
    inverse: np.ndarray          # (O, 4, 4) the inverse of its pose


@inlined_kernel
def _to_primitive(kind: int, dims: np.ndarray, point: np.ndarray) -> float:
    """Return the distance from a point (in the primitive's frame) to a box, sphere, cylinder."""
    if kind == SPHERE:
        return np.sqrt(point[0] ** 2 + point[1] ** 2 + point[2] ** 2) - dims[0]
    if kind == BOX:
        outside, inside = 0.0, -np.inf
        for a in range(3):
            gap = abs(point[a]) - 0.5 * dims[a]
            outside += max(gap, 0.0) ** 2
            inside = max(inside, gap)
        return np.sqrt(outside) if outside > 0.0 else inside
    radial = np.sqrt(point[0] ** 2 + point[1] ** 2) - dims[1]      # cylinder: height, radius
    axial = abs(point[2]) - 0.5 * dims[0]
    if radial > 0.0 and axial > 0.0:
        return np.sqrt(radial ** 2 + axial ** 2)
    return max(radial, axial)


@kernel
def pair_lower_bounds(poses: np.ndarray, spheres: SphereBounds, pairs: np.ndarray
                      ) -> np.ndarray:
    """
    Return a lower bound of each pair's distance (m; below 0 when the spheres overlap).

    ``poses`` (links, 4, 4) place the links. Pair (a, b): links a and b when b < links, else
    link a and obstacle b - links (``SphereBounds``). Link to link: min |c_i - c_j| - r_i - r_j
    over their spheres; link to obstacle: min d(c_i, obstacle) - r_i.
    """
    centres, radii, first = spheres.centres, spheres.radii, spheres.first
    kinds, dims, inverse = spheres.kinds, spheres.dims, spheres.inverse
    links = len(first) - 1
    world = np.empty_like(centres)
    for link in range(links):
        for i in range(first[link], first[link + 1]):
            for r in range(3):
                world[i, r] = (poses[link, r, 0] * centres[i, 0] + poses[link, r, 1]
                               * centres[i, 1] + poses[link, r, 2] * centres[i, 2]
                               + poses[link, r, 3])
    out = np.empty(len(pairs))
    local = np.empty(3)
    for p in range(len(pairs)):
        a, b = pairs[p, 0], pairs[p, 1]
        best = np.inf
        for i in range(first[a], first[a + 1]):
            if b < links:
                for j in range(first[b], first[b + 1]):
                    gap = np.sqrt((world[i, 0] - world[j, 0]) ** 2
                                  + (world[i, 1] - world[j, 1]) ** 2
                                  + (world[i, 2] - world[j, 2]) ** 2) - radii[i] - radii[j]
                    best = min(best, gap)
            else:
                o = b - links
                for r in range(3):
                    local[r] = (inverse[o, r, 0] * world[i, 0] + inverse[o, r, 1] * world[i, 1]
                                + inverse[o, r, 2] * world[i, 2] + inverse[o, r, 3])
                best = min(best, _to_primitive(kinds[o], dims[o], local) - radii[i])
        out[p] = best
    return out
