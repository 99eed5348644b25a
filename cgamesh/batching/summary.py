"""What a batch returns: one record per input and the counts (``cgamesh.batch`` returns a
``BatchSummary``; ``cgamesh batch --json`` prints it)."""

from __future__ import annotations

from dataclasses import asdict, dataclass


@dataclass(frozen=True)
class InputRecord:
    """One input's outcome. ``status`` is "done", "skipped" (its outputs were current) or
    "failed" (``reason`` says why, on one line). ``seconds`` is the task's own wall time and
    ``cpu_seconds`` its processor time; the
    counts are those of the run that made the outputs (for a skipped input, an earlier one)."""

    input: str
    name: str
    status: str
    reason: str = ""
    outputs: tuple[str, ...] = ()
    sha256: str = ""
    seconds: float = 0.0
    cpu_seconds: float = 0.0
    vertices: int = 0
    bytes: int = 0


@dataclass(frozen=True)
class BatchSummary:
    """The counts of a batch and every input's record, in the order the inputs were given."""

    done: int
    skipped: int
    failed: int
    seconds: float
    records: tuple[InputRecord, ...]
    manifest: str
    workers: int

    @property
    def ok(self) -> bool:
        return self.failed == 0

    @property
    def throughput(self) -> float:
        """Inputs meshed per second of the run's wall time."""
        return self.done / self.seconds if self.seconds > 0 else 0.0

    @property
    def failures(self) -> tuple[InputRecord, ...]:
        return tuple(r for r in self.records if r.status == "failed")

    def line(self) -> str:
        return (f"batch: {self.done} done, {self.skipped} skipped, {self.failed} failed, "
                f"{self.seconds:.2f} s, {self.throughput:.2f} inputs/s on {self.workers} "
                f"worker{'s' if self.workers != 1 else ''}; manifest {self.manifest}")

    def to_dict(self) -> dict:
        return {"done": self.done, "skipped": self.skipped, "failed": self.failed, "seconds": self.seconds,
                "throughput": self.throughput, "workers": self.workers, "manifest": self.manifest,
                "inputs": [asdict(r) for r in self.records]}
