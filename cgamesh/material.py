"""A surface's appearance as the scene file states it (metallic-roughness, as glTF and USD use)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Material:
    """Base colour (linear RGB, each in [0, 1]), roughness and metallic in [0, 1]."""

    color: tuple[float, float, float] = (0.8, 0.8, 0.8)
    roughness: float = 0.5
    metallic: float = 0.0
