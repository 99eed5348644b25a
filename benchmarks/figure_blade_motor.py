"""One streamline as a tube both ways: blade interpolation against motor interpolation.

    python benchmarks/figure_blade_motor.py [--out docs/figures/blade_vs_motor.png] [--index 3]

Takes one streamline of dipy's shipped cb_2.npz (samples 2-8 mm apart), makes it a tube of
radius 0.25 mm through its samples (normals along the path, Catmull-Rom) and draws, for blade
and motor interpolation, the mesh's silhouette seen along the streamline's least-spread axis,
with the samples' circles and the ratio of each ring's radius to the sample radius along the
curve. Needs matplotlib (the report extra) and dipy (its data).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import fidelity  # noqa: E402

from cgamesh.geometry.objects import circle_euclidean  # noqa: E402
from cgamesh.pipelines.scene import build_surface  # noqa: E402


def ring_radii(chain: fidelity.Chain, interpolation: str, t: np.ndarray) -> np.ndarray:
    surface = build_surface(fidelity.chain_spec(chain, interpolation))
    _, _, radius = circle_euclidean(surface.sample(t).blades)
    return radius * surface.frame.scale


def main() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("docs/figures/blade_vs_motor.png"))
    parser.add_argument("--index", type=int, default=3, help="which streamline of cb_2.npz")
    args = parser.parse_args()
    import importlib.util

    data = Path(importlib.util.find_spec("dipy").submodule_search_locations[0]) / "data" / "files" / "cb_2.npz"
    chain = fidelity.npz_streamlines(data, 0.25)[args.index]
    centred = chain.centres - chain.centres.mean(axis=0)
    _, _, axes = np.linalg.svd(centred, full_matrices=False)
    plane = axes[:2]  # view along the least-spread axis

    figure, panels = plt.subplots(3, 1, figsize=(9, 8), gridspec_kw={"height_ratios": [2, 2, 1.2]})
    for panel, interpolation, colour in ((panels[0], "blade", "#c0392b"), (panels[1], "motor", "#2471a3")):
        tube = fidelity.cgamesh_tube(chain, interpolation)
        flat = (tube.vertices - chain.centres.mean(axis=0)) @ plane.T
        panel.scatter(flat[:, 0], flat[:, 1], s=0.3, color=colour, alpha=0.35, linewidths=0)
        nodes = centred @ plane.T
        panel.plot(nodes[:, 0], nodes[:, 1], "k.", markersize=3)
        panel.set_aspect("equal")
        panel.set_title(f"interpolation: {interpolation} (mesh vertices, samples as dots)", fontsize=9)
        panel.tick_params(labelsize=7)
    t = np.linspace(0.0, len(chain.centres) - 1, 40 * (len(chain.centres) - 1) + 1)
    for interpolation, colour in (("blade", "#c0392b"), ("motor", "#2471a3")):
        panels[2].plot(t, ring_radii(chain, interpolation, t) / 0.25, color=colour, label=interpolation)
    panels[2].axhline(1.25, color="grey", linewidth=0.6, linestyle="--")
    panels[2].set_yscale("log")
    panels[2].set_xlabel("t (sample index)", fontsize=8)
    panels[2].set_ylabel("ring radius / sample radius", fontsize=8)
    panels[2].legend(fontsize=8)
    panels[2].tick_params(labelsize=7)
    figure.suptitle(f"cb_2.npz streamline {args.index}: {len(chain.centres)} samples, tube radius 0.25 mm", fontsize=10)
    figure.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(args.out, dpi=110)
    print(f"{args.out}: blade rings up to {ring_radii(chain, 'blade', t).max() / 0.25:.2f} x the radius, "
          f"motor {ring_radii(chain, 'motor', t).max() / 0.25:.3f} x")


if __name__ == "__main__":
    main()
