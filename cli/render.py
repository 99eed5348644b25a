"""``cgamesh render SCENE.yaml -o OUT.png``: ray trace a scene's analytic surfaces and objects."""

from __future__ import annotations

import argparse
import re
import time
from pathlib import Path

from cgamesh.errors import InvalidInputError
from cgamesh_cli.arguments import add_budget_option, whole_number

MAX_SIDE = 16384


def image_size(text: str) -> tuple[int, int]:
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not match:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT such as 640x480, got {text!r}")
    width, height = int(match.group(1)), int(match.group(2))
    if not (1 <= width <= MAX_SIDE and 1 <= height <= MAX_SIDE):
        raise argparse.ArgumentTypeError(f"expected each side from 1 to {MAX_SIDE}, got {width}x{height}")
    return width, height


def add_tracer_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--root-finder", choices=("polynomial", "sampled"), default="polynomial",
                        help="closed-form polynomial roots (default) or the paper's sampled finder")
    parser.add_argument("--samples", type=whole_number(2), default=64,
                        help="objects per curve segment for --root-finder sampled (default 64)")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cgamesh render",
        description="Ray trace the analytic surfaces (and spheres, planes, discs) of a scene file to a PNG "
                    "with Blinn-Phong lighting, shadows and reflections.",
    )
    parser.add_argument("scene", help="the YAML scene file (format version 1)")
    parser.add_argument("-o", "--output", required=True, help="output image: .png")
    parser.add_argument("--size", type=image_size, default=(640, 480), help="WIDTHxHEIGHT (default 640x480)")
    add_tracer_options(parser)
    add_budget_option(parser)
    parser.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    return parser


def run(args: argparse.Namespace) -> str:
    from cgamesh.progress import Progress
    from cgamesh.inputs.scene import load_scene
    from cgamesh.tracer.evolved import RootFinder
    from cgamesh.tracer.render import band_count, render_png
    from cgamesh.tracer.world import build_world

    output = Path(args.output)
    if output.suffix.lower() != ".png":
        raise InvalidInputError(f"{output}: unknown image format {output.suffix or '(no extension)'!r}; expected .png")
    start = time.perf_counter()
    world = build_world(load_scene(args.scene), RootFinder(args.root_finder, args.samples))
    width, height = args.size
    with Progress(band_count(width, height, world, args.max_memory), enabled=not args.quiet) as progress:
        written = render_png(world, width, height, output, progress.advance, args.max_memory)
    seconds = time.perf_counter() - start
    return f"{output}: {width}x{height}, {width * height} primary rays, {seconds:.2f} s, {written} bytes"
