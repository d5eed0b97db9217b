"""The skeleton: the node hierarchy with rest transforms, and the skin's bones (see ``rig.py`` for
the conventions)."""
from __future__ import annotations

from dataclasses import dataclass, fields
from functools import cached_property

import numpy as np

from .._shared.checks import item_index
from .._shared.frozen import frozen
from ..errors import InvalidInputError
from ..tolerances import tol


@dataclass(frozen=True, eq=False)
class Skeleton:
    """The node hierarchy with its rest transforms, and which nodes are the skin's bones.

    Every array is kept as a read-only copy.

    Parameters
    ----------
    names : list of str
        The j node names, unique.
    parents : (j,) int64
        Parent node index, -1 for roots; parents[i] < i.
    rest_translations : (j, 3) float64
        Local rest translation of each node.
    rest_rotations : (j, 4) float64
        Local rest rotation of each node, unit quaternions (x, y, z, w).
    rest_scales : (j, 3) float64
        Local rest scale of each node.
    rest_matrices : (j, 4, 4) float64
        Exact local rest matrices (T @ R @ S for TRS nodes).
    bone_nodes : (b,) int64
        Node index of each bone (what ``Rig.joints`` index).
    inverse_bind : (b, 4, 4) float64
        Inverse bind matrix of each bone.

    Examples
    --------
    >>> skeleton = cgaskin.capsule_arm().skeleton
    >>> skeleton.names, skeleton.parents.tolist(), skeleton.n_bones
    (['shoulder', 'elbow', 'wrist'], [-1, 0, 1], 3)
    >>> skeleton.rest_translations[1]
    array([1., 0., 0.])
    """

    names: list
    parents: np.ndarray
    rest_translations: np.ndarray
    rest_rotations: np.ndarray
    rest_scales: np.ndarray
    rest_matrices: np.ndarray
    bone_nodes: np.ndarray
    inverse_bind: np.ndarray

    def __post_init__(self):
        # read-only copies (the maker's arrays stay theirs): values derived from them are cached
        # (``inverse_bind_rows``, the rest pose of sampling), so an edit in place would leave those stale
        for name in ("parents", "rest_translations", "rest_rotations", "rest_scales", "rest_matrices",
                     "bone_nodes", "inverse_bind"):
            object.__setattr__(self, name, frozen(np.array(getattr(self, name), order="C")))

    def __reduce__(self):
        # made again through the constructor, so that an unpickled skeleton's arrays are read-only too
        return Skeleton, tuple(getattr(self, f.name) for f in fields(self))

    @property
    def n_nodes(self) -> int:
        return len(self.names)

    @property
    def n_bones(self) -> int:
        return len(self.bone_nodes)

    @cached_property
    def inverse_bind_rows(self) -> np.ndarray:
        """(b, 12) C-contiguous top 3x4 rows of the inverse bind matrices (checked affine once)."""
        ibm = np.asarray(self.inverse_bind, dtype=np.float64)
        if not np.allclose(ibm[:, 3, :], [0, 0, 0, 1], atol=tol.affine_row):
            raise InvalidInputError("inverse bind matrices must be affine (last row 0 0 0 1)")
        return np.ascontiguousarray(ibm[:, :3, :].reshape(-1, 12))

    def node_index(self, joint) -> int:
        """The index of a node given by name or index.

        Parameters
        ----------
        joint : str or int
            A node name, or an index in ``range(n_nodes)``.

        Returns
        -------
        int

        Raises
        ------
        InvalidInputError
            An unknown name (the message lists the valid ones) or an index out of range.
        """
        index = item_index(joint, self.n_nodes, "joint", f"the skeleton has {self.n_nodes} nodes")
        if index is not None:
            return index
        try:
            return self.names.index(joint)
        except ValueError:
            raise InvalidInputError(
                f"unknown joint {joint!r}; valid joints: {', '.join(map(repr, self.names))}") from None
