"""Same meshes? Every job meshed by the tree before a change and by the tree after it, compared.

    python benchmarks/compare_trees.py [--base REV|DIR] [--head REV|DIR] [--quick] [--jobs PATTERN] [--parallel]

``--base`` defaults to f8376ab (the tree before the one-mesher refactor), ``--head`` to the
working tree; a revision is checked out in a temporary git worktree (trees.py), a folder is
used as it is. Each tree runs in a worker process of its own (compare_trees_child.py) through
interfaces that outlive a refactor: ``cgamesh.load(path, **options)`` for arrays in float64
before export, ``cgamesh_cli.main.main(argv)`` for written files.

Jobs: every example at its own resolution and at the overrides and tolerances the tests use,
with and without tangents, and written through the command to every format (plain, and glTF
with --quantize --tangents); the scenes of compare_scenes.py (every curve, kind, closed, caps,
align, interpolation; uv modes; turned strips); bench_scene_batch's random tubes and ribbons;
the five navis neurons and dipy's fornix at the defaults (arrays, GLB, USDA + USDZ) and one
neuron and the fornix with --color-by radius / direction / segment, --split, caps,
--subdivide 0, --radius and (the neuron) --tolerance. ``--quick``: a handful (about a minute).

Arrays pass when equal, or when their largest difference is at most 1e-12: positions relative
to the diagonal of the surface's bounding box, unit vectors (normals, tangents) absolute, the
rest relative to their largest magnitude; integer arrays (faces, weld) must be equal. A
refusal passes when both trees refuse with the same message. Written files pass on identical
bytes (a USDZ on identical members: its zip records times); files that differ are reported
and read back by the base tree's readers (cgamesh.readers.readback), then pass when their
arrays agree to float32 rounding (glTF quantized by --quantize: to its quantization step).
Prints a row per job (job, outcome, worst difference) and exits 1 on any mismatch.
"""

from __future__ import annotations

import argparse
import fnmatch
import re
import json
import shutil
import sys
import tempfile
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from trees import DEFAULT_BASE, HERE, ROOT, TreeError, Worker, bench_scene, load_average, open_trees, run_tool

import compare_scenes

sys.path.insert(0, str(ROOT / "tests"))
from realdata_files import fornix, neurons  # noqa: E402 (how the tests find navis' and dipy's files)

LIMIT = 1e-12  # float64 arrays before export
FLOAT32 = 2.0 * np.finfo(np.float32).eps  # two float32 steps relative to the magnitude
# glTF --quantize: positions as 16-bit steps of the box, normals and tangents as 8-bit, UVs 16-bit
QUANTIZED = {"positions": 1.0 / 32767.0, "normals": 1.0 / 127.0, "tangents": 1.0 / 127.0, "uvs": 1.0 / 65535.0}
FORMATS = (".glb", ".gltf", ".usda", ".usdc", ".usd", ".usdz", ".obj", ".ply", ".stl")
UNIT_VECTORS = ("normals", "tangents")


@dataclass
class Job:
    """``kind`` "api": cgamesh.load(input, **options); "cli": the command with ``argv``;
    "export": cgamesh.load(input, **options).export(name) for each name in ``argv``."""

    name: str
    kind: str
    input: str = ""
    options: dict = field(default_factory=dict)
    argv: list = field(default_factory=list)
    quantize: bool = False
    quick: bool = False

    def message(self, out: Path) -> dict:
        return {"kind": self.kind, "input": self.input, "options": self.options, "argv": self.argv, "out": str(out)}


# Example overrides: (label, cgamesh.load options) as the tests mesh examples.
EXAMPLE_VARIANTS = [("file", {}), ("file+tangents", {"tangents": True}), ("12x24", {"around": 12, "along": 24}),
                    ("12x24+tangents", {"around": 12, "along": 24, "tangents": True}),
                    ("24x48", {"around": 24, "along": 48}), ("8x12+tangents", {"around": 8, "along": 12, "tangents": True}),
                    ("5x9", {"around": 5, "along": 9}), ("3x2", {"around": 3, "along": 2}),
                    ("3x2+tangents", {"around": 3, "along": 2, "tangents": True}),
                    ("tolerance-1e-2", {"tolerance": 1e-2}), ("tolerance-1e-3", {"tolerance": 1e-3}),
                    ("tolerance-1e-4", {"tolerance": 1e-4})]
QUICK_EXAMPLES = {("kb_tube", "file"), ("kb_tube", "12x24+tangents"), ("motor_tube", "file"),
                  ("fig10_cubic_pairs", "file"), ("ribbon_loop", "5x9"), ("closed_loop", "tolerance-1e-3"),
                  ("fig14_bezier_orders", "3x2+tangents")}
