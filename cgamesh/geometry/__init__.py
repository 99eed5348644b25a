"""Geometry: the CGA algebra, control objects, curves, the blade projection and evolved surfaces."""
