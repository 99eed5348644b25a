"""What every writer is told besides the meshes: one frozen value, ``WriteOptions``.

Every writer of the table in registry.py is called as ``write(path, surfaces, options)``. The
part every format shares (the frame and unit of the coordinates) sits at the top level; what
only one format reads sits in that format's own part (``options.gltf``), read by that writer
alone, so a glTF-only option never passes through the USD or OBJ writers' signatures.

To add a writer option: a field in the format's part here (with its default), read in that
format's writer; if the command line sets it, an Option in cgamesh.options with ``writes`` naming
the part (docs/architecture.md, "Input formats and options").
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class GltfOptions:
    """Options of the glTF writer (.glb, .gltf) only.

    tangents: write a TANGENT attribute (VEC4, w = +-1), so normal maps work.
    quantize: store positions, normals and UVs in 16 / 8 bits (KHR_mesh_quantization).
    """

    tangents: bool = False
    quantize: bool = False

    @classmethod
    def from_options(cls, values) -> GltfOptions:
        """The glTF options of ``values`` (a mapping by the names of the table in
        cgamesh.options: those with ``writes="gltf"``) that were given; the defaults else."""
        from cgamesh.options import for_writer

        return cls(**for_writer(values, "gltf"))


@dataclass(frozen=True)
class WriteOptions:
    """How to place the meshes in any output file.

    up:              the up axis of the meshes' coordinates, "z" or "y" (glTF is +Y up: a
                     z-up input is turned; USD records it).
    meters_per_unit: the length of the coordinates' unit in metres (> 0, finite).
    source_units:    that unit's name, recorded in the file ("m", "um", ...).
    gltf:            the glTF writer's own options.
    """

    up: str = "z"
    meters_per_unit: float = 1.0
    source_units: str = "m"
    gltf: GltfOptions = field(default_factory=GltfOptions)