LOW = ["--around", "8", "--along", "12"]  # tests/test_export_formats.py


def example_jobs(examples: list[Path]) -> list[Job]:
    jobs = []
    for path in examples:
        for label, options in EXAMPLE_VARIANTS:
            jobs.append(Job(f"example/{path.stem}/{label}", "api", str(path), options,
                            quick=(path.stem, label) in QUICK_EXAMPLES))
        every = [a for suffix in FORMATS for a in ("-o", f"{{out}}/plain{suffix}")]
        jobs.append(Job(f"example/{path.stem}/write-every-format", "cli", argv=[str(path), *every, *LOW, "-q"],
                        quick=path.stem == "fig14_bezier_orders"))
        jobs.append(Job(f"example/{path.stem}/write-glb-12x24", "cli",
                        argv=[str(path), "-o", "{out}/low.glb", "--around", "12", "--along", "24", "-q"]))
        jobs.append(Job(f"example/{path.stem}/write-gltf-quantize-tangents", "cli", quantize=True,
                        argv=[str(path), "-o", "{out}/packed.glb", "-o", "{out}/packed.gltf", "--quantize",
                              "--tangents", *LOW, "-q"], quick=path.stem == "kb_tube"))
        jobs.append(Job(f"example/{path.stem}/write-glb-tolerance-1e-3", "cli",
                        argv=[str(path), "-o", "{out}/tolerance.glb", "--tolerance", "1e-3", "-q"]))
    return jobs


def scene_jobs(scenes: dict[str, Path]) -> list[Job]:
    """The scenes of compare_scenes.py and the benchmarks' random tubes and ribbons."""
    jobs = []
    for name, path in scenes.items():
        if name == "uv-xatlas":
            try:
                import xatlas  # noqa: F401
            except ImportError:
                print("xatlas is not installed: uv-xatlas skipped", file=sys.stderr)
                continue
        quick = name in ("circles-kb-caps-motor-x3", "point_pairs-bezier-blade-x3", "uv-natural-scale-0.5",
                         "bench-tubes-60x4-blade")
        jobs.append(Job(f"scene/{name}/file", "api", str(path), quick=quick))
        jobs.append(Job(f"scene/{name}/tangents", "api", str(path), {"tangents": True}))
        if name.startswith("bench-ribbons"):
            jobs.append(Job(f"scene/{name}/2x7", "api", str(path), {"around": 2, "along": 7}))
        if name.startswith("uv-"):
            jobs.append(Job(f"scene/{name}/write-glb-quantize-tangents", "cli", quantize=True,
                            argv=[str(path), "-o", "{out}/uv.glb", "--quantize", "--tangents", "-q"]))
            jobs.append(Job(f"scene/{name}/write-usda", "cli", argv=[str(path), "-o", "{out}/uv.usda", "-q"]))
    return jobs


FLAGS = {"radius": "--radius", "color_by": "--color-by", "split": "--split", "subdivide": "--subdivide",
         "around": "--around", "tolerance": "--tolerance"}  # centreline options of load() as the command's flags
REALDATA_VARIANTS = [("color-by-radius", {"color_by": "radius"}), ("color-by-direction", {"color_by": "direction"}),
                     ("color-by-segment", {"color_by": "segment"}), ("split", {"split": True}), ("caps", {"caps": True}),
                     ("subdivide-0", {"subdivide": 0}), ("around-5", {"around": 5})]


def realdata_writes(name: str, path: Path, options: dict, quick: bool = False) -> list[Job]:
    """The arrays of ``cgamesh.load(path, **options)``, and the command writing a GLB, then USDA
    and USDZ (a run writing only glTF holds the mesh as written: a path of its own). Options the
    command lacks (caps) are written through ``Meshes.export`` instead."""
    jobs = [Job(name, "api", str(path), options, quick=quick)]
    if all(key in FLAGS for key in options):
        flags = [str(x) for key, value in options.items() for x in ((FLAGS[key],) if value is True else (FLAGS[key], value))]
        writes = [("write-glb", ["mesh.glb"]), ("write-usda-usdz", ["mesh.usda", "mesh.usdz"])]
        for label, outputs in writes[:1] if "tolerance" in options else writes:  # a tolerance run: 10 s and more
            files = [a for o in outputs for a in ("-o", f"{{out}}/{o}")]
            jobs.append(Job(f"{name}/{label}", "cli", argv=[str(path), *files, *flags, "-q"], quick=quick and label == "write-glb"))
    else:
        jobs.append(Job(f"{name}/export-glb-usda-usdz", "export", str(path), options,
                        argv=["mesh.glb", "mesh.usda", "mesh.usdz"]))
    return jobs


