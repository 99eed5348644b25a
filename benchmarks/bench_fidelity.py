"""Tube fidelity on real data: cgamesh motor, cgamesh blade and pyvista's Spline + tube, side by side.

    python benchmarks/bench_fidelity.py [--swc FILE] [--npz FILE] [--radius 0.25]

Data (only files that installed packages ship; nothing is downloaded):
- tractography: dipy's ``cb_2.npz`` (two bundles of streamlines sampled every 2-8 mm; BSD
  licence), each streamline a tube of radius ``--radius`` (mm);
- a neuron: navis' example skeleton ``722817260.swc`` (a hemibrain DA1 lPN, radii per node),
  split into unbranched chains at its branch points.

Every chain becomes one circles surface through its samples (normals along the path: the
bisector of the chords; Catmull-Rom; 8 rings per segment, 16 vertices around), meshed by
cgamesh with interpolation motor and blade, and by pyvista (a benchmark-only dependency) as
``Spline(points, rings).tube(scalars=radius, absolute=True)``. The statistics (benchmarks/
fidelity.py) are taken against two smooth centrelines through each chain, a natural cubic
spline and a chord-length Catmull-Rom spline, with the radius linear in arc length:
bulge (vertex distance to the centreline over the radius there), neck (centreline sample's
distance to the nearest vertex over its radius) and folded segments. Nothing is asserted:
tests/test_fidelity.py holds the thresholds on smaller inputs.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
import fidelity  # noqa: E402


def shipped(package: str, relative: str) -> Path:
    module = __import__(package)
    return Path(module.__file__).parent / relative


def report(title: str, chains) -> None:
    segments = sum(len(c.centres) - 1 for c in chains)
    print(f"\n{title}: {len(chains)} chains, {segments} segments")
    candidates = [("cgamesh motor", lambda c: fidelity.cgamesh_tube(c, "motor")),
                  ("cgamesh blade", lambda c: fidelity.cgamesh_tube(c, "blade")),
                  ("pyvista", fidelity.pyvista_tube)]
    header = (f"{'reference':<12} {'tube':<14} {'vertices':>9} {'>1.25':>8} {'>1.6':>8} {'p99':>6} {'max':>6} "
              f"{'neck<0.75':>10} {'p1':>6} {'min':>6} {'folded':>7} {'failed':>6} {'s':>6}")
    print(header)
    print("-" * len(header))
    for reference in fidelity.REFERENCES:
        for name, build in candidates:
            start = time.perf_counter()
            f = fidelity.measure(chains, build, reference)
            print(f"{reference:<12} {name:<14} {f.vertices:>9} {100 * f.bulge_over_125:>7.3f}% "
                  f"{100 * f.bulge_over_160:>7.3f}% {f.bulge_p99:>6.3f} {f.bulge_max:>6.2f} "
                  f"{100 * f.neck_under_075:>9.2f}% {f.neck_p1:>6.3f} {f.neck_min:>6.3f} {f.folded:>7} "
                  f"{f.failed_chains:>6} {time.perf_counter() - start:>6.1f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--npz", type=Path, default=None, help="streamlines: points + offsets (default dipy's cb_2.npz)")
    parser.add_argument("--swc", type=Path, default=None, help="a neuron (default navis' 722817260.swc)")
    parser.add_argument("--radius", type=float, default=0.25, help="streamline tube radius (mm)")
    args = parser.parse_args()
    npz = args.npz or shipped("dipy", "data/files/cb_2.npz")
    swc = args.swc or shipped("navis", "data/swc/722817260.swc")
    report(f"streamlines {npz.name}, radius {args.radius}", fidelity.npz_streamlines(npz, args.radius))
    report(f"neuron {swc.name}", fidelity.swc_chains(swc))


if __name__ == "__main__":
    main()
