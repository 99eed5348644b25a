"""The resource budget: oversized requests are refused in one line naming the knob, streamed work
stays within it, and the estimates are at least what the work really allocates."""

from __future__ import annotations

import tracemalloc
from fractions import Fraction
from math import comb
from pathlib import Path

import numpy as np
import pytest

from cgamesh import budget
from cgamesh.budget import Budget, ResourceLimitError, format_size, parse_size
from cgamesh.export.options import WriteOptions
from cgamesh.export.registry import write
from cgamesh.geometry.curves.bezier import bernstein
from cgamesh.inputs.scene import load_scene, parse_scene
from cgamesh.pipelines.scene import Resolution, mesh_scene, plan_surface
from cgamesh_cli.main import main

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
KB = EXAMPLES / "kb_tube.yaml"


def run(capsys, *argv) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def assert_refused(code: int, err: str, *fragments: str) -> None:
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("cgamesh: error: "), err
    assert "Traceback" not in err and "Warning" not in err
    for fragment in fragments:
        assert fragment in err, err


# --- sizes -----------------------------------------------------------------------------------------

@pytest.mark.parametrize("text, size", [("2G", 2 * 2**30), ("512MiB", 512 * 2**20), ("500MB", 500 * 10**6),
                                        ("1e9", 10**9), ("1.5gib", int(1.5 * 2**30)), ("4096", 4096)])
def test_sizes_parse(text, size):
    assert parse_size(text) == size


@pytest.mark.parametrize("text", ["", "G", "2X", "-1G", "0", "nan", "1e999"])
def test_bad_sizes_are_refused(text):
    with pytest.raises(ValueError):
        parse_size(text)


def test_sizes_format():
    assert format_size(224 * 2**30) == "224 GiB"
    assert format_size(9.6 * 2**30) == "9.6 GiB"
    assert format_size(10**300 * 10**100) .endswith("TiB")  # a squared 10**30 still prints


def test_the_default_limit_is_a_fraction_of_the_available_memory():
    available = budget.available_memory()
    assert available is None or available > 0
    expected = budget.DEFAULT_FRACTION * (available if available else budget.FALLBACK_AVAILABLE)
    assert budget.default_limit() == pytest.approx(expected, rel=0.2)  # memory moves while we look


# --- the cases of the issue ------------------------------------------------------------------------

def _big_resolution_scene(tmp_path) -> Path:
    text = KB.read_text()
    path = tmp_path / "kb_tube.yaml"
    lines = [line for line in text.splitlines() if "resolution" not in line and "tolerance" not in line]
    lines.append("    resolution: {around: 100000, along: 100000}")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_huge_resolution_in_the_file_is_refused_naming_the_knob(tmp_path, capsys):
    scene = _big_resolution_scene(tmp_path)
    code, _, err = run(capsys, scene, "-o", tmp_path / "out.glb", "--max-memory", "8G")
    assert_refused(code, err, "kb_tube.yaml:", "surfaces[0].resolution asks for", "(100000 x 100000)",
                   "the limit is 8 GiB (--max-memory)")
    assert not (tmp_path / "out.glb").exists()


@pytest.mark.parametrize("flag, value", [("--along", "1000000000"), ("--around", str(10**30))])
def test_huge_counts_on_the_command_line_are_refused(tmp_path, capsys, flag, value):
    code, _, err = run(capsys, KB, "-o", tmp_path / "out.glb", flag, value)
    assert_refused(code, err, f"{flag} {value}", "(--max-memory)")


def test_a_tolerance_below_the_floor_is_refused(tmp_path, capsys):
    code, _, err = run(capsys, KB, "-o", tmp_path / "out.glb", "--tolerance", "1e-20")
    assert_refused(code, err, "--tolerance 1e-20", "1e-07 of its bounding radius")


def test_a_fine_tolerance_beyond_the_budget_is_refused(tmp_path, capsys):
    # priced from the tolerance's own plan: about 824 x 2,585 vertices, 1.4 GiB
    code, _, err = run(capsys, KB, "-o", tmp_path / "out.glb", "--tolerance", "1e-5", "--max-memory", "500M")
    assert_refused(code, err, "--tolerance 1e-05 asks for", "of meshing to tolerance", "(--max-memory)")


