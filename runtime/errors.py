"""Exceptions raised by cgaskin.

Every error a user can trigger with bad input is one of these, so that callers can catch
``CgaskinError`` and numba never surfaces a traceback of its own.
"""


class CgaskinError(Exception):
    """Base class of every error cgaskin raises on purpose."""


class InvalidInputError(CgaskinError, ValueError):
    """An argument has the wrong shape, dtype or value (NaN, infinite, out of range)."""


class ModelFormatError(CgaskinError, ValueError):
    """A model file is malformed, truncated, or uses something the loader cannot read."""


class NoSkinError(ModelFormatError):
    """A model file holds no skinned mesh."""


class MemoryLimitError(InvalidInputError, MemoryError):
    """What was asked for would need more memory than the machine has available (or than the limit
    given, ``--max-memory``): refused before any of it is allocated. The message names the size asked
    for (``--frames 100000000``, ``times``, ``operations[0].count``), the estimate and the memory there
    is. A ``MemoryError`` too, so that code catching numpy's catches it."""


class MissingFolderError(CgaskinError, FileNotFoundError):
    """A file cannot be written because the folder it goes into does not exist: the message names the
    folder (cgaskin makes no folders a caller did not ask for). A ``FileNotFoundError`` (an ``OSError``)
    too, as Python's own ``open`` raises there."""


class FolderInUseError(CgaskinError):
    """Another ``cgaskin batch`` run holds the batch folder (its lock file): two runs on one folder would
    delete each other's files in flight. The message names the folder and the other run's process."""


class MissesMeshError(CgaskinError, ValueError):
    """A cutting plane, a scalpel or a drill bit does not meet the mesh."""


class TearPathError(CgaskinError, ValueError):
    """The tear plane's section of the surface does not lead from S_i to S_{i+1} (they lie on
    different pieces of it, or a boundary of the mesh is in the way)."""


class ProtocolError(InvalidInputError):
    """A message to ``cgaskin serve`` that is not a valid request; ``id`` is its id when that much could
    be read (the reply names it)."""

    def __init__(self, message: str, id=None):
        super().__init__(message)
        self.id = id


class LimitError(InvalidInputError):
    """An operation that a ``cgaskin serve``'s ``Limits`` do not grant (too large, or the session at its
    size); the session is unchanged."""


class InternalError(CgaskinError, RuntimeError):
    """A bug in cgaskin, not bad input: please report it with the inputs (the model and the call)."""


class StaleGeneratedError(CgaskinError):
    """``generated/`` does not match what ``codegen/`` emits now."""


class KernelBuildError(CgaskinError):
    """``cgaskin build --kernels`` could not build the shipped kernels: one did not compile, or one
    links code from a module its key does not cover."""


class PlacementWarning(RuntimeWarning):
    """A new vertex made on a posed mesh (a posed cut or tear) could not be placed exactly on its
    posed target: its blended transform is singular or nearly so."""


#: the tear's name for it (``cgaskin.TearPlacementWarning``)
TearPlacementWarning = PlacementWarning


class OpenRimWarning(UserWarning):
    """A drill with ``wall=True`` met an open boundary of the mesh: a rim that runs into it is a chain,
    not a loop, and the hole gets no wall there (``DrillResult.open_rims``)."""


class ModelWarning(UserWarning):
    """A model's data was repaired or partly left out where cgaskin read, checked or wrote it: weights
    renormalised, influences beyond four dropped, attributes glTF does not define ignored, an
    unreadable clip or a non-triangle primitive skipped (loaders and ``cgaskin.Rig``), or something
    glTF cannot hold as given written another way (``save``). The message names the file or rig."""


class ManifestWarning(RuntimeWarning):
    """A batch folder's manifest could not be read: every item is made again."""


class KernelCacheWarning(RuntimeWarning):
    """numba's on-disk cache of cgaskin's kernels cannot be used (unreadable, or this numba lacks what
    cgaskin keys it with): the kernels compile again; nothing else changes."""


class PlaneMissesMeshWarning(UserWarning):
    """The cutting plane does not cross the mesh: one half is empty."""
