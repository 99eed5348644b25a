"""The motions of many open Catmull-Rom chains at once: ``geometry.motors.Motions``, kept under
the names the batched centreline pass (chains.py, rings.py) calls."""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.motors import MotionNodes, Motions, MotionState

ChainNodes = MotionNodes  # kept for chains.py: the nodes of every chain (all open)


class ChainMotions(Motions):
    """Kept for chains.py and rings.py: ``Motions`` of open catmull_rom chains, evaluated by span."""

    @classmethod
    def through(cls, centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, nodes: MotionNodes) -> "ChainMotions":
        return super().through(centre, normal, radius, nodes, "catmull_rom")

    def evaluate(self, span: np.ndarray, s: np.ndarray) -> MotionState:
        """The motion state at local parameters s (A,) of global spans (A,): ``Motions.span_state``."""
        return self.span_state(span, s)
