"""Scene files for ``compare_trees.py``: the option combinations the scene tests draw, fixed.

The tests draw scenes at random (hypothesis); a comparison of two trees wants the same files
on both sides, so here they are drawn once from a seeded generator, in the tests' ranges:
every curve kind, circles and point pairs, blade and motor interpolation, closed or open,
caps or not, align or not, orientations on the exact axes as often as anywhere, sizes from
1e-3 to 1e3, centres up to 1e4 from the origin, a control sometimes repeated, resolutions at
their bounds or a tolerance key (tests/test_scene_batched.py, test_input_space.py). Beside
them: the uv modes of tests/test_uv_modes.py and the turned strips of tests/test_winding.py.

``scene_files(folder)`` writes them and returns {name: path}.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

CURVES = ("linear", "bezier", "rational_bezier", "kb", "catmull_rom")
AXES = np.concatenate([np.eye(3), -np.eye(3)])


def _direction(rng) -> np.ndarray:
    """An exact +-axis half the time, else a direction from the sphere (rounded, as files hold them)."""
    if rng.random() < 0.5:
        return AXES[rng.integers(6)]
    v = rng.normal(size=3)
    return np.round(v / np.linalg.norm(v), 6)


def _surface(rng, name: str, kind: str, curve: str, closed: bool, caps: bool, interpolation: str) -> str:
    """One surface of 2 to 5 controls along a random walk (3 or more when closed)."""
    count = int(rng.integers(3 if closed else 2, 6))
    scale = 10.0 ** int(rng.integers(-3, 4))
    point = np.round(rng.uniform(-1.0, 1.0, 3) * 10.0 ** int(rng.integers(0, 5)), 6)
    step = _direction(rng)
    lines = []
    for _ in range(count):
        weight = f", weight: {10.0 ** rng.uniform(-1.0, 1.0):.6g}" if curve == "rational_bezier" else ""
        if kind == "circles":
            radius = scale * rng.uniform(0.3, 1.0)
            lines.append(f"{{center: {point.tolist()}, normal: {_direction(rng).tolist()}, radius: {radius:.6g}{weight}}}")
        else:
            across = _direction(rng) * scale * rng.uniform(0.4, 2.0)
            lines.append(f"{{a: {point.tolist()}, b: {(point + across).tolist()}{weight}}}")
        step = step + 0.5 * rng.normal(size=3)
        point = np.round(point + 1.5 * scale * step / max(np.linalg.norm(step), 1e-3), 9)
    if rng.random() < 0.2:  # a repeated control
        lines.insert(1, lines[0])
    kb = (f"    tension: {rng.choice([0.0, 0.5, -1.0, 1.0])}\n    bias: {rng.choice([0.0, 0.5, -1.0])}\n"
          f"    continuity: {rng.choice([0.0, 0.25, 1.0])}\n") if curve == "kb" else ""
    least = 3 if kind == "circles" else 2
    if rng.random() < 0.2:
        extent = "    tolerance: " + f"{scale * 10.0 ** rng.integers(-3, -1):.3g}\n"
    else:
        extent = (f"    resolution: {{around: {rng.choice([least, least + 1, 7, 16])}, "
                  f"along: {rng.choice([2, 3, 17, 40])}}}\n")
    motor = f"    interpolation: {interpolation}\n" if kind == "circles" else ""
    cap = f"    caps: {str(caps).lower()}\n" if kind == "circles" else ""
    return (f"  - name: {name}\n    type: {kind}\n    curve: {curve}\n{kb}{motor}"
            f"    closed: {str(closed).lower()}\n    align: {str(rng.random() < 0.75).lower()}\n{cap}{extent}"
            "    controls:\n" + "".join(f"      - {line}\n" for line in lines))


def option_scenes(seed: int = 11) -> dict[str, str]:
    """{name: scene text}: for every kind, curve, closed, caps and interpolation allowed, one
    file of three surfaces of that shape (the batched pass groups them) and one file of a
    single surface (a refusal there refuses that surface alone)."""
    rng = np.random.default_rng(seed)
    scenes = {}
    for kind in ("circles", "point_pairs"):
        for curve in CURVES:
            for closed in ((False, True) if curve in ("kb", "catmull_rom") else (False,)):
                for caps in ((False, True) if kind == "circles" and not closed else (False,)):
                    for interpolation in (("blade", "motor") if kind == "circles" else ("blade",)):
                        name = f"{kind}-{curve}{'-closed' if closed else ''}{'-caps' if caps else ''}-{interpolation}"
                        for size in (1, 3):
                            body = "".join(_surface(rng, f"s{i}", kind, curve, closed, caps, interpolation)
                                           for i in range(size))
                            scenes[f"{name}-x{size}"] = "cgamesh: 1\nsurfaces:\n" + body
    return scenes


def _two_tubes() -> str:
    """The uv-mode test's scene of two tubes (tests/test_uv_modes.py), its ``uv`` left to fill."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
    from test_uv_modes import TWO_TUBES

    return TWO_TUBES