def test_a_refused_tolerance_names_about_one_that_fits(tmp_path, capsys):
    """Vertices grow about as 1 / tolerance: the refusal scales the tolerance to the limit (with a
    margin), and a run at the tolerance it names fits."""
    code, _, err = run(capsys, KB, "-o", tmp_path / "out.glb", "--tolerance", "1e-5", "--max-memory", "100M")
    assert code == 2 and "(--max-memory); a tolerance of about " in err and err.rstrip().endswith("would fit")
    fitting = err.rstrip().rsplit("a tolerance of about ", 1)[1].split()[0]
    assert 1e-5 < float(fitting) < 1e-3
    code, out, err = run(capsys, KB, "-o", tmp_path / "out.glb", "--tolerance", fitting, "--max-memory", "100M")
    assert code == 0, err


SMALL_RIBBON = """cgamesh: 1
surfaces:
  - name: twist
    type: point_pairs
    curve: bezier
    controls:
      - {a: [-0.3, 0, 0], b: [0.3, 0, 0]}
      - {a: [0, -0.3, 0.3], b: [0, 0.3, 0.3]}
      - {a: [0.3, 0, 0.6], b: [-0.3, 0, 0.6]}
"""


def test_a_ribbon_at_1e_7_is_refused_before_it_grows(tmp_path, capsys):
    scene = tmp_path / "ribbon.yaml"
    scene.write_text(SMALL_RIBBON)
    code, _, err = run(capsys, scene, "-o", tmp_path / "out.glb", "--tolerance", "1e-7", "--max-memory", "4G")
    assert_refused(code, err, "ribbon.yaml:", "--tolerance 1e-07 asks for", "(--max-memory)")


def test_the_python_api_applies_the_same_budget():
    scene = load_scene(KB)
    with pytest.raises(ResourceLimitError, match=r"asks for .* the limit is 1 GiB \(--max-memory\)"):
        mesh_scene(scene, Resolution(100000, 100000), max_memory="1G")
    meshes = mesh_scene(scene, Resolution(8, 12), max_memory=Budget(64 * 2**20))
    spec = scene.surfaces[0]
    assert 9 * 12 <= meshes[0][0].vertex_count <= budget.grid_vertices("circles", 8, 12, spec.caps)


def _bezier_scene(count: int) -> str:
    k = np.arange(count)
    controls = "\n".join(f"      - {{center: [{np.cos(i / 50):.4f}, {np.sin(i / 50):.4f}, {i * 0.01:.3f}], "
                         f"normal: [0, 0, 1], radius: 0.2}}" for i in k)
    return f"cgamesh: 1\nsurfaces:\n  - name: many\n    type: circles\n    curve: bezier\n    controls:\n{controls}\n"


def test_bernstein_weights_of_any_order_are_exact():
    alpha = np.array([0.0, 0.013, 0.5, 0.77, 1.0])
    for order in (3, 61, 1099):
        b = bernstein(order, alpha)
        assert np.all(np.isfinite(b)) and np.allclose(b.sum(axis=1), 1.0, rtol=0, atol=1e-12)
        for a_index in (1, 3):
            a = Fraction(float(alpha[a_index]))
            for i in (0, order // 3, order // 2, order):
                exact = comb(order, i) * a**i * (1 - a) ** (order - i)
                assert b[a_index, i] == pytest.approx(float(exact), rel=1e-9, abs=1e-300)
        assert b[0, 0] == 1.0 and b[-1, -1] == 1.0


def test_1100_bezier_controls_mesh_on_their_circles():
    scene = parse_scene(_bezier_scene(1100), "many.yaml")
    (mesh, _), = mesh_scene(scene, Resolution(8, 16))
    assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.normals))
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1.0)
    # Every ring's vertices lie on one circle: equal distances from their mean, in one plane.
    rings = mesh.positions[: 16 * 9].reshape(16, 9, 3)[:, :-1]
    centre = rings.mean(axis=1, keepdims=True)
    distance = np.linalg.norm(rings - centre, axis=2)
    assert np.allclose(distance, distance[:, :1], rtol=1e-9)


def test_verify_of_a_50_control_bezier_is_refused_clearly(tmp_path, capsys):
    scene = tmp_path / "many.yaml"
    scene.write_text(_bezier_scene(50))
    code, _, err = run(capsys, scene, "-o", tmp_path / "many.glb", "--around", "8", "--along", "16", "-q")
    assert code == 0, err
    code, _, err = run(capsys, "verify", scene, tmp_path / "many.glb", "-q")
    assert_refused(code, err, "degree 588", "use --root-finder sampled")


