"""Exceptions raised by cgaskin.

Every error a user can trigger with bad input is one of these, so that callers can catch
``CgaskinError`` and numba never surfaces a traceback of its own.
"""

__all__ = ["CgaskinError", "FolderInUseError", "InternalError", "InvalidInputError", "KernelBuildError",
           "KernelCacheWarning", "LimitError", "ManifestWarning", "MemoryLimitError", "MissesMeshError",
           "MissingFolderError", "ModelFormatError", "ModelWarning", "NoSkinError", "OpenRimWarning",
           "PlacementWarning", "PlaneMissesMeshWarning", "ProtocolError", "StaleGeneratedError", "TearPathError",
           "TearPlacementWarning"]


class CgaskinError(Exception):
    """Base class of every error cgaskin raises on purpose.

    Examples
    --------
    >>> try:
    ...     cgaskin.versor.dilator(0.0)
    ... except cgaskin.CgaskinError as error:
    ...     print(type(error).__name__)
    InvalidInputError
    """


class InvalidInputError(CgaskinError, ValueError):
    """An argument has the wrong shape, dtype or value (NaN, infinite, out of range).

    Examples
    --------
    >>> try:
    ...     cgaskin.versor.rotor([0, 0, 0], 1.0)
    ... except cgaskin.InvalidInputError as error:
    ...     print(error)
    axis has zero length: a rotation needs a direction
    """


class ModelFormatError(CgaskinError, ValueError):
    """A model file is malformed, truncated, or uses something the loader cannot read.

    Examples
    --------
    >>> with open("broken.glb", "wb") as file:
    ...     _ = file.write(b"not a model")
    >>> try:
    ...     cgaskin.load("broken.glb")
    ... except cgaskin.ModelFormatError as error:
    ...     print(error)
    broken.glb: the glTF JSON is malformed: ...
    """


class NoSkinError(ModelFormatError):
    """A model file holds no skinned mesh.

    Examples
    --------
    >>> with open("empty.gltf", "w") as file:
    ...     _ = file.write('{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{}]}')
    >>> try:
    ...     cgaskin.load("empty.gltf")
    ... except cgaskin.NoSkinError as error:
    ...     print(error)
    empty.gltf: holds no mesh (no node of its scene has one): nothing to load
    """


class MemoryLimitError(InvalidInputError, MemoryError):
    """What was asked for would need more memory than the machine has available (or than the limit
    given, ``--max-memory``): refused before any of it is allocated. The message names the size asked
    for (``--frames 100000000``, ``times``, ``operations[0].count``), the estimate and the memory there
    is. A ``MemoryError`` too, so that code catching numpy's catches it.

    Examples
    --------
    >>> times = np.broadcast_to(0.0, (10**11,))                 # 1e11 times, without their memory
    >>> try:
    ...     cgaskin.capsule_arm().poses("wave", times)
    ... except MemoryError as error:
    ...     print(error)
    times (100000000000 poses of 3 joints) would take about 62.1 TiB of memory, more than the ...
    """


class MissingFolderError(CgaskinError, FileNotFoundError):
    """A file cannot be written because the folder it goes into does not exist: the message names the
    folder (cgaskin makes no folders a caller did not ask for). A ``FileNotFoundError`` (an ``OSError``)
    too, as Python's own ``open`` raises there.

    Examples
    --------
    >>> try:
    ...     cgaskin.save(cgaskin.capsule_arm(), "no/such/folder/arm.glb")
    ... except FileNotFoundError as error:
    ...     print(type(error).__name__, "-", error)
    MissingFolderError - cannot write arm.glb: no/such/folder: no such folder; make it first ...
    """


class FolderInUseError(CgaskinError):
    """Another ``cgaskin batch`` run holds the batch folder (its lock file): two runs on one folder would
    delete each other's files in flight. The message names the folder and the other run's process.

    Examples
    --------
    >>> try:
    ...     raise cgaskin.errors.FolderInUseError("out/: in use by cgaskin batch (pid 4242)")
    ... except cgaskin.CgaskinError as error:
    ...     print(error)
    out/: in use by cgaskin batch (pid 4242)
    """


class MissesMeshError(CgaskinError, ValueError):
    """A cutting plane, a scalpel or a drill bit does not meet the mesh.

    Examples
    --------
    >>> try:
    ...     cgaskin.drill(cgaskin.capsule_arm(), [0, 5, 0], [1, 5, 0], 0.1)    # 5 above the arm
    ... except cgaskin.MissesMeshError as error:
    ...     print(error)
    the bit (radius 0.1 around [0.0, 5.0, 0.0] -> [1.0, 5.0, 0.0]) does not reach into the mesh of 'capsule_arm'
    """


