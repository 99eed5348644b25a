"""Matrix products whose every row is summed the same way, however many rows there are.

BLAS multiplies a lone row by a matrix (or a vector) with a matrix-vector (or dot) kernel that
sums in another order than the kernel it uses for two rows or more, so a result computed for one
object alone differed in its last bits from the same object's row in a batch. ``rows_times``
multiplies a lone row as two rows of one broadcast array (numpy sums such an operand in its own
loop, in the order of the batched products of ``products``): one surface meshed alone then gives
the same bits as among thousands, which the batched scene pass (cgamesh.meshing.scene_batch)
relies on and tests/test_scene_batched.py checks.
"""

from __future__ import annotations

import numpy as np


def rows_times(rows: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """rows (..., P) @ matrix (P, R) or (P,), each row's sums in the same order whatever the batch."""
    rows = np.asarray(rows)
    if rows.ndim == 0 or rows.size != rows.shape[-1] or rows.size == 0:
        return rows @ matrix
    pair = np.broadcast_to(rows.reshape(1, -1), (2, rows.shape[-1])) @ matrix
    return pair[0].reshape(rows.shape[:-1] + matrix.shape[1:])
