"""A progress bar on stderr for runs long enough to want one.

It stays silent for the first second and when stderr is not a terminal, so short runs and
piped output are not cluttered.
"""

from __future__ import annotations

import sys
import time

SILENT_SECONDS = 1.0
WIDTH = 30


class Progress:
    def __init__(self, total: int, enabled: bool = True, stream=None):
        self.total = max(total, 1)
        self.done = 0
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled and getattr(self.stream, "isatty", lambda: False)()
        self.start = time.perf_counter()
        self.drawn = False

    def advance(self, label: str = "", count: int = 1) -> None:
        """``count`` more items done, the last of them ``label``."""
        self.done += count
        if not self.enabled or time.perf_counter() - self.start < SILENT_SECONDS:
            return
        filled = WIDTH * self.done // self.total
        bar = "#" * filled + "-" * (WIDTH - filled)
        self.stream.write(f"\r[{bar}] {self.done}/{self.total} {label[:40]:<40}")
        self.stream.flush()
        self.drawn = True

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, *exc) -> None:
        if self.drawn:
            self.stream.write("\n")
            self.stream.flush()
