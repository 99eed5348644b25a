"""Property tests over the input space a scene file reaches.

Orientations drawn from the exact +-axes as often as from the sphere, every curve kind and
object kind, both interpolations of circles (blade and motor), caps / closed / align in every
allowed combination, resolutions at their bounds,
sizes and distances over many decades, a control repeated exactly or 1e-9 of the size apart.
Each scene either meshes (finite positions, unit normals
orthogonal to their circle or ruling, the first ring on the first control and the last on the
last) or is refused with one line naming the scene's file, line and surface; numpy warnings are
errors. A second property writes every output format.
"""

from __future__ import annotations

import os
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from direction_strategies import coordinate, direction, sphere_direction

from cgamesh.errors import InvalidInputError
from cgamesh.export.options import WriteOptions
from cgamesh.inputs.scene import parse_scene
from cgamesh.pipelines.scene import Resolution, mesh_scene

CURVES = ("linear", "bezier", "rational_bezier", "kb", "catmull_rom")
# A modest count keeps the suite fast; CGAMESH_PROPERTY_EXAMPLES asks for a longer search.
EXAMPLES = int(os.environ.get("CGAMESH_PROPERTY_EXAMPLES", "40"))
PROPERTY = settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])



@st.composite
def scenes(draw):
    """(scene text, the controls as (kind, values) in file units, flags of the surface)."""
    kind = draw(st.sampled_from(("circles", "point_pairs")))
    curve = draw(st.sampled_from(CURVES))
    closed = curve in ("kb", "catmull_rom") and draw(st.booleans())
    count = draw(st.integers(3 if closed else 2, 5))
    align = draw(st.booleans())
    caps = kind == "circles" and not closed and draw(st.booleans())
    interpolation = draw(st.sampled_from(("blade", "motor"))) if kind == "circles" else "blade"
    scale = 10.0 ** draw(st.integers(-3, 3))
    offset = np.array(draw(st.tuples(coordinate, coordinate, coordinate))) * 10.0 ** draw(st.integers(0, 4))
    step = np.array(draw(direction))
    point = offset.copy()
    controls = []
    for i in range(count):
        weight = f", weight: {10.0 ** draw(st.floats(-2.0, 2.0))!r}" if curve == "rational_bezier" else ""
        if kind == "circles":
            normal = draw(direction)
            radius = scale * draw(st.floats(0.3, 1.0))
            controls.append(("circle", point.copy(), np.array(normal), radius))
            line = f"{{center: {point.tolist()}, normal: {list(normal)}, radius: {radius!r}{weight}}}"
        else:
            across = np.array(draw(direction)) * scale
            controls.append(("pair", point.copy(), point + across))
            line = f"{{a: {point.tolist()}, b: {(point + across).tolist()}{weight}}}"
        controls[-1] = controls[-1] + (line,)
        step = step + 0.5 * np.array(draw(sphere_direction))
        point = point + 1.5 * scale * step / max(np.linalg.norm(step), 1e-3)
    repeat = draw(st.sampled_from((None, None, 0.0, 1e-9)))
    if repeat is not None:  # the first control again, identical or 1e-9 of the size apart
        shift = np.array([repeat * scale, 0.0, 0.0])
        first = controls[0]
        if kind == "circles":
            line = first[-1].replace(f"center: {first[1].tolist()}", f"center: {(first[1] + shift).tolist()}")
            copy = ("circle", first[1] + shift, first[2], first[3], line)
        else:
            line = (first[-1].replace(f"a: {first[1].tolist()}", f"a: {(first[1] + shift).tolist()}")
                    .replace(f"b: {first[2].tolist()}", f"b: {(first[2] + shift).tolist()}"))
            copy = ("pair", first[1] + shift, first[2] + shift, line)
        controls.insert(1, copy)
    least_around = 3 if kind == "circles" else 2
    around = draw(st.sampled_from((least_around, least_around + 1, 7, 16)))
    along = draw(st.sampled_from((2, 3, 17, 40)))
    body = "".join(f"      - {c[-1]}\n" for c in controls)
    text = (f"cgamesh: 1\nsurfaces:\n  - name: s\n    type: {kind}\n    curve: {curve}\n"
            f"    interpolation: {interpolation}\n"
            f"    closed: {str(closed).lower()}\n    align: {str(align).lower()}\n    caps: {str(caps).lower()}\n"
            f"    resolution: {{around: {around}, along: {along}}}\n    controls:\n{body}")
    return text, kind, controls, around, caps, closed


