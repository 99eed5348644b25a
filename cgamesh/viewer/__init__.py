"""A self-contained HTML viewer page for a scene: ``write_page(path, scene, meshes)``.

The page works offline: three.js (with OrbitControls) and ganja.js are embedded from the
minified builds vendored in ``assets/`` (built from pinned npm packages by
tools/viewer/build.mjs; each carries its licence banner, and the licence files are embedded
too), the page's own script from ``viewer.js``, and the meshes as base64 arrays.

three.js shows the meshes as exported to glTF (+Y up, metres; the scene format's axis map),
lit, with orbit controls, a UV-checker texture toggle and a vertex-normal toggle. ganja.js
draws, in CGA G(4,1), the scene's control circles / point pairs and a few interpolated ones
(computed here, read out of the projected objects C(t)) in an inset panel.
"""

from __future__ import annotations

import base64
import html
import json
import os
import re
from importlib import resources
from pathlib import Path

import numpy as np

from cgamesh.export.atomic import atomic_write
from cgamesh.material import Material
from cgamesh.meshing.mesh import SurfaceMesh

# glTF's frame from the scene's: out = AXIS[up] @ x
AXIS = {"z": np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]), "y": np.eye(3)}
INTERPOLATED_PER_SURFACE = 7
MAX_NORMAL_LINES = 20000


def _asset(name: str) -> str:
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")


def _b64(array: np.ndarray, dtype) -> str:
    return base64.b64encode(np.ascontiguousarray(array, dtype=np.dtype(dtype).newbyteorder("<")).tobytes()).decode()


def page_data(scene, meshes: list[tuple[SurfaceMesh, Material]]) -> dict:
    """The JSON the page's script reads: meshes in glTF's frame, CGA objects in the same frame."""
    axis = AXIS[scene.up] * scene.meters_per_unit
    surfaces = []
    for mesh, material in meshes:
        surfaces.append({
            "name": mesh.name,
            "color": [float(c) for c in material.color],
            "roughness": float(material.roughness),
            "metallic": float(material.metallic),
            "double_sided": bool(mesh.double_sided),
            "vertices": mesh.vertex_count,
            "positions": _b64(mesh.positions @ axis.T, np.float32),
            "normals": _b64(mesh.normals @ AXIS[scene.up].T, np.float32),
            "uvs": _b64(np.c_[mesh.uvs[:, 0], 1.0 - mesh.uvs[:, 1]], np.float32),
            "indices": _b64(mesh.faces, np.uint32),
            # linear RGB per vertex, shown through the material (three.js vertexColors)
            "colors": None if mesh.colors is None else _b64(np.clip(mesh.colors, 0.0, 1.0), np.float32),
        })
    controls, interpolated = _cga_objects(scene)
    return {
        "scene": os.path.basename(scene.path),
        "units": scene.units,
        "surfaces": surfaces,
        "cga": {
            "controls": [(np.asarray(points) @ axis.T).tolist() for points in controls],
            "interpolated": [(np.asarray(points) @ axis.T).tolist() for points in interpolated],
        },
        "max_normal_lines": MAX_NORMAL_LINES,
    }


def _cga_objects(scene) -> tuple[list, list]:
    """Control objects and a few interpolated ones, each as the points that fix it (file frame):
    three points on a circle (counter-clockwise about its normal), the two ends of a point pair."""
    from cgamesh.pipelines.scene import build_surface
    from cgamesh.geometry.surface import CircleRings

    controls, interpolated = [], []
    for spec in scene.surfaces:
        for control in spec.controls:
            if spec.type == "point_pairs":
                controls.append([control.a, control.b])
            elif control.through is not None:
                controls.append([list(p) for p in control.through])
            else:
                controls.append(_circle_points(np.array(control.center), np.array(control.normal), control.radius))
        surface = build_surface(spec)
        t = np.linspace(0.0, surface.segment_count, INTERPOLATED_PER_SURFACE + 2)[1:-1]
        projection = surface.sample(t)
        if spec.type == "point_pairs":
            from cgamesh.meshing.ribbons import PairRings

            rings = PairRings.from_projection(projection, surface.frame)
            interpolated += [[a.tolist(), b.tolist()] for a, b in zip(rings.a, rings.b)]
        else:
            rings = CircleRings.from_projection(projection, surface.frame)
            interpolated += [_circle_points(c, n, r) for c, n, r in zip(rings.centre, rings.normal, rings.radius)]
    return controls, interpolated


def _circle_points(centre: np.ndarray, normal: np.ndarray, radius: float) -> list:
    normal = normal / np.linalg.norm(normal)
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(normal, helper)
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    return [(centre + radius * d).tolist() for d in (u, v, -u)]


def render_page(scene, meshes: list[tuple[SurfaceMesh, Material]]) -> str:
    """The whole page as text."""
    data = json.dumps(page_data(scene, meshes), separators=(",", ":"), allow_nan=False)
    manifest = json.loads(_asset("assets/MANIFEST.json"))
    versions = manifest["packages"]
    licences = "\n\n".join(f"{name} {versions[name]['version']}:\n\n{_asset(f'assets/{file}')}"
                           for name, file in (("three", "three.LICENSE"), ("ganja.js", "ganja.js.LICENSE")))
    page = _asset("template.html")
    replacements = {
        "{{TITLE}}": html.escape(f"{os.path.basename(scene.path)} - cgamesh viewer"),
        "{{LICENCES}}": html.escape(licences),
        "{{THREE}}": _script_text(_asset("assets/three.min.js")),
        "{{GANJA}}": _script_text(_asset("assets/ganja.min.js")),
        "{{VIEWER}}": _script_text(_asset("viewer.js")),
        "{{DATA}}": data.replace("</", "<\\/"),
    }
    # One pass, so a placeholder-like text inside an embedded script is never replaced.
    return re.sub(r"\{\{[A-Z]+\}\}", lambda m: replacements.get(m.group(), m.group()), page)


def _script_text(text: str) -> str:
    """A script body that cannot end its <script> element early."""
    return text.replace("</script", "<\\/script")


def write_page(path: str | os.PathLike[str], scene, meshes: list[tuple[SurfaceMesh, Material]]) -> int:
    """Write the page atomically; returns its size in bytes."""
    data = render_page(scene, meshes).encode("utf-8")
    with atomic_write(Path(path)) as f:
        f.write(data)
    return len(data)
