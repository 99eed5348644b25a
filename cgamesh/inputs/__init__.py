"""Inputs: what a user hands cgamesh, read and validated into specs (scene files and their rendering keys).

Which file is read by which reader is the table in formats.py (suffix or probe -> reader, kind,
default unit; ``register`` for other formats); the readers are scene.py (YAML scene files),
swc.py (neuron skeletons), streamlines.py (.trk, .tck, .trx), arrays.py (.npz and arrays in
memory), each giving a Scene or a ``centerlines.Centerlines``.
"""