def mesh_or_refuse(text):
    """The meshes, or None after checking the refusal is one line naming the file and surface."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            return mesh_scene(parse_scene(text, "space.yaml"), Resolution())
        except InvalidInputError as error:
            message = str(error)
            assert "\n" not in message and message.startswith("space.yaml:3: surfaces[0]"), message
            return None


def assert_on_circle(points, centre, normal, radius):
    n = normal / np.linalg.norm(normal)
    offset = points - centre
    height = offset @ n
    in_plane = np.linalg.norm(offset - height[:, None] * n, axis=1)
    size = radius + np.linalg.norm(centre)
    assert np.abs(height).max() <= 1e-9 * size
    assert np.abs(in_plane - radius).max() <= 1e-9 * size


def assert_on_segment(points, a, b):
    d = b - a
    s = (points - a) @ d / (d @ d)
    assert s.min() >= -1e-9 and s.max() <= 1 + 1e-9
    size = np.linalg.norm(d) + np.linalg.norm(a)
    assert np.linalg.norm(points - a - s[:, None] * d, axis=1).max() <= 1e-9 * size


def _pairs_example(controls, curve="linear", align="false", around=2, along=2):
    """A drawn point-pair scene (as ``scenes`` gives it) from (a, b) end points."""
    lines = [f"{{a: {list(map(float, a))}, b: {list(map(float, b))}}}" for a, b in controls]
    body = "".join(f"      - {line}\n" for line in lines)
    text = (f"cgamesh: 1\nsurfaces:\n  - name: s\n    type: point_pairs\n    curve: {curve}\n"
            f"    closed: false\n    align: {align}\n    caps: false\n"
            f"    resolution: {{around: {around}, along: {along}}}\n    controls:\n{body}")
    drawn = [("pair", np.array(a, dtype=float), np.array(b, dtype=float), line) for (a, b), line in zip(controls, lines)]
    return text, "point_pairs", drawn, around, False, False


@PROPERTY
@given(scenes())
# Found by a random search: the scan for lines projected where no projection exists (a warning).
@example(_pairs_example([((0, 0, 0), (0, 0, 1)), ((1e-9, 0, 0), (1e-9, 0, 1)), ((0, 0, 1.5), (0, 0, 2.5))]))
@example(_pairs_example([((0, 0, 0), (1, 0, 1)), ((1e-9, 0, 0), (1.000000001, 0, 1)),
                         ((1.0606601717798214, 0, 1.0606601717798214), (2.0606601717798214, 0, 2.0606601717798214))]))
def test_every_scene_meshes_onto_its_controls_or_is_refused_in_one_line(drawn):
    text, kind, controls, around, caps, closed = drawn
    meshes = mesh_or_refuse(text)
    if meshes is None:
        return
    mesh = meshes[0][0]
    assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.uvs))
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-9)
    columns = around + 1 if kind == "circles" else around
    first = mesh.positions[:columns]
    if kind == "circles":
        assert_on_circle(first, *controls[0][1:4])
        if not closed:
            rings = (len(mesh.positions) - (2 * around + 2 if caps else 0)) // columns
            assert_on_circle(mesh.positions[(rings - 1) * columns: rings * columns], *controls[-1][1:4])
            grid_normals = mesh.normals[: rings * columns].reshape(rings, columns, 3)[:, :-1]
            ring = mesh.positions[: rings * columns].reshape(rings, columns, 3)[:, :-1]
            # The circle's tangent at vertex j is parallel to the chord from j - 1 to j + 1.
            chord = np.roll(ring, -1, axis=1) - np.roll(ring, 1, axis=1)
            cosine = np.einsum("kji,kji->kj", chord, grid_normals) / np.linalg.norm(chord, axis=2)
            assert np.abs(cosine).max() <= 1e-6
    else:
        assert_on_segment(first, controls[0][1], controls[0][2])


FAR_AXIS_RATIONAL = ("cgamesh: 1\nsurfaces:\n  - name: s\n    type: circles\n    curve: rational_bezier\n"
                     "    closed: false\n    align: true\n    caps: false\n    resolution: {around: 16, along: 17}\n"
                     "    controls:\n"
                     "      - {center: [732.9759048910715, 869.3111423225721, 645.3281676861824], normal: [-1.0, 0.0, 0.0], "
                     "radius: 0.003, weight: 9.710008716837494}\n"
                     "      - {center: [732.9759048910715, 869.3111423225721, 645.3281676861824], normal: [-1.0, 0.0, 0.0], "
                     "radius: 0.003, weight: 9.710008716837494}\n"
                     "      - {center: [732.9609048910716, 869.3111423225721, 645.3281676861824], normal: [0.0, -1.0, 0.0], "
                     "radius: 0.007118020536816981, weight: 0.020347433849963317}\n")


def test_a_far_rational_tube_from_an_exact_axis_with_a_repeated_control():
    """Found by a random search of the property above (rational Bezier only): rounding noise in
    the sampled velocities, aliased by the fit of N, put its normals 4e-5 out of the circle's
    normal plane until zeta's samples were held to degree 2 (``normals._ZETA_DEGREE_2``)."""
    controls = [("circle", np.array([732.9759048910715, 869.3111423225721, 645.3281676861824]), np.array([-1.0, 0.0, 0.0]),
                 0.003, ""),
                ("circle", np.array([732.9759048910715, 869.3111423225721, 645.3281676861824]), np.array([-1.0, 0.0, 0.0]),
                 0.003, ""),
                ("circle", np.array([732.9609048910716, 869.3111423225721, 645.3281676861824]), np.array([0.0, -1.0, 0.0]),
                 0.007118020536816981, "")]
    test_every_scene_meshes_onto_its_controls_or_is_refused_in_one_line.hypothesis.inner_test(
        (FAR_AXIS_RATIONAL, "circles", controls, 16, False, False))


@settings(max_examples=max(6, EXAMPLES // 6), deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                HealthCheck.function_scoped_fixture])
@given(drawn=scenes(), suffix=st.sampled_from([".glb", ".gltf", ".usda", ".usdc", ".usdz", ".obj", ".ply", ".stl"]))
def test_every_output_format_writes_what_meshes(tmp_path, drawn, suffix):
    from cgamesh.export.registry import write
    from cgamesh.readers.readback import read_gltf

    if suffix.startswith(".usd"):
        pytest.importorskip("pxr")
    meshes = mesh_or_refuse(drawn[0])
    if meshes is None:
        return
    out = tmp_path / f"space{suffix}"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        write(out, meshes, WriteOptions("z", 1.0, "m"))
    assert out.stat().st_size > 0
    if suffix == ".glb":
        back = read_gltf(out, world=True)[0]
        x, y, z = back.positions.astype(np.float64).T
        size = np.abs(meshes[0][0].positions).max() + 1.0
        np.testing.assert_allclose(np.stack([x, -z, y], axis=1), meshes[0][0].positions, atol=1e-6 * size)
