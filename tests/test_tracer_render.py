"""Whole renders: the traced examples against stored reference images, determinism, the command."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from cgamesh.inputs.scene import load_scene
from cgamesh.tracer.evolved import RootFinder
from cgamesh.tracer.png import read_png
from cgamesh.tracer.render import render
from cgamesh.tracer.world import build_world
from cgamesh_cli.main import main

ROOT = Path(__file__).resolve().parent.parent
TRACED = sorted((ROOT / "examples").glob("traced_*.yaml"))
_spec = importlib.util.spec_from_file_location("make_tracer_references", ROOT / "tests/data/make_tracer_references.py")
references = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(references)


def test_there_is_a_traced_example_of_every_traced_paper_figure():
    names = {path.stem for path in TRACED}
    assert names >= {"traced_fig03_primitives", "traced_fig01_lights", "traced_fig11_point_pairs",
                     "traced_fig16_surface", "traced_fig17_scene"}


@pytest.mark.parametrize("example", TRACED, ids=lambda p: p.stem)
def test_traced_example_matches_its_reference_image(example):
    """Same picture within a tolerance: a few pixels may differ where a ray grazes an edge and
    another platform's rounding decides differently."""
    image = render(build_world(load_scene(example)), *references.SIZE)
    stored = read_png(references.reference_path(example)).astype(np.float64) / 255.0
    assert image.shape == stored.shape
    difference = np.abs(image - stored).max(axis=2)
    assert difference.mean() < 2.0 / 255.0
    assert np.mean(difference > 16.0 / 255.0) < 0.01
    assert image.std() > 0.05  # not a blank picture


def test_rendering_is_deterministic():
    world = build_world(load_scene(ROOT / "examples/traced_fig17_scene.yaml"))
    first, second = render(world, 40, 30), render(world, 40, 30)
    assert np.abs(first - second).max() <= 0.0


def test_the_sampled_finder_renders_nearly_the_same_picture():
    world = build_world(load_scene(ROOT / "examples/traced_fig16_surface.yaml"))
    exact = render(world, 48, 36)
    sampled = render(build_world(load_scene(ROOT / "examples/traced_fig16_surface.yaml"), RootFinder("sampled", 256)),
                     48, 36)
    assert np.mean(np.abs(exact - sampled).max(axis=2) > 8.0 / 255.0) < 0.02


def test_render_command_writes_the_png(tmp_path, capsys):
    out = tmp_path / "fig16.png"
    assert main(["render", str(ROOT / "examples/traced_fig16_surface.yaml"), "-o", str(out), "--size", "32x24",
                 "--root-finder", "sampled", "--samples", "16"]) == 0
    assert read_png(out).shape == (24, 32, 3)
    assert "32x24" in capsys.readouterr().out


def test_render_command_refuses_bad_arguments(tmp_path, capsys):
    scene = str(ROOT / "examples/traced_fig16_surface.yaml")
    assert main(["render", scene, "-o", str(tmp_path / "x.jpg")]) == 2
    assert "expected .png" in capsys.readouterr().err
    for bad in (["--size", "64by48"], ["--samples", "1"]):  # one line naming the flag, exit 2
        assert main(["render", scene, "-o", str(tmp_path / "x.png"), *bad]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith(f"cgamesh: error: argument {bad[0]}: ")
    assert not (tmp_path / "x.png").exists()