def realdata_jobs() -> list[Job]:
    """Each neuron and the fornix at the defaults; the smallest neuron and the fornix with options."""
    smallest = min(neurons(), key=lambda p: p.stat().st_size)
    jobs = []
    for path in neurons():
        jobs += realdata_writes(f"neuron/{path.stem}/defaults", path, {}, quick=path == smallest)
    jobs += realdata_writes("fornix/defaults", fornix(), {"radius": 0.5}, quick=True)
    for name, path, options, radius in ((f"neuron/{smallest.stem}", smallest, {}, 40.0),
                                        ("fornix", fornix(), {"radius": 0.5}, 0.25)):
        variants = REALDATA_VARIANTS + [("radius", {"radius": radius})]
        if name.startswith("neuron"):  # about 10 s a run: one tolerance, 1e-1 of the median radius
            variants.append(("tolerance-2", {"tolerance": 2.0}))
        for label, extra in variants:
            jobs += realdata_writes(f"{name}/{label}", path, {**options, **extra})
    return jobs


def selected(jobs: list[Job], quick: bool, patterns: list[str]) -> list[Job]:
    """The quick ones with ``quick``; those matching any of ``patterns`` (fnmatch, or a plain
    substring when a pattern has no wildcard) when given."""
    if quick:
        jobs = [job for job in jobs if job.quick]
    if patterns:
        globs = [p if any(c in p for c in "*?[") else f"*{p}*" for p in patterns]
        jobs = [job for job in jobs if any(fnmatch.fnmatchcase(job.name, g) for g in globs)]
    return jobs


# ---- comparing ------------------------------------------------------------------------------

def difference(name: str, a: np.ndarray, b: np.ndarray, relative_box: bool = True) -> float:
    """0 for equal arrays, inf for different shapes or integers, else the largest difference
    as this module's docstring measures it."""
    if a.shape != b.shape:
        return np.inf
    if a.dtype.kind in "fc" or b.dtype.kind in "fc":
        if np.array_equal(a, b, equal_nan=True):
            return 0.0
    elif np.array_equal(a, b):
        return 0.0
    if a.dtype.kind not in "fc" or b.dtype.kind not in "fc" or not np.array_equal(np.isnan(a), np.isnan(b)):
        return np.inf
    gap = np.nanmax(np.abs(a.astype(np.float64) - b.astype(np.float64))) if a.size else 0.0
    field_name = name.split(".", 1)[-1]
    if field_name in UNIT_VECTORS:
        scale = 1.0
    elif field_name == "positions" and relative_box and a.size:
        scale = float(np.linalg.norm(np.ptp(a, axis=0)))
    else:
        scale = float(np.nanmax(np.abs(a))) if a.size else 0.0
    return gap / scale if scale > 0.0 else gap


@dataclass
class Outcome:
    passed: bool
    text: str
    worst: float = 0.0
    where: str = ""


def compare_arrays(base: Path, head: Path, limit=lambda name: LIMIT, relative_box: bool = True) -> Outcome:
    """The npz dumps of one job by both trees."""
    with np.load(base) as first, np.load(head) as second:
        names = sorted(set(first.files) | set(second.files))
        missing = [n for n in names if n not in first.files or n not in second.files]
        if missing:
            side = "head" if missing[0] in first.files else "base"
            return Outcome(False, f"{missing[0]} missing in {side}", np.inf, missing[0])
        worst, where, notes, failed = 0.0, "", [], False
        for name in names:
            a, b = first[name], second[name]
            if a.shape != b.shape:
                return Outcome(False, f"{name}: shape {a.shape} in base, {b.shape} in head", np.inf, name)
            if a.dtype != b.dtype:
                notes.append(f"{name} {a.dtype}->{b.dtype}")
            gap = difference(name, a, b, relative_box)
            failed = failed or gap > limit(name)
            if gap > worst:
                worst, where = gap, name
    if failed:
        return Outcome(False, f"DIFFERENT (worst {where})", worst, where)
    text = "identical" if worst == 0.0 else f"within {LIMIT:g}"
    return Outcome(True, text + (f"; dtypes {', '.join(notes[:3])}" if notes else ""), worst, where)


def same_surface(a: dict, b: dict) -> bool:
    """Name, flags and material equal; the a priori bound of a tolerance mesh (a float) within LIMIT."""
    x, y = a.get("max_deviation"), b.get("max_deviation")
    close = x == y or (x is not None and y is not None and abs(x - y) <= LIMIT * abs(x))
    return close and {**a, "max_deviation": 0} == {**b, "max_deviation": 0}


