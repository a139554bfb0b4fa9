# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
Solid shapes in a frame: the URDF's ``<collision>`` elements and the scene's obstacles.

A ``Shape`` is a box, sphere, cylinder (with the fields of shape_msgs/SolidPrimitive) or a
triangle mesh, placed by a 4x4 pose in its link's (or the base's) frame. Each gives its coal
geometry for the exact distances (``coal_geometry``) and a triangle mesh that holds it
(``enclosing_mesh``: a cylinder's polygon is circumscribed, a sphere's too) for the
conservative sphere model.

Meshes are untrusted (a robot_description comes from the network): ``MeshSource`` reads them
only from ``package://`` URIs, through the given package lookup (ament_index in the node and
the command), or beside the URDF file given to the library or the command, never from
``file://`` elsewhere or a URL, and refuses files over ``MAX_MESH_BYTES`` or meshes over
``MAX_MESH_VERTICES``. trimesh reads them.

A ``package://NAME/...`` whose NAME is no known package (pybullet's ``package://meshes/...``,
many vendors' files) is looked up beside the URDF file, as pybullet and yourdfpy do: first
``<folder>/NAME/...``, then ``<folder>/...``; either must stay inside that folder (after
symbolic links), like every other file read beside it.
"""
from __future__ import annotations

from dataclasses import dataclass
import functools
import os
from pathlib import Path
from typing import Callable

import numpy as np
from trajplan_ros.collision.errors import InvalidCollisionInput
from trajplan_ros.kinematics.lazy_modules import lazy

coal = lazy('coal')
trimesh = lazy('trimesh')

__all__ = ['MAX_MESH_BYTES', 'MAX_MESH_VERTICES', 'MeshSource', 'Shape', 'SHAPE_DIMENSIONS']

#: Largest mesh file read, bytes.
MAX_MESH_BYTES = 20 * 1024 * 1024
#: Most vertices of a mesh.
MAX_MESH_VERTICES = 1_000_000
#: The dimensions of each primitive, as shape_msgs/SolidPrimitive orders them.
SHAPE_DIMENSIONS = {'box': ('x', 'y', 'z'), 'sphere': ('radius',),
                    'cylinder': ('height', 'radius')}
#: Sides of the polygon that encloses a cylinder or a sphere's circles.
_SIDES = 24


@dataclass(frozen=True, eq=False)
class Shape:
    """
    One solid: ``kind`` box, sphere, cylinder or mesh, placed by ``pose`` (4x4) in its frame.

    ``dimensions``: box (x, y, z), sphere (radius,), cylinder (height, radius), in metres; a
    mesh has ``vertices`` (V, 3) and ``faces`` (F, 3) instead, already scaled.
    """

    kind: str
    pose: np.ndarray
    dimensions: tuple[float, ...] = ()
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None

    def coal_geometry(self) -> coal.CollisionGeometry:
        """Return the shape as coal geometry, in its own frame (``pose`` places it)."""
        if self.kind == 'box':
            return coal.Box(*self.dimensions)
        if self.kind == 'sphere':
            return coal.Sphere(self.dimensions[0])
        if self.kind == 'cylinder':
            return coal.Cylinder(self.dimensions[1], self.dimensions[0])
        model = coal.BVHModelOBBRSS()
        model.beginModel(len(self.faces), len(self.vertices))
        model.addVertices(np.ascontiguousarray(self.vertices, dtype=float))
        model.addTriangles(np.ascontiguousarray(self.faces, dtype=np.int32))
        model.endModel()
        return model

    def enclosing_mesh(self) -> trimesh.Trimesh:
        """Return a triangle mesh, in the frame, whose convex pieces hold the whole shape."""
        if self.kind == 'box':
            mesh = trimesh.creation.box(extents=self.dimensions)
        elif self.kind == 'sphere':
            mesh = trimesh.creation.icosphere(subdivisions=1, radius=1.0)
            # an icosphere's faces cut inside the sphere: push them out to its inradius
            inner = np.min(np.linalg.norm(mesh.triangles_center, axis=1))
            mesh.vertices *= self.dimensions[0] / inner
        elif self.kind == 'cylinder':
            height, radius = self.dimensions
            mesh = trimesh.creation.cylinder(radius=radius / np.cos(np.pi / _SIDES),
                                             height=height, sections=_SIDES)
        else:
            mesh = trimesh.Trimesh(self.vertices, self.faces, process=False)
        return mesh.apply_transform(self.pose)

    @classmethod
    def primitive(cls, kind: str, dimensions: tuple[float, ...], pose: np.ndarray,
                  where: str) -> Shape:
        """Return a checked box, sphere or cylinder; ``where`` names it in a refusal."""
        if kind not in SHAPE_DIMENSIONS:
            raise InvalidCollisionInput(f'{where}: unknown type {kind!r}; use box, sphere or '
                                        'cylinder')
        names = SHAPE_DIMENSIONS[kind]
        dims = tuple(float(v) for v in dimensions)
        if len(dims) != len(names):
            raise InvalidCollisionInput(f'{where}: a {kind} has {len(names)} dimensions '
                                        f'[{", ".join(names)}], got {len(dims)}')
        if not all(np.isfinite(v) and v > 0 for v in dims):
            raise InvalidCollisionInput(f'{where}: dimensions must be finite and positive, got '
                                        f'{list(dims)}')
        return cls(kind, pose, dims)


@dataclass(frozen=True)
class MeshSource:
    """
    Where meshes may be read from.

    ``package://`` URIs through ``package_share`` (package name -> share folder, e.g.
    ament_index's get_package_share_directory), and files beside ``folder``.
    """

    package_share: Callable[[str], str | os.PathLike] | None = None
    folder: Path | None = None

    def path(self, uri: str) -> Path:
        """Return the file of a mesh URI, or refuse it with the reason."""
        return self.locate(uri)[0]

    def locate(self, uri: str) -> tuple[Path, str]:
        """
        Return the file of a mesh URI and the unknown package read beside the URDF ('' if none).

        Refuses (``InvalidCollisionInput``) with the reason.
        """
        if uri.startswith('package://'):
            package, _, rest = uri[len('package://'):].partition('/')
            unknown = ('no package lookup to resolve package:// (is AMENT_PREFIX_PATH set?)'
                       if self.package_share is None
                       else f'package {package!r} is not in the ament index')
            if self.package_share is not None:
                try:
                    root = Path(self.package_share(package)).resolve()
                except Exception:                # ament_index raises its own lookup errors
                    root = None
                if root is not None:
                    return _inside(uri, root, rest), ''
            if self.folder is None:
                raise InvalidCollisionInput(f'mesh {uri!r}: {unknown}')
            return self._beside(uri, package, rest, unknown), package
        elif '://' in uri and not uri.startswith('file://'):
            raise InvalidCollisionInput(f'mesh {uri!r}: only package:// URIs and files beside '
                                        'the URDF are read')
        else:
            if self.folder is None:
                raise InvalidCollisionInput(f'mesh {uri!r}: a URDF given as text reads meshes '
                                            'from package:// URIs only')
            root, rest = self.folder.resolve(), uri.removeprefix('file://')
        return _inside(uri, root, rest), ''

    def _beside(self, uri: str, package: str, rest: str, unknown: str) -> Path:
        """Return ``<folder>/package/rest`` or else ``<folder>/rest``: the first that exists."""
        root = self.folder.resolve()
        tried = [_inside(uri, root, f'{package}/{rest}'), _inside(uri, root, rest)]
        found = next((path for path in tried if path.is_file()), None)
        if found is None:
            raise InvalidCollisionInput(f'mesh {uri!r}: {unknown}, and neither '
                                        f'{" nor ".join(str(p) for p in tried)} exists beside '
                                        'the URDF')
        return found

    def load(self, uri: str, scale: np.ndarray, beside: set[str] | None = None
             ) -> tuple[np.ndarray, np.ndarray]:
        """
        Return the vertices (scaled) and faces of the mesh at ``uri``, checked as above.

        ``beside``: collects the unknown packages whose meshes were read beside the URDF.
        """
        path, package = self.locate(uri)
        if package and beside is not None:
            beside.add(package)
        try:
            size = path.stat().st_size
        except OSError as exc:
            raise InvalidCollisionInput(f'mesh {uri!r}: {exc.strerror}') from None
        if size > MAX_MESH_BYTES:
            raise InvalidCollisionInput(f'mesh {uri!r} is {size} bytes, over the '
                                        f'{MAX_MESH_BYTES} byte limit')
        vertices, faces = _read_mesh(str(path))
        if len(vertices) > MAX_MESH_VERTICES:
            raise InvalidCollisionInput(f'mesh {uri!r} has {len(vertices)} vertices, over the '
                                        f'limit of {MAX_MESH_VERTICES}')
        if not len(faces) or not np.all(np.isfinite(vertices)):
            raise InvalidCollisionInput(f'mesh {uri!r} has no triangles or non-finite vertices')
        return vertices * scale, faces


def _inside(uri: str, root: Path, rest: str) -> Path:
    """Return ``root / rest`` with its links resolved, refused if that leaves ``root``."""
    path = (root / rest).resolve()
    if not path.is_relative_to(root):
        raise InvalidCollisionInput(f'mesh {uri!r} lies outside {root}')
    return path


@functools.lru_cache(maxsize=64)
def _read_mesh(path: str) -> tuple[np.ndarray, np.ndarray]:
    """Return a mesh file's vertices and faces (read once per path)."""
    try:
        mesh = trimesh.load(path, force='mesh', process=False)
    except Exception as exc:                       # trimesh raises many kinds on bad files
        raise InvalidCollisionInput(f'mesh {path}: not readable: {exc}') from None
    if not isinstance(mesh, trimesh.Trimesh):
        raise InvalidCollisionInput(f'mesh {path}: no triangles')
    # an STL file repeats each vertex for every triangle at it: one copy of each is enough
    # (the same triangles), and holds the hulls and hierarchies built on it to a third
    mesh.merge_vertices(merge_tex=True, merge_norm=True)
    return np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int64)
