"""SIGTERM and SIGINT as an exception, so that a stopped run cleans up like a failed one.

``install()`` makes both signals raise ``Interrupted`` in the main thread. It derives from
BaseException (like KeyboardInterrupt), so no ``except Exception`` swallows it, and every
``with`` block on the way out runs: the atomic writers remove their temporaries, an
``all_or_nothing`` commit removes everything it staged, and no output is touched. The command
line then prints ``cgamesh: interrupted`` and exits with 128 + the signal's number (130 for
SIGINT, 143 for SIGTERM), as shells report a process a signal stopped.
"""

from __future__ import annotations

import signal


class Interrupted(BaseException):
    """The run was stopped by a signal; ``signal_number`` says which."""

    def __init__(self, signal_number: int) -> None:
        super().__init__(signal.Signals(signal_number).name)
        self.signal_number = signal_number

    @property
    def exit_status(self) -> int:
        return 128 + self.signal_number


def _raise(signal_number, frame):
    raise Interrupted(signal_number)


def install() -> dict:
    """Raise Interrupted on SIGINT and SIGTERM (call from the main thread); returns the previous
    handlers, for ``restore``."""
    return {number: signal.signal(number, _raise) for number in (signal.SIGINT, signal.SIGTERM)}


def restore(previous: dict) -> None:
    for number, handler in previous.items():
        signal.signal(number, handler)