def compare_answers(base: dict, head: dict) -> Outcome | None:
    """A failure from the answers alone (different refusals, exit status, stderr, surfaces), or None."""
    for side, result in (("base", base), ("head", head)):
        if "died" in result:
            return Outcome(False, f"{side} worker died: {result['died'][-300:]}", np.inf)
    if "error" in base or "error" in head:
        if base.get("error") == head.get("error"):
            return Outcome(True, "same refusal: " + re.sub(r"/\S*/", "", base["error"])[:60])
        return Outcome(False, f"base {base.get('error', 'meshed')[:70]!r} / head {head.get('error', 'meshed')[:70]!r}",
                       np.inf)
    if len(base.get("surfaces", [])) != len(head.get("surfaces", [])):
        return Outcome(False, f"{len(base['surfaces'])} surfaces in base, {len(head['surfaces'])} in head", np.inf)
    for a, b in zip(base.get("surfaces", []), head.get("surfaces", [])):
        if not same_surface(a, b):
            return Outcome(False, f"surface {a['name']!r} differs: base {a} / head {b}", np.inf)
    for key in ("status", "stderr", "up", "units", "meters_per_unit", "skipped"):
        if base.get(key) != head.get(key):
            return Outcome(False, f"{key} differs: base {str(base.get(key))[:60]!r} / head {str(head.get(key))[:60]!r}",
                           np.inf)
    return None


def same_usdz(a: Path, b: Path) -> bool:
    """The same members with the same bytes (a zip also records when each was written)."""
    with zipfile.ZipFile(a) as first, zipfile.ZipFile(b) as second:
        if first.namelist() != second.namelist():
            return False
        return all(first.read(name) == second.read(name) for name in first.namelist())


def differing_files(base: Path, head: Path) -> tuple[list[str], list[str]]:
    """(files not byte-identical, files only one tree wrote), by name relative to the job's folder."""
    names = {p.name for p in base.iterdir()} | {p.name for p in head.iterdir()}
    alone = sorted(n for n in names if not (base / n).is_file() or not (head / n).is_file())
    differ = []
    for name in sorted(names - set(alone)):
        a, b = base / name, head / name
        if a.read_bytes() == b.read_bytes():
            continue
        if name.endswith(".usdz") and same_usdz(a, b):
            continue
        differ.append(name)
    return differ, alone


def compare_written(job: Job, base: Path, head: Path, decoder: Worker, folder: Path) -> Outcome:
    differ, alone = differing_files(base, head)
    if alone:
        return Outcome(False, f"written by one tree only: {', '.join(alone)}", np.inf)
    if not differ:
        return Outcome(True, "identical bytes")
    readable = [n for n in differ if Path(n).suffix.lower() in FORMATS]
    if len(readable) < len(differ):
        other = sorted(set(differ) - set(readable))
        return Outcome(False, f"bytes differ: {', '.join(other)} (no reader)", np.inf, other[0])
    dumps = {(n, side): folder / f"{side.parent.name}-{n}.npz" for n in readable for side in (base, head)}
    decoder.send({"kind": "decode", "files": [[str(side / n), str(dump)] for (n, side), dump in dumps.items()]})
    answer = decoder.receive()
    if "files" not in answer:
        return Outcome(False, f"bytes differ: {', '.join(readable)}; reading back failed: "
                              f"{answer.get('error') or answer.get('died')}", np.inf)
    worst = Outcome(True, "")
    for name in readable:
        if answer["files"][str(base / name)] != answer["files"][str(head / name)]:
            return Outcome(False, f"bytes differ: {name}, surfaces read back differ", np.inf, name)
        suffix = Path(name).suffix.lower()
        if job.quantize and suffix in (".glb", ".gltf"):
            limit = lambda key: QUANTIZED.get(key.split(".", 1)[-1], 1.0 / 65535.0)  # noqa: E731
        else:  # float32 in glTF and USD; OBJ prints digits, PLY / STL store float32
            limit = lambda key: FLOAT32 if suffix in (".glb", ".gltf") or suffix.startswith(".usd") else 1e-6  # noqa: E731
        outcome = compare_arrays(dumps[name, base], dumps[name, head], limit, relative_box=False)
        if not outcome.passed:
            return Outcome(False, f"bytes differ: {name}, read back {outcome.text}", outcome.worst, outcome.where)
        if outcome.worst >= worst.worst:
            worst = outcome
    kind = "quantization" if job.quantize else "float32"
    return Outcome(True, f"bytes differ ({', '.join(readable)}); read back within {kind} rounding", worst.worst,
                   worst.where)


