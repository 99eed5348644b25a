"""``cgamesh view SCENE.yaml -o PAGE.html``: one self-contained HTML page showing the scene."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from cgamesh.errors import InvalidInputError
from cgamesh_cli.arguments import add_budget_option, add_option_flags


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cgamesh view",
        description="Write one self-contained HTML page (works offline) showing the scene's meshes with "
                    "three.js and its control circles / point pairs with ganja.js.",
    )
    parser.add_argument("scene", help="the YAML scene file")
    parser.add_argument("-o", "--output", required=True, help="the page to write (.html)")
    add_option_flags(parser, ("around", "along"))  # the table's (cgamesh.options), as cgamesh SCENE.yaml
    add_budget_option(parser)
    parser.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    return parser


def run(args: argparse.Namespace) -> str:
    from cgamesh.pipelines.scene import Resolution, mesh_scene
    from cgamesh.inputs.scene import load_scene
    from cgamesh.viewer import write_page

    output = Path(args.output)
    if output.suffix.lower() not in (".html", ".htm"):
        raise InvalidInputError(f"{output}: unknown output format {output.suffix or '(no extension)'!r}; "
                                "expected .html")
    start = time.perf_counter()
    scene = load_scene(args.scene)
    meshes = mesh_scene(scene, Resolution(args.around, args.along), max_memory=args.max_memory)
    written = write_page(output, scene, meshes)
    return f"{output}: {len(meshes)} surface{'s' if len(meshes) != 1 else ''}, {time.perf_counter() - start:.2f} s, {written} bytes"
