"""The accuracy report (benchmarks/report_accuracy.py) runs end to end at small size."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parent.parent / "benchmarks" / "report_accuracy.py"


def test_the_report_writes_its_tables_and_plots(tmp_path):
    subprocess.run([sys.executable, str(SCRIPT), "--out", str(tmp_path), "--small"], check=True,
                   capture_output=True, text=True, timeout=600)
    text = (tmp_path / "accuracy.md").read_text()
    assert "## Tessellation" in text and "## The tracer's root finders" in text
    # Every tolerance row meets its tolerance (deviation relative to size <= the tolerance).
    rows = re.findall(r"\| tolerance \| ([0-9.e-]+) \| (\d+) \| ([0-9.e+-]+) \|", text)
    assert rows and all(float(deviation) <= float(tolerance) for tolerance, _, deviation in rows)
    # The comparison with the smallest uniform grid: the bound meets the tolerance, the measured
    # deviation of both meshes is within it, and the ratios are those of the columns.
    assert "## Tolerance against the smallest uniform grid" in text
    compared = re.findall(r"\| \S+ \| ([0-9.e-]+) \| \d+ \| \d+ \| (\d+) \| ([0-9.e+-]+) \| ([0-9.e+-]+) \| \d+ "
                          r"\| (\d+) \| ([0-9.e+-]+) \| ([0-9.]+) \| ([0-9.]+) \|", text)
    assert compared
    for tolerance, vertices, bound, measured, uniform, uniform_measured, ratio, _ in compared:
        assert float(measured) <= float(bound) <= float(tolerance) and float(uniform_measured) <= float(tolerance)
        assert abs(float(ratio) - int(vertices) / int(uniform)) <= 0.006
    figures = sorted(p.name for p in (tmp_path / "figures").glob("*.png"))
    assert "root_finders.png" in figures and any(name.startswith("accuracy_") for name in figures)
    assert all((tmp_path / "figures" / name).read_bytes().startswith(b"\x89PNG") for name in figures)
