"""Where a body's centre of mass can lie: the box that holds its links' shapes.

A URDF link may carry shapes (``<collision>``, else ``<visual>``): boxes, cylinders,
spheres and meshes, each at its ``<origin>``. The mass of a rigid body lies inside its
material, so its centre of mass lies inside the convex hull of its shapes, and so inside
the axis-aligned box around them in the body's joint frame. That box, for a chain body
every link with mass of which has shapes that can be read, is a linear bound of the
consistent parameters (m low <= m c <= m high; harness.robot.consistency). Meshes are read
by trimesh (STL, OBJ, PLY and the other formats it reads without extras); a mesh's
``package://NAME/...`` is looked up in the URDF's enclosing folders and in the folders of
ROS_PACKAGE_PATH.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from .urdf import Robot, UrdfError, attribute_floats, origin_frame, parse_urdf

Box = tuple[np.ndarray, np.ndarray]   # (low, high) corners in the body's joint frame


def com_boxes(robot: Robot) -> tuple[dict[int, Box], dict[str, str]]:
    """Per chain body (by joint index) whose every link with mass has readable shapes, the
    box around them; per body without one (by its link's name), why not."""
    links = {link.get("name"): link for link in parse_urdf(robot.source).getroot()
             .iter("link")}
    boxes: dict[int, Box] = {}
    missing: dict[str, str] = {}
    for i, body in enumerate(robot.joints):
        points, reason = [], ""
        for name, (R, p, massive) in body.frames.items():
            try:
                shapes = link_points(links[name], robot.source)
            except UrdfError as error:
                reason = str(error)
                break
            if shapes is None:
                if massive:
                    reason = (f"link {name!r} has mass but no <collision> or <visual> "
                              "shape")
                    break
                continue
            points.append(shapes @ R.T + p)
        if reason or not points:
            missing[body.child_link] = reason or "no link of the body has mass"
            continue
        every = np.concatenate(points)
        boxes[i] = (every.min(axis=0), every.max(axis=0))
    return boxes, missing


def link_points(link, source: Path) -> np.ndarray | None:
    """Points (k, 3) in the link's frame whose box holds its shapes (the collision ones,
    else the visual ones); None for a link without shapes. UrdfError names a shape that
    cannot be read."""
    elements = link.findall("collision") or link.findall("visual")
    if not elements:
        return None
    points = []
    for element in elements:
        where = f"{source}: link {link.get('name')!r} <{element.tag}>"
        geometry = element.find("geometry")
        if geometry is None or len(geometry) == 0:
            raise UrdfError(f"{where}: no <geometry> shape")
        R, p = origin_frame(element, where)
        points.append(_shape_points(geometry[0], source, where) @ R.T + p)
    return np.concatenate(points)


def _shape_points(shape, source: Path, where: str) -> np.ndarray:
    """Points in the shape's frame whose box holds it."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)],
                       dtype=float)
    if shape.tag == "box":
        return corners * attribute_floats(shape, "size", 3, "", where) / 2.0
    if shape.tag == "sphere":
        return corners * attribute_floats(shape, "radius", 1, "", where)[0]
    if shape.tag == "cylinder":  # its axis along z
        radius = attribute_floats(shape, "radius", 1, "", where)[0]
        length = attribute_floats(shape, "length", 1, "", where)[0]
        return corners * np.array([radius, radius, length / 2.0])
    if shape.tag == "mesh":
        scale = attribute_floats(shape, "scale", 3, "1 1 1", where)
        return _mesh_vertices(shape.get("filename", ""), source, where) * scale
    raise UrdfError(f"{where}: unknown shape <{shape.tag}>")


def _mesh_vertices(filename: str, source: Path, where: str) -> np.ndarray:
    import trimesh  # loaded only when a mesh is read

    path = resolve_mesh(filename, source, where)
    try:
        mesh: Any = trimesh.load(str(path), force="mesh")
        vertices = np.array(mesh.vertices, dtype=np.float64)
    except Exception as error:  # trimesh raises many kinds for a file it cannot read
        raise UrdfError(f"{where}: cannot read the mesh {path} ({error})") from None
    if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) == 0 \
            or not np.all(np.isfinite(vertices)):
        raise UrdfError(f"{where}: the mesh {path} has no finite vertices")
    return vertices


def resolve_mesh(filename: str, source: Path, where: str) -> Path:
    """A mesh's file: package://NAME/REST in a folder NAME that encloses the URDF or lies
    in a folder of ROS_PACKAGE_PATH, file://PATH, or a path relative to the URDF's
    folder; UrdfError if it does not exist."""
    if filename.startswith("package://"):
        package, _, rest = filename[len("package://"):].partition("/")
        roots = [folder for folder in Path(source).resolve().parents
                 if folder.name == package]
        for entry in filter(None, os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep)):
            roots += [Path(entry) / package, *([Path(entry)] if Path(entry).name == package
                                               else [])]
        for root in roots:
            if (root / rest).is_file():
                return root / rest
        raise UrdfError(f"{where}: the mesh {filename} is not found (no folder {package!r} "
                        "encloses the URDF or lies in ROS_PACKAGE_PATH)")
    path = Path(filename[len("file://"):] if filename.startswith("file://") else filename)
    path = path if path.is_absolute() else Path(source).parent / path
    if not path.is_file():
        raise UrdfError(f"{where}: the mesh {filename} is not found ({path})")
    return path
