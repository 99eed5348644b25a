"""The rendering keys of a scene file: camera, lights, objects, background, max_depth, attenuation."""

from __future__ import annotations

import re

import numpy as np
import pytest

from cgamesh.errors import DegenerateGeometryError, InvalidInputError, NonFiniteInputError, SceneFileError
from cgamesh.inputs.scene import parse_scene
from cgamesh.inputs.scene_rendering import Attenuation, PhongMaterial
from cgamesh.tracer.world import build_world

SURFACE = """cgamesh: 1
surfaces:
  - name: tube
    type: circles
    curve: linear
    controls:
      - {center: [0, 0, 0], normal: [0, 0, 1], radius: 1.0}
      - {center: [0, 0, 1], normal: [0, 0, 1], radius: 0.8}
"""

FULL = SURFACE + """camera:
  position: [4, -5, 3]
  look_at: [0, 0, 0.5]
  up: [0, 0, 1]
  focal_length: 1.5
  image_plane: [1.2, 0.9]
lights:
  - {position: [3, -3, 5], color: [1.0, 0.9, 0.8], intensity: 0.2}
  - {position: [-3, 1, 4]}
objects:
  - {type: sphere, center: [2, 0, 0.5], radius: 0.5, material: {color: [1, 0, 0], reflectivity: 0.3}}
  - {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}
  - type: disc
    center: [0, 2, 0.5]
    normal: [0, -1, 0]
    radius: 0.4
    material: {ambient: 0.2, diffuse: 0.5, specular: 0.9, shininess: 64}
background: [0.1, 0.1, 0.2]
max_depth: 3
attenuation: {a: 1, b: 0.1, c: 0}
"""


def test_rendering_keys_parse_into_the_specs():
    scene = parse_scene(FULL, "full.yaml")
    assert scene.camera.position == (4.0, -5.0, 3.0) and scene.camera.image_plane == (1.2, 0.9)
    assert scene.camera.focal_length == 1.5
    assert [light.intensity for light in scene.lights] == [0.2, 1.0]
    assert scene.lights[1].color == (1.0, 1.0, 1.0)
    assert [o.type for o in scene.objects] == ["sphere", "plane", "disc"]
    assert scene.objects[0].material == PhongMaterial(color=(1.0, 0.0, 0.0), reflectivity=0.3)
    assert scene.objects[2].material.shininess == 64.0
    assert scene.background == (0.1, 0.1, 0.2) and scene.max_depth == 3
    assert scene.attenuation == Attenuation(1.0, 0.1, 0.0)


def test_rendering_keys_are_optional_with_the_papers_defaults():
    scene = parse_scene(SURFACE)
    assert scene.camera is None and scene.lights is None and scene.objects == ()
    assert scene.background == (0.0, 0.0, 0.0) and scene.max_depth == 2
    assert scene.attenuation == Attenuation(0.02, 0.0, 0.002)  # paper section 9.2.1
    world = build_world(scene)
    assert len(world.lights) == 1  # a light beside the automatic camera
    # The automatic camera sees the whole scene: its bounding sphere's centre is in front.
    pixel, depth = world.camera.project(world.centre[None], 64, 48)
    np.testing.assert_allclose(pixel, [[32.0, 24.0]], atol=1e-9)
    assert depth[0] > world.radius


def test_an_explicit_empty_light_list_means_no_lights():
    assert build_world(parse_scene(SURFACE + "lights: []\n")).lights == ()


@pytest.mark.parametrize("extra, error, message", [
    ("camera: {position: [0, 0, 0]}", SceneFileError, "camera.look_at must be given (a point [x, y, z])"),
    ("camera: {position: [1, 1, 1], look_at: [1, 1, 1]}", DegenerateGeometryError,
     "camera.look_at must differ from camera.position"),
    ("camera: {position: [0, 0, 5], look_at: [0, 0, 0]}", DegenerateGeometryError,
     "camera.look_at must not be straight above or below camera.position"),
    ("camera: {position: [0, -5, 5], look_at: [0, 0, 0], up: [0, 1, -1]}", DegenerateGeometryError,
     "camera.up must not be parallel to the view direction"),
    ("camera: {position: [0, -5, 0], look_at: [0, 0, 0], focal_length: 0}", SceneFileError,
     "camera.focal_length must be > 0, got 0.0"),
    ("camera: {position: [0, -5, 0], look_at: [0, 0, 0], image_plane: [1]}", SceneFileError,
     "camera.image_plane must be a list of 2 numbers [x_max, y_max], got a list of 1 item"),
    ("camera: {position: [0, -5, 0], look_at: [0, 0, 0], zoom: 2}", SceneFileError, "camera.zoom is not a known key"),
    ("lights: [{position: [0, 0, .nan]}]", NonFiniteInputError, "lights[0].position[2] must be a finite number"),
    ("lights: [{position: [0, 0, 1], intensity: -1}]", SceneFileError, "lights[0].intensity must be >= 0, got -1.0"),
    ("lights: [{position: [0, 0, 1], color: [1, -1, 1]}]", SceneFileError, "lights[0].color[1] must be >= 0"),
    ("objects: [{type: cube}]", SceneFileError, "objects[0].type must be one of sphere, plane, disc, got 'cube'"),
    ("objects: [{type: sphere, center: [0, 0, 0]}]", SceneFileError, "objects[0].radius must be given"),
    ("objects: [{type: sphere, center: [0, 0, 0], radius: 0}]", DegenerateGeometryError,
     "objects[0].radius must be > 0, got 0.0"),
    ("objects: [{type: plane, point: [0, 0, 0], normal: [0, 0, 0]}]", DegenerateGeometryError,
     "objects[0].normal must be non-zero"),
    ("objects: [{type: plane, point: [0, 0, 0], normal: [0, 0, 1], radius: 2}]", SceneFileError,
     "objects[0].radius is not a known key"),
    ("objects: [{type: disc, center: [0, 0, 0], normal: [0, 0, 1], radius: 1, material: {reflectivity: 2}}]",
     SceneFileError, "objects[0].material.reflectivity must be in [0, 1], got 2.0"),
    ("objects: [{type: sphere, center: [0, 0, 0], radius: 1, material: {shininess: 0}}]", SceneFileError,
     "objects[0].material.shininess must be > 0"),
    ("background: [0, 0, 2]", SceneFileError, "background[2] must be in [0, 1], got 2.0"),
    ("max_depth: 17", SceneFileError, "max_depth must be an integer from 0 to 16, got 17 (an integer)"),
    ("attenuation: {a: 0}", SceneFileError, "attenuation.a must be > 0, got 0.0"),
    ("attenuation: {d: 1}", SceneFileError, "attenuation.d is not a known key"),
])
def test_rendering_mistakes_are_one_line_with_file_line_and_key_path(extra, error, message):
    text = SURFACE + extra + "\n"
    line = text.count("\n")  # the extra key sits on the last line
    with pytest.raises(error) as info:
        build_world(parse_scene(text, "scene.yaml"))
    text = str(info.value)
    assert "\n" not in text
    assert message in text
    assert re.match(rf"scene\.yaml:{line}: ", text), text
    assert isinstance(info.value, InvalidInputError)
