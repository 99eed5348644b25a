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
    figures = sorted(p.name for p in (tmp_path / "figures").glob("*.png"))
    assert "root_finders.png" in figures and any(name.startswith("accuracy_") for name in figures)
    assert all((tmp_path / "figures" / name).read_bytes().startswith(b"\x89PNG") for name in figures)