def test_a_huge_sample_count_is_refused(tmp_path, capsys):
    code, _, err = run(capsys, "render", EXAMPLES / "traced_fig16_surface.yaml", "-o", tmp_path / "x.png",
                       "--size", "8x8", "--root-finder", "sampled", "--samples", str(10**7), "--max-memory", "4G")
    assert_refused(code, err, "--samples 10000000", "of sampled objects", "(--max-memory)")
    assert not (tmp_path / "x.png").exists()


def test_an_image_too_big_to_hold_is_refused_and_streams_instead():
    from cgamesh.tracer.png import read_png
    from cgamesh.tracer.render import plan, render, render_png
    from cgamesh.tracer.world import build_world

    world = build_world(load_scene(EXAMPLES / "traced_fig16_surface.yaml"))
    with pytest.raises(ResourceLimitError, match=r"an image of 16384x16384 asks for 12 GiB .*\(--max-memory\)"):
        render(world, 16384, 16384, max_memory="1G")
    # Streaming: the bands of a 16384 x 16384 render fit a small budget.
    bands, at_once = plan(world, 16384, 16384, max_memory="40M")
    assert sum(b.stop - b.start for b in bands) == 16384 and at_once <= 40 * 2**20 // (16 * 2**10)


def test_a_wide_render_streams_within_the_budget(tmp_path):
    from cgamesh.tracer.png import read_png
    from cgamesh.tracer.render import render, render_png
    from cgamesh.tracer.world import build_world

    world = build_world(load_scene(EXAMPLES / "traced_fig16_surface.yaml"))
    width, height = 2048, 3
    limit = 8 * 2**20  # smaller than one row's tracing at the default band size
    tracemalloc.start()
    try:
        size = render_png(world, width, height, tmp_path / "wide.png", max_memory=Budget(limit))
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert size == (tmp_path / "wide.png").stat().st_size
    streamed = read_png(tmp_path / "wide.png")
    held = render(world, width, height)
    assert streamed.shape[:2] == (height, width)
    assert np.array_equal(streamed, np.round(held * 255).astype(streamed.dtype) if streamed.dtype == np.uint8
                          else np.round(held * 255) / 255)
    assert peak <= budget.FIXED_OVERHEAD + limit


# --- the estimates are upper bounds of what the work allocates ----------------------------------------

def _peak(work) -> int:
    tracemalloc.start()
    try:
        work()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.slow
@pytest.mark.parametrize("example, around, along", [("kb_tube", 64, 256), ("kb_tube", 4, 4000),
                                                    ("traced_fig11_point_pairs", 16, 512),
                                                    ("traced_fig11_point_pairs", 2, 2048)])
@pytest.mark.parametrize("suffix", [".glb", ".usdc", ".obj", ".ply", ".stl"])
def test_the_mesh_estimate_covers_meshing_and_writing(tmp_path, example, around, along, suffix):
    if suffix == ".usdc":
        pytest.importorskip("pxr")
    scene = load_scene(EXAMPLES / f"{example}.yaml")
    resolution = Resolution(around, along)
    plans = [plan_surface(spec, resolution) for spec in scene.surfaces]
    vertices = sum(p.vertices for p in plans)
    estimate = (sum(p.held for p in plans)
                + max([p.peak - p.held for p in plans] + [budget.export_bytes([suffix], vertices)]))

    def work(resolution):
        meshes = mesh_scene(scene, resolution)
        write(tmp_path / f"out{suffix}", meshes, WriteOptions(scene.up, scene.meters_per_unit, scene.units))

    work(Resolution(4, 4))  # the format's library imported first: a fixed cost, not the mesh's
    measured = _peak(lambda: work(resolution))
    assert measured <= estimate, (measured, estimate)


@pytest.mark.slow
@pytest.mark.parametrize("example, relative", [("kb_tube", 1e-2), ("fig10_cubic_pairs", 1e-2)])
def test_the_tolerance_estimate_covers_the_run(example, relative):
    scene = load_scene(EXAMPLES / f"{example}.yaml")
    spec = scene.surfaces[0]
    probe = plan_surface(spec, Resolution(tolerance=1.0))
    tolerance = relative * probe.surface.frame.scale
    plan = plan_surface(spec, Resolution(tolerance=tolerance))
    meshes = []
    measured = _peak(lambda: meshes.extend(mesh_scene(scene, Resolution(tolerance=tolerance))))
    assert measured <= plan.peak, (measured, plan.peak)
    assert meshes[0][0].max_deviation <= tolerance
