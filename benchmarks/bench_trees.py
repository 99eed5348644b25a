"""No slower? The benchmarks' cases timed on the tree before a change and the tree after it, interleaved.

    python benchmarks/bench_trees.py [--base REV|DIR] [--head REV|DIR] [--repeat 5] [--quick] [--cases PATTERN]

``--base`` defaults to f8376ab (the tree before the one-mesher refactor), ``--head`` to the
working tree (trees.py checks a revision out into a temporary git worktree). Cases, each timed
in a fresh child process (bench_trees_child.py) running one tree's code:

- bench_tubes.py: the KB tube example meshed at 1024 x 1024 in process (``mesh_scene``, after
  warm-up meshes), and that mesh written as a GLB, each the median of 5 calls in the child
  (a call takes 0.05 to 0.1 s);
- bench_scene_batch.py: its scene of 2,000 catmull_rom tubes of 4 circles (written by the base
  tree's own benchmark helpers; read before the clock starts) meshed by ``mesh_scene``;
- bench_realdata.py: the three smallest navis neurons (--radius 40) and dipy's fornix
  (--radius 0.5), file to GLB through the command at 8 around and 3 rings between nodes, the
  whole process timed (its rusage).

Runs go base, head, base, head, ... (``--repeat`` of each, every case in every round), so both
trees see the same machine. Printed per case: the median CPU time (user + system of the measured
part), user time alone, wall time and peak resident memory of base and head, and head / base;
ratios above 1.05 are flagged ("!"), and a CPU ratio above it named. On a machine shared with
other work the system time (the kernel handing out the fresh pages a 1M-vertex mesh touches)
varies several-fold from run to run: the user time is then the steadier figure of the code. Figures only: nothing is asserted of a
time. Both trees must mesh the same vertex counts (else exit status 1). ``--quick``: one round at
small sizes (KB tube 256 x 256, 200 tubes, one neuron and the fornix).
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import statistics
import struct
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from trees import (DEFAULT_BASE, HERE, ROOT, Tree, TreeError, bench_scene, compile_tree, load_average, open_trees,
                   run_once, run_tool)

sys.path.insert(0, str(ROOT / "tests"))
from realdata_files import fornix, neurons  # noqa: E402 (how the tests and bench_realdata.py find the files)

THRESHOLD = 1.05
CHILD = HERE / "bench_trees_child.py"


@dataclass(frozen=True)
class Case:
    """One benchmark: ``argv`` of the child after the tree's root ("{out}" for a scratch file);
    ``whole``: the figure is the whole process (the parent's rusage), else the child's own."""

    name: str
    argv: tuple[str, ...]
    whole: bool = False


def glb_vertices(path: Path) -> int:
    """Vertex count of a GLB from its JSON chunk (bench_realdata.py's check)."""
    with open(path, "rb") as file:
        file.read(12)
        length, _ = struct.unpack("<II", file.read(8))
        gltf = json.loads(file.read(length))
    return sum(gltf["accessors"][p["attributes"]["POSITION"]]["count"] for m in gltf["meshes"] for p in m["primitives"])


def cases(base: Tree, folder: Path, quick: bool) -> list[Case]:
    size, surfaces = (256, 200) if quick else (1024, 2000)
    kb = base.root / "examples" / "kb_tube.yaml"
    scene = bench_scene(base, folder / "scene.yaml", surfaces)
    warmup = bench_scene(base, folder / "warmup.yaml", 8)
    found = [(path.stem, path, "40") for path in sorted(neurons(), key=lambda p: p.stat().st_size)[: 1 if quick else 3]]
    found.append(("fornix", fornix(), "0.5"))
    out = [Case(f"kb tube {size} x {size}", ("kb-tube", str(kb), str(size), "{out}")),
           Case(f"scene {surfaces} tubes x 4", ("scene", str(scene), str(warmup)))]
    for name, path, radius in found:
        out.append(Case(f"{name} to GLB", ("command", str(path), "-o", "{out}", "--radius", radius, "--around", "8",
                                            "--subdivide", "3", "-q"), whole=True))
    return out


def measure(tree: Tree, case: Case, out: Path) -> dict[str, dict]:
    """{figure: {"cpu", "wall", "peak", "vertices"}} of one run of ``case`` on ``tree``."""
    run = run_once(tree, [str(CHILD), str(tree.root), *(a.replace("{out}", str(out)) for a in case.argv)])
    if case.whole:
        return {"process": {"cpu": run.cpu, "user": run.user, "wall": run.wall, "peak": run.peak_mb,
                            "vertices": glb_vertices(out)}}
    return {name: {**figure, "peak": run.peak_mb, "vertices": run.result["vertices"]}
            for name, figure in run.result.items() if isinstance(figure, dict)}


def ratio(head: float, base: float) -> str:
    value = head / base if base > 0 else float("inf")
    return f"{value:5.2f}{'!' if value > THRESHOLD else ' '}"


def report(name: str, figure: str, runs: dict[str, list[dict]]) -> bool:
    """Print one row of medians; True when the CPU ratio is above the threshold."""
    median = {label: {key: statistics.median(r[key] for r in runs[label]) for key in ("cpu", "user", "wall", "peak")}
              for label in runs}
    b, h = median["base"], median["head"]
    flagged = h["cpu"] > THRESHOLD * b["cpu"]
    print(f"{name:<24} {figure:<9} {b['cpu']:8.3f} {h['cpu']:8.3f} {ratio(h['cpu'], b['cpu'])}   "
          f"{b['user']:8.3f} {h['user']:8.3f} {ratio(h['user'], b['user'])}   "
          f"{b['wall']:8.3f} {h['wall']:8.3f} {ratio(h['wall'], b['wall'])}   "
          f"{b['peak']:7.0f} {h['peak']:7.0f} {ratio(h['peak'], b['peak'])}"
          + ("   <- CPU above 1.05" if flagged else ""))
    return flagged


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", default=DEFAULT_BASE, help=f"revision or tree folder before the change (default {DEFAULT_BASE})")
    parser.add_argument("--head", default=None, help="revision or tree folder after it (default: the working tree)")
    parser.add_argument("--repeat", type=int, default=None, help="runs of each tree per case (default 5; --quick 1)")
    parser.add_argument("--quick", action="store_true", help="one round at small sizes")
    parser.add_argument("--cases", action="append", default=[], metavar="PATTERN",
                        help="only cases whose name matches (fnmatch; a plain word matches as a substring)")
    args = parser.parse_args(argv)
    repeat = args.repeat or (1 if args.quick else 5)
    if repeat < 1:
        raise TreeError(f"--repeat must be at least 1, got {repeat}")
    with open_trees(args.base, args.head) as trees, tempfile.TemporaryDirectory(prefix="cgamesh-bench-") as tmp:
        folder = Path(tmp)
        for tree in trees:
            compile_tree(tree)
            print(tree.describe())
        chosen = cases(trees[0], folder, args.quick)
        if args.cases:
            globs = [p if any(c in p for c in "*?[") else f"*{p}*" for p in args.cases]
            chosen = [c for c in chosen if any(fnmatch.fnmatchcase(c.name, g) for g in globs)]
            if not chosen:
                raise TreeError(f"no case matches {' '.join(args.cases)}")
        print(f"{len(chosen)} cases, {repeat} runs of each tree, interleaved; load average {load_average()}", flush=True)
        runs = {case.name: {} for case in chosen}  # case -> figure -> tree label -> [figures]
        for round_number in range(repeat):
            for case in chosen:
                for tree in trees:
                    out = folder / f"{tree.label}.glb"
                    for figure, value in measure(tree, case, out).items():
                        runs[case.name].setdefault(figure, {"base": [], "head": []})[tree.label].append(value)
                    out.unlink(missing_ok=True)
            print(f"round {round_number + 1} of {repeat} done; load average {load_average()}", flush=True)
    print(f"\n{'case':<24} {'figure':<9} {'CPU s: base':>12} {'head':>8} {'h/b':>5}    {'user s: base':>12} {'head':>8} "
          f"{'h/b':>5}    {'wall s: base':>12} {'head':>8} {'h/b':>5}    {'peak MB: base':>12} {'head':>7} {'h/b':>5}")
    flagged, mismatched = [], []
    for case in chosen:
        for figure, by_tree in runs[case.name].items():
            if report(case.name, figure, by_tree):
                flagged.append(f"{case.name} {figure}")
            counts = {r["vertices"] for label in by_tree for r in by_tree[label]}
            if len(counts) > 1:
                mismatched.append(f"{case.name} {figure}: vertex counts {sorted(counts)}")
    print(f"medians of {repeat}; '!' marks head / base above {THRESHOLD}; "
          + (f"CPU above it: {', '.join(flagged)}" if flagged else "no CPU ratio above it"))
    for line in mismatched:
        print(f"the trees mesh different vertex counts: {line}", file=sys.stderr)
    return 1 if mismatched else 0


if __name__ == "__main__":
    run_tool("bench_trees", main)
