"""``cgamesh verify SCENE.yaml MESH.glb``: check a mesh's vertices and normals with the ray tracer."""

from __future__ import annotations

import argparse
import sys

from cgamesh_cli.arguments import add_budget_option
from cgamesh_cli.render import add_tracer_options, image_size

EXIT_FAILED = 1


def _non_negative(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0.0 <= value < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text}")
    return value


def build_parser() -> argparse.ArgumentParser:
    from cgamesh.tracer import verify as v

    parser = argparse.ArgumentParser(
        prog="cgamesh verify",
        description="Trace a ray through every mesh vertex along its normal and compare the mesh with the "
                    "analytic surface: vertex distance and normal angle per surface; exit status 1 when a "
                    "threshold is broken.",
    )
    parser.add_argument("scene", help="the YAML scene file the mesh was made from")
    parser.add_argument("mesh", help="the exported mesh: .glb or .gltf")
    parser.add_argument("--image", metavar="DIFF.png",
                        help="also write traced | mesh | difference images of the surfaces side by side")
    parser.add_argument("--size", type=image_size, default=(320, 240),
                        help="WIDTHxHEIGHT of each of the three --image panels (default 320x240)")
    parser.add_argument("--max-angle", type=_non_negative, default=v.MAX_ANGLE_DEGREES,
                        help=f"largest angle between normals, degrees (default {v.MAX_ANGLE_DEGREES})")
    parser.add_argument("--max-distance", type=_non_negative, default=v.MAX_DISTANCE,
                        help=f"largest vertex distance from the surface, relative to its bounding radius "
                             f"(default {v.MAX_DISTANCE:g})")
    parser.add_argument("--max-missed", type=_non_negative, default=v.MAX_MISSED,
                        help=f"largest fraction of vertex rays that hit nothing (default {v.MAX_MISSED:g})")
    add_tracer_options(parser)
    add_budget_option(parser)
    parser.add_argument("-q", "--quiet", action="store_true", help="print nothing (the exit status tells)")
    return parser


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace
    from pathlib import Path

    from cgamesh.errors import InvalidInputError
    from cgamesh.progress import Progress
    from cgamesh.inputs.scene import load_scene
    from cgamesh.tracer import verify as v
    from cgamesh.tracer.evolved import RootFinder
    from cgamesh.readers.files import read_limit
    from cgamesh.tracer.meshfile import read_glb
    from cgamesh.tracer.png import write_png
    from cgamesh.tracer.world import build_world

    if Path(args.mesh).suffix.lower() not in (".glb", ".gltf"):
        raise InvalidInputError(f"{args.mesh}: expected a .glb or .gltf mesh file")
    if args.image and Path(args.image).suffix.lower() != ".png":
        raise InvalidInputError(f"{args.image}: expected a .png image file")
    scene = load_scene(args.scene)
    meshes = read_glb(args.mesh, scene.up, scene.meters_per_unit, read_limit(args.max_memory))
    world = build_world(scene, RootFinder(args.root_finder, args.samples), primitives=False)
    thresholds = v.Thresholds(args.max_angle, args.max_distance, args.max_missed)
    with Progress(len(world.surfaces()), enabled=not args.quiet) as progress:
        reports = v.verify_meshes(world.surfaces(), meshes, thresholds, progress.advance, args.max_memory)
    if args.image:
        width, height = args.size
        plain = replace(world, shadows=False, max_depth=0)
        names = [s.name for s in world.surfaces()]
        write_png(args.image, v.comparison_image(plain, [m for m in meshes if m.name in names], width, height,
                                                 args.max_memory))
    if not args.quiet:
        print(v.format_reports(reports, thresholds), file=sys.stdout)
    return 0 if all(r.passed for r in reports) else EXIT_FAILED
