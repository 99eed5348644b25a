"""Readers of exported files (glTF, USD, OBJ, PLY, STL) as meshes, for the quality report and checks."""
