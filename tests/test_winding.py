"""Every triangle winds counter-clockwise seen from the side its vertex normals point to (the
scene contract), on scenes the random input-space scenes (tests/test_input_space.py) found."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cgamesh.errors import CgameshError
from cgamesh.inputs.scene import parse_scene
from cgamesh.pipelines.scene import Resolution, mesh_scene, mesh_surface

from test_scene_batched import batched_count, mesh_alone

AXES = [np.eye(3)[i] * sign for i in range(3) for sign in (1.0, -1.0)]


def against_normals(text: str) -> int:
    """Triangles whose geometric normal points against the sum of their vertex normals."""
    mesh = mesh_surface(parse_scene(text, "scene.yaml").surfaces[0], Resolution())
    corners = mesh.positions[mesh.faces]
    geometric = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return int(np.count_nonzero(np.einsum("ti,ti->t", geometric, mesh.normals[mesh.faces].sum(axis=1)) < 0.0))


def ribbon(controls, curve="kb", closed="false", around=2, along=2) -> str:
    body = "".join(f"      - {{a: {list(map(float, a))}, b: {list(map(float, b))}}}\n" for a, b in controls)
    return ("cgamesh: 1\nsurfaces:\n  - name: s\n    type: point_pairs\n    curve: " + curve + "\n"
            f"    closed: {closed}\n    align: false\n    resolution: {{around: {around}, along: {along}}}\n"
            "    controls:\n" + body)


@pytest.mark.parametrize("step", AXES + [np.array([0.0, 1.3416407864998738, 0.6708203932499369])],
                         ids=lambda s: ",".join(f"{x:g}" for x in s))
@pytest.mark.parametrize("along", [2, 3, 9])
def test_a_ribbon_starting_on_a_repeated_control_winds_with_its_normals(step, along):
    """The field's sign at the first ruling is a limit there (the path stands still): the quad
    between it and a ruling of the other sign was split, one triangle each way."""
    a, b = np.zeros(3), np.array([1.0, 0.0, 0.0]) if abs(step[0]) < 0.5 else np.array([0.0, 1.0, 0.0])
    text = ribbon([(a, b), (a, b), (a + step, b + step)], along=along)
    assert against_normals(text) == 0


def test_a_closed_ribbon_winds_the_quad_before_its_seam_with_its_normals():
    """Found by a random search: the seam took the first ruling's normals, opposite to the last
    ruling's field along part of it, and the quad before it was wound by the vote of the last
    ruling's signs (one triangle against its normals); it is wound by geometry now."""
    text = ('cgamesh: 1\n'
            'surfaces:\n'
            '  - name: s0\n'
            '    type: point_pairs\n'
            '    curve: kb\n'
            '    tension: 1.0\n'
            '    bias: 0.0\n'
            '    continuity: 0.0\n'
            '    closed: true\n'
            '    align: false\n'
            '    resolution: {around: 8, along: 9}\n'
            '    controls:\n'
            '      - {a: [0.25, 1.0, 0.0], b: [-0.25, -1.0, 0.0]}\n'
            '      - {a: [-0.18350341907227385, 0.4082482904638631, 0.4082482904638631], b: [1.8164965809277263, 0.4082482904638631, 0.4082482904638631]}\n'
            '      - {a: [1.4831632475943928, 0.7415816237971964, 0.07491495713052965], b: [1.4831632475943928, 0.7415816237971964, 2.0749149571305296]}\n')
    assert against_normals(text) == 0


def closed_three_ring_tube(name: str = "s", shift: float = 0.0) -> str:
    """A closed tube of 3 rings (2 distinct) whose normals turn by more than a right angle from
    ring to ring: the chord between them does not run along d/dt."""
    return (f"  - name: {name}\n    type: circles\n    curve: kb\n    closed: true\n"
            "    align: false\n    resolution: {around: 16, along: 3}\n    controls:\n"
            f"      - {{center: [0.0, {shift}, 0.0], normal: [1.0, 0.0, 0.0], radius: 1.0}}\n"
            f"      - {{center: [1.3416407864998738, {shift}, 0.6708203932499369], normal: [1.0, 0.0, 0.0], radius: 1.0}}\n"
            f"      - {{center: [2.841640786499874, {shift}, 0.6708203932499369], normal: [1.0, 0.0, 0.0], radius: 1.0}}\n")


