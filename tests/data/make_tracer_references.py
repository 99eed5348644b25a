"""Regenerate the tracer's reference images: every examples/traced_*.yaml at 64 x 48.

    python tests/data/make_tracer_references.py

tests/test_tracer_render.py renders the same scenes and compares them with these files with a
tolerance. Regenerate (and look at the images) only when a change to the tracer is meant to
change its pictures.
"""

from __future__ import annotations

from pathlib import Path

from cgamesh.inputs.scene import load_scene
from cgamesh.tracer.png import write_png
from cgamesh.tracer.render import render
from cgamesh.tracer.world import build_world

SIZE = (64, 48)
HERE = Path(__file__).resolve().parent
EXAMPLES = HERE.parent.parent / "examples"


def reference_path(example: Path) -> Path:
    return HERE / f"tracer_{example.stem}.png"


def main() -> None:
    for example in sorted(EXAMPLES.glob("traced_*.yaml")):
        image = render(build_world(load_scene(example)), *SIZE)
        write_png(reference_path(example), image)
        print(reference_path(example).name)


if __name__ == "__main__":
    main()
