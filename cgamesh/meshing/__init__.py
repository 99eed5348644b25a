"""Meshing: rings by TRS stepping, analytic normals, ribbons, UVs, tolerance-driven tessellation, welding."""