def test_a_closed_tube_of_three_rings_winds_with_its_normals():
    """Rings turned apart (circles.TURNED_AGREEMENT) have the strip between them wound by geometry."""
    assert against_normals("cgamesh: 1\nsurfaces:\n" + closed_three_ring_tube()) == 0


def test_a_scene_winds_turned_strips_as_each_surface_alone():
    scene = parse_scene("cgamesh: 1\nsurfaces:\n" + closed_three_ring_tube("a") + closed_three_ring_tube("b", 3.0),
                        "scene.yaml")
    alone, batched = mesh_alone(scene), mesh_scene(scene, Resolution())
    assert batched_count(scene) == 2  # both meshed together
    for (a, _), (b, _) in zip(alone, batched):
        assert np.array_equal(a.faces, b.faces) and np.array_equal(a.positions, b.positions)
        assert np.array_equal(a.normals, b.normals)
        corners = b.positions[b.faces]
        geometric = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        assert np.all(np.einsum("ti,ti->t", geometric, b.normals[b.faces].sum(axis=1)) >= 0.0)


FOLDING_RIBBON = [((0.0, 0.0, 0.0), (0.0, 1.0, 0.0)), ((-1.5, 0.0, 0.0), (-2.5, 0.0, 0.0)),
                  ((-2.560660171779821, 0.0, 1.0606601717798212), (-1.560660171779821, 0.0, 1.0606601717798212))]


def test_a_closed_folding_ribbon_winds_with_its_normals():
    """A fold crossing the quad between two rulings diagonally, where neither ruling may reverse:
    the rulings' normals neither agree nor oppose (ribbons.TURNED_AGREEMENT), so the quad is
    wound by its own geometry."""
    assert against_normals(ribbon(FOLDING_RIBBON, closed="true", around=7, along=40)) == 0


@pytest.mark.parametrize("closed", ["true", "false"])
def test_a_scene_winds_turned_ribbon_quads_as_each_surface_alone(closed):
    """Two copies of the folding ribbon, one shifted: meshed together, each gets the mesh it gets
    alone, every triangle with its normals."""
    first = ribbon(FOLDING_RIBBON, closed=closed, around=7, along=40)
    shifted = [(tuple(np.add(a, (0.0, 5.0, 0.0))), tuple(np.add(b, (0.0, 5.0, 0.0)))) for a, b in FOLDING_RIBBON]
    second = ribbon(shifted, closed=closed, around=7, along=40)
    scene = parse_scene(first + second[second.index("  - name:"):].replace("name: s", "name: t"), "scene.yaml")
    alone, batched = mesh_alone(scene), mesh_scene(scene, Resolution())
    for (a, _), (b, _) in zip(alone, batched):
        assert np.array_equal(a.faces, b.faces) and np.array_equal(a.normals, b.normals)
        corners = b.positions[b.faces]
        geometric = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        assert np.all(np.einsum("ti,ti->t", geometric, b.normals[b.faces].sum(axis=1)) >= 0.0)


POINT = st.tuples(*[st.floats(-2.0, 2.0, allow_nan=False).map(lambda x: round(x, 3))] * 3)


@settings(max_examples=int(os.environ.get("CGAMESH_PROPERTY_EXAMPLES", "40")), deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(controls=st.lists(st.tuples(POINT, POINT), min_size=3, max_size=4), closed=st.sampled_from(["true", "false"]),
       around=st.integers(2, 4), along=st.integers(3, 6))
def test_coarse_ribbons_wind_with_their_normals_together_or_alone(controls, closed, around, along):
    """Few rulings of a random ribbon: consecutive ones are often turned far apart. Every
    triangle winds with its normals, and each surface meshed among others as it is alone."""
    text = ribbon(controls, closed=closed, around=around, along=along)
    try:
        scene = parse_scene(text + text[text.index("  - name:"):].replace("name: s", "name: t"), "scene.yaml")
        alone = mesh_alone(scene)
    except CgameshError:
        return  # a refused scene (a point pair of one point, a vanishing ruling) has no triangles to wind
    batched = mesh_scene(scene, Resolution())
    for (a, _), (b, _) in zip(alone, batched):
        assert np.array_equal(a.faces, b.faces) and np.array_equal(a.normals, b.normals)
        corners = a.positions[a.faces]
        geometric = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        assert np.all(np.einsum("ti,ti->t", geometric, a.normals[a.faces].sum(axis=1)) >= 0.0)