def uv_scenes() -> dict[str, str]:
    """tests/test_uv_modes.py's two tubes in every uv mode (xatlas too: compare_trees skips it
    when xatlas is not installed)."""
    natural = _two_tubes().format(uv="natural")
    return {"uv-natural": natural,
            "uv-natural-scale-0.5": natural.replace("uv: natural", "uv: natural\n    uv_scale: 0.5"),
            "uv-natural-scale-0.1": natural.replace("uv: natural", "uv: natural\n    uv_scale: 0.1"),
            "uv-none": _two_tubes().format(uv="none"),
            "uv-xatlas": _two_tubes().format(uv="xatlas")}


def _ribbon(name: str, controls, closed: str, around: int, along: int) -> str:
    body = "".join(f"      - {{a: {list(map(float, a))}, b: {list(map(float, b))}}}\n" for a, b in controls)
    return (f"  - name: {name}\n    type: point_pairs\n    curve: kb\n    closed: {closed}\n    align: false\n"
            f"    resolution: {{around: {around}, along: {along}}}\n    controls:\n" + body)


def _closed_three_ring_tube(name: str, shift: float) -> str:
    return (f"  - name: {name}\n    type: circles\n    curve: kb\n    closed: true\n"
            "    align: false\n    resolution: {around: 16, along: 3}\n    controls:\n"
            f"      - {{center: [0.0, {shift}, 0.0], normal: [1.0, 0.0, 0.0], radius: 1.0}}\n"
            f"      - {{center: [1.3416407864998738, {shift}, 0.6708203932499369], normal: [1.0, 0.0, 0.0], radius: 1.0}}\n"
            f"      - {{center: [2.841640786499874, {shift}, 0.6708203932499369], normal: [1.0, 0.0, 0.0], radius: 1.0}}\n")


FOLDING_RIBBON = [((0.0, 0.0, 0.0), (0.0, 1.0, 0.0)), ((-1.5, 0.0, 0.0), (-2.5, 0.0, 0.0)),
                  ((-2.560660171779821, 0.0, 1.0606601717798212), (-1.560660171779821, 0.0, 1.0606601717798212))]


def winding_scenes() -> dict[str, str]:
    """tests/test_winding.py's turned strips: closed three-ring tubes, folding ribbons (alone and
    two together, for the batched pass), ribbons starting on a repeated control."""
    head = "cgamesh: 1\nsurfaces:\n"
    shifted = [(tuple(np.add(a, (0, 5, 0))), tuple(np.add(b, (0, 5, 0)))) for a, b in FOLDING_RIBBON]
    scenes = {"winding-closed-tubes": head + _closed_three_ring_tube("a", 0.0) + _closed_three_ring_tube("b", 3.0)}
    for closed in ("true", "false"):
        scenes[f"winding-folding-ribbons-{closed}"] = head + _ribbon("s", FOLDING_RIBBON, closed, 7, 40) + \
            _ribbon("t", shifted, closed, 7, 40)
    for along in (2, 3, 9):
        a, b, step = (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.3416407864998738, 0.6708203932499369)
        moved = (tuple(np.add(a, step)), tuple(np.add(b, step)))
        scenes[f"winding-repeated-start-{along}"] = head + _ribbon("s", [(a, b), (a, b), moved], "false", 2, along)
    return scenes


def scene_files(folder: Path) -> dict[str, Path]:
    """Write every scene of this module into ``folder``; {name: path}."""
    paths = {}
    for name, text in {**option_scenes(), **uv_scenes(), **winding_scenes()}.items():
        paths[name] = folder / f"{name}.yaml"
        paths[name].write_text(text)
    return paths