def compare_job(job: Job, workers: dict[str, Worker], folder: Path, parallel: bool) -> Outcome:
    outs = {label: folder / label / "job" for label in workers}
    for out in outs.values():
        shutil.rmtree(out, ignore_errors=True)
    answers = {}
    for label in ("base", "head"):
        workers[label].send(job.message(outs[label]))
        if not parallel:
            answers[label] = workers[label].receive()
    for label in ("base", "head"):
        if parallel:
            answers[label] = workers[label].receive()
    outcome = compare_answers(answers["base"], answers["head"])
    if outcome is None:
        if job.kind == "api":
            outcome = compare_arrays(outs["base"] / "arrays.npz", outs["head"] / "arrays.npz")
        else:
            outcome = compare_written(job, outs["base"], outs["head"], workers["base"], folder)
    for out in outs.values():
        shutil.rmtree(out, ignore_errors=True)
    for stray in folder.glob("*.npz"):
        stray.unlink()
    return outcome


def print_row(name: str, outcome: Outcome, seconds: float, width: int) -> None:
    worst = "" if outcome.worst == 0.0 else ("inf" if not np.isfinite(outcome.worst) else f"{outcome.worst:.2e}")
    where = f" {outcome.where}" if outcome.where and outcome.worst else ""
    mark = "ok  " if outcome.passed else "FAIL"
    print(f"{mark} {name:<{width}} {outcome.text:<48} {worst:>9}{where}  ({seconds:.1f} s)", flush=True)


def build_jobs(base_root: Path, folder: Path, base_tree) -> list[Job]:
    scenes = compare_scenes.scene_files(folder)
    for interpolation in ("blade", "motor"):
        for controls in (2, 4):
            name = f"bench-tubes-60x{controls}-{interpolation}"
            scenes[name] = bench_scene(base_tree, folder / f"{name}.yaml", 60, controls, interpolation)
    for controls in (2, 3, 5):
        name = f"bench-ribbons-60x{controls}"
        scenes[name] = bench_scene(base_tree, folder / f"{name}.yaml", 60, controls, kind="ribbon")
    examples = sorted((base_root / "examples").glob("*.yaml"))
    return example_jobs(examples) + scene_jobs(scenes) + realdata_jobs()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", default=DEFAULT_BASE, help=f"revision or tree folder before the change (default {DEFAULT_BASE})")
    parser.add_argument("--head", default=None, help="revision or tree folder after it (default: the working tree)")
    parser.add_argument("--quick", action="store_true", help="a handful of jobs (about a minute)")
    parser.add_argument("--jobs", action="append", default=[], metavar="PATTERN",
                        help="only jobs whose name matches (fnmatch; a plain word matches as a substring); repeatable")
    parser.add_argument("--list", action="store_true", help="print the selected jobs' names and stop")
    parser.add_argument("--parallel", action="store_true", help="run both trees' workers at once (two cores)")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    with open_trees(args.base, args.head) as (base, head), tempfile.TemporaryDirectory(prefix="cgamesh-compare-") as tmp:
        folder = Path(tmp)
        (folder / "inputs").mkdir()
        jobs = selected(build_jobs(base.root, folder / "inputs", base), args.quick, args.jobs)
        if args.list:
            print("\n".join(job.name for job in jobs))
            return 0
        if not jobs:
            raise TreeError(f"no job matches {' '.join(args.jobs)}")
        print(f"{base.describe()}\n{head.describe()}\n{len(jobs)} jobs; load average {load_average()}", flush=True)
        workers = {tree.label: Worker(tree, HERE / "compare_trees_child.py") for tree in (base, head)}
        failures, width = [], max(len(job.name) for job in jobs)
        try:
            for label, worker in workers.items():
                print(f"{label} worker imports cgamesh from {worker.start()['cgamesh']}", flush=True)
            for job in jobs:
                began = time.perf_counter()
                outcome = compare_job(job, workers, folder, args.parallel)
                print_row(job.name, outcome, time.perf_counter() - began, width)
                if not outcome.passed:
                    failures.append(job.name)
        except BaseException:
            for worker in workers.values():
                worker.close(kill=True)
            raise
        for worker in workers.values():
            worker.close()
    minutes = (time.perf_counter() - start) / 60.0
    if failures:
        print(f"{len(failures)} of {len(jobs)} jobs DIFFER ({minutes:.1f} min): {', '.join(failures[:10])}"
              + (" ..." if len(failures) > 10 else ""))
        return 1
    print(f"all {len(jobs)} jobs give the same meshes ({minutes:.1f} min)")
    return 0


if __name__ == "__main__":
    run_tool("compare_trees", main)
