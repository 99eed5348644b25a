"""A skeleton (points with parents) split into unbranched chains that meet at junction nodes.

A chain runs from a node where the tree branches or starts (a root, or a node with two or more
children) down through nodes with exactly one child to the next such node or a leaf; it
includes that first node, so a child chain starts exactly on its parent's node and tubes meet
there without a gap. Junctions are the nodes with two or more children (where two or more
chains meet, also a root with two children); each is closed by a sphere of its radius.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Chains:
    """Unbranched chains of a tree, as one flat index array.

    nodes:     (L,) int64 node indices of every chain, chain after chain, root side first.
    offsets:   (M + 1,) int64 boundaries of the M chains in ``nodes``.
    junctions: (J,) int64 nodes with two or more children.
    """

    nodes: np.ndarray
    offsets: np.ndarray
    junctions: np.ndarray

    def __len__(self) -> int:
        return len(self.offsets) - 1

    def chain(self, i: int) -> np.ndarray:
        return self.nodes[self.offsets[i]: self.offsets[i + 1]]


def split_tree(parents: np.ndarray) -> Chains:
    """The chains and junctions of the tree ``parents`` ((N,) parent index, -1 for a root).

    The parents must form a forest (the readers refuse cycles). A root with no children is a
    lone point and belongs to no chain.
    """
    parents = np.asarray(parents, dtype=np.int64)
    n = len(parents)
    has_parent = parents >= 0
    children = np.bincount(parents[has_parent], minlength=n)
    # A chain starts at each child of a node that is a root or a junction: (start node, first child).
    starts_below = np.flatnonzero(has_parent)
    starts_below = starts_below[(parents[starts_below] >= 0)]
    head = parents[starts_below]
    opens = (parents[head] < 0) | (children[head] != 1)
    first_child = starts_below[opens]
    nodes, lengths = _members(parents, first_child)
    offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
    junctions = np.flatnonzero(children >= 2).astype(np.int64)
    return Chains(nodes=nodes, offsets=offsets, junctions=junctions)


def unrooted(parents: np.ndarray) -> np.ndarray:
    """Indices of the nodes from which following parents never reaches a root (on or below a cycle).

    Pointer jumping: after k rounds each node holds its 2^k-th ancestor (roots their own), so
    log2(N) array rounds take every node of a tree to its root, without a walk per node.
    """
    parents = np.asarray(parents, dtype=np.int64)
    ancestor = np.where(parents < 0, np.arange(len(parents)), parents)
    for _ in range(int(np.ceil(np.log2(len(parents) + 1))) + 1):
        ancestor = ancestor[ancestor]
    return np.flatnonzero(parents[ancestor] >= 0)


def _members(parents: np.ndarray, firsts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every chain [head, first, ...] in order, and the chains' lengths.

    Each node that has a parent belongs to exactly one chain, the one of the nearest chain
    start at or above it; pointer jumping finds that start and the distance to it for all
    nodes in log2(N) array rounds (no walk per node, whatever the chains' lengths).
    """
    n = len(parents)
    index = np.arange(n)
    is_first = np.zeros(n, dtype=bool)
    is_first[firsts] = True
    member = parents >= 0
    pointer = np.where(is_first | ~member, index, parents)
    distance = np.where(is_first | ~member, 0, 1)
    for _ in range(int(np.ceil(np.log2(n + 1))) + 1):
        distance = distance + distance[pointer]
        pointer = pointer[pointer]
    chain_of_first = np.full(n, -1, dtype=np.int64)
    chain_of_first[firsts] = np.arange(len(firsts))
    members = np.flatnonzero(member)
    chain = chain_of_first[pointer[members]]
    order = np.lexsort((distance[members], chain))
    lengths = np.bincount(chain, minlength=len(firsts)) + 1  # + the head
    nodes = np.empty(int(lengths.sum()), dtype=np.int64)
    begin = np.cumsum(lengths) - lengths
    nodes[begin] = parents[firsts]
    body = np.ones(len(nodes), dtype=bool)
    body[begin] = False
    nodes[body] = members[order]
    return nodes, lengths