class TearPathError(CgaskinError, ValueError):
    """The tear plane's section of the surface does not lead from S_i to S_{i+1} (they lie on
    different pieces of it, or a boundary of the mesh is in the way).

    Examples
    --------
    >>> issubclass(cgaskin.TearPathError, ValueError)
    True
    """


class ProtocolError(InvalidInputError):
    """A message to ``cgaskin serve`` that is not a valid request; ``id`` is its id when that much could
    be read (the reply names it).

    Examples
    --------
    >>> from cgaskin.serve import Tab
    >>> print(Tab(cgaskin.capsule_arm()).handle('{"op": "fly", "id": 7}'))
    {"id":7,"ok":false,"error":"op 'fly': the operations are hello, ...","kind":"ProtocolError"}
    """

    def __init__(self, message: str, id=None):
        super().__init__(message)
        self.id = id


class LimitError(InvalidInputError):
    """An operation that a ``cgaskin serve``'s ``Limits`` do not grant (too large, or the session at its
    size); the session is unchanged.

    Examples
    --------
    >>> from cgaskin.serve import Limits, Tab
    >>> tab = Tab(cgaskin.capsule_arm(), Limits(max_vertices=690))      # the arm has 690 already
    >>> print(tab.handle('{"op": "cut", "id": 1, "normal": [1, 0, 0], "point": [1.5, 0, 0]}'))
    {"id":1,"ok":false,"error":"this tab's mesh holds 690 vertices, ...","kind":"LimitError"}
    """


class InternalError(CgaskinError, RuntimeError):
    """A bug in cgaskin, not bad input: please report it with the inputs (the model and the call).

    Examples
    --------
    >>> issubclass(cgaskin.errors.InternalError, RuntimeError)
    True
    """


class StaleGeneratedError(CgaskinError):
    """``generated/`` does not match what ``codegen/`` emits now.

    Examples
    --------
    >>> issubclass(cgaskin.errors.StaleGeneratedError, cgaskin.CgaskinError)
    True
    """


class KernelBuildError(CgaskinError):
    """``cgaskin build --kernels`` could not build the shipped kernels: one did not compile, or one
    links code from a module its key does not cover.

    Examples
    --------
    >>> issubclass(cgaskin.errors.KernelBuildError, cgaskin.CgaskinError)
    True
    """


class PlacementWarning(RuntimeWarning):
    """A new vertex made on a posed mesh (a posed cut or tear) could not be placed exactly on its
    posed target: its blended transform is singular or nearly so.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("error", cgaskin.PlacementWarning)    # refuse inexact placements
    ...     halves = cgaskin.cut(cgaskin.capsule_arm(), [1, 0, 0], [1.5, 0, 0])
    >>> len(halves)
    2
    """


#: the tear's name for it (``cgaskin.TearPlacementWarning``)
TearPlacementWarning = PlacementWarning


class OpenRimWarning(UserWarning):
    """A drill with ``wall=True`` met an open boundary of the mesh: a rim that runs into it is a chain,
    not a loop, and the hole gets no wall there (``DrillResult.open_rims``).

    Examples
    --------
    >>> issubclass(cgaskin.OpenRimWarning, UserWarning)        # shown once per place, by default
    True
    """


class ModelWarning(UserWarning):
    """A model's data was repaired or partly left out where cgaskin read, checked or wrote it: weights
    renormalised, influences beyond four dropped, attributes glTF does not define ignored, an
    unreadable clip or a non-triangle primitive skipped (loaders and ``cgaskin.Rig``), or something
    glTF cannot hold as given written another way (``save``). The message names the file or rig.

    Examples
    --------
    >>> import warnings
    >>> arm = cgaskin.capsule_arm()
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     rig = cgaskin.Rig(arm.vertices, arm.faces, arm.joints, arm.weights * 2, arm.skeleton)
    >>> [warning.category.__name__ for warning in caught]
    ['ModelWarning']
    """


class ManifestWarning(RuntimeWarning):
    """A batch folder's manifest could not be read: every item is made again.

    Examples
    --------
    >>> issubclass(cgaskin.errors.ManifestWarning, RuntimeWarning)
    True
    """


class KernelCacheWarning(RuntimeWarning):
    """numba's on-disk cache of cgaskin's kernels cannot be used (unreadable, or this numba lacks what
    cgaskin keys it with): the kernels compile again; nothing else changes.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", cgaskin.errors.KernelCacheWarning)  # compiling again is fine
    ...     pose = cgaskin.capsule_arm().pose("wave", 0.5)
    """


class PlaneMissesMeshWarning(UserWarning):
    """The cutting plane does not cross the mesh: one half is empty.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     positive, negative = cgaskin.cut(cgaskin.capsule_arm(), [0, 0, 1], [0, 0, 5])
    >>> caught[0].category.__name__, positive.n_vertices, negative.n_vertices
    ('PlaneMissesMeshWarning', 0, 690)
    """
