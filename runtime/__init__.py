"""cgaskin: deform, cut and tear skinned characters with Conformal Geometric Algebra.

The runtime calls only the kernels in ``cgaskin.generated`` (emitted by ``cgaskin build``).
"""
import sys as _sys

from ._shared import version as _version
from ._shared.jit import cache_generated as _cache_generated
from .generated import kernels as _kernels, skinning as _skinning

_cache_generated(_kernels, _skinning)         # before anything compiles: they load the shipped kernels

from .errors import (CgaskinError, InvalidInputError, MemoryLimitError, MissesMeshError, MissingFolderError,
                     ModelFormatError, ModelWarning, NoSkinError, OpenRimWarning, PlacementWarning)
from .algebra import versor
from .animation.pose import Pose, clip_from_poses
from .animation.poses import Poses
from .animation.rig import Channel, Clip, Rig, Skeleton
from .animation.skinning import skin, skin_affine, skin_normals, skin_vertices
from .animation.validate import check_mesh
from .surgery.bvh import TriangleBVH
from .surgery.cut import CutResult, PlaneMissesMeshWarning, cut, cut_details
from .surgery.drill import DrillResult, drill, drill_details
from .surgery.tear import StrokeResult, TearPathError, TearPlacementWarning, TearResult, tear, tear_stroke
from .surgery.topology import Topology, rig_topology
from .surgery.session import OperationCost, Surgery
from .app.precompile import precompile

_sys.modules[__name__ + ".versor"] = versor      # `import cgaskin.versor` as before the move

__version__ = _version.VERSION

__all__ = ["CgaskinError", "Channel", "Clip", "CutResult", "DrillResult", "InvalidInputError", "MemoryLimitError",
           "MissesMeshError", "MissingFolderError", "ModelFormatError", "ModelWarning", "NoSkinError",
           "OpenRimWarning", "OperationCost", "PlacementWarning", "PlaneMissesMeshWarning", "Pose", "Poses", "Rig",
           "Skeleton", "StrokeResult", "Surgery", "TearPathError", "TearPlacementWarning", "TearResult", "Topology",
           "TriangleBVH", "capsule_arm", "check_mesh", "clip_from_poses", "cut", "cut_details", "drill",
           "drill_details", "load", "precompile", "rig_topology", "save", "show", "skin", "skin_affine",
           "skin_normals", "skin_vertices", "tear", "tear_stroke"]


def load(path, **options):
    """Load a model file as a ``Rig``.

    .glb/.gltf are read natively, every other format assimp reads (.fbx, .dae, .obj, .stl, ...)
    through it; a mesh without a skin loads with its mesh nodes as rigid bones.

    Parameters
    ----------
    path : str or os.PathLike
        The model file; its extension picks the reader.
    **options
        Passed to the reader (glTF takes none; assimp: ``timeout``, ``executable``).

    Returns
    -------
    Rig
        The model's mesh, skin, skeleton and clips.

    Raises
    ------
    ModelFormatError
        A malformed file, or a format nothing installed reads (``NoSkinError``: no mesh at all).

    Examples
    --------
    >>> cgaskin.save(cgaskin.capsule_arm(), "arm.glb")
    PosixPath('arm.glb')
    >>> rig = cgaskin.load("arm.glb")
    >>> rig.vertices.shape, [clip.name for clip in rig.clips]
    ((690, 3), ['wave'])
    """
    from .rigs import load as _load
    return _load(path, **options)


def save(rig, path):
    """Save a ``Rig`` as a skinned glTF 2.0 file, its clips included.

    Parameters
    ----------
    rig : Rig
        The model to write.
    path : str or os.PathLike
        The file: .glb (binary) or .gltf (JSON with the buffers embedded).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    MissingFolderError
        The folder of ``path`` does not exist.

    Examples
    --------
    >>> cgaskin.save(cgaskin.capsule_arm(), "arm.glb")
    PosixPath('arm.glb')
    """
    from .rigs import save as _save
    return _save(rig, path)


def capsule_arm(*args, **kwargs):
    """The built-in procedural rig: a capsule arm on a chain of joints, with a "wave" clip.

    Parameters
    ----------
    *args, **kwargs
        ``n_joints=3, length=3.0, radius=0.25, rings_per_segment=12, segments_around=16``: the
        capsule along +x from 0 to ``length``, its joints evenly spaced along it
        (``cgaskin.rigs.procedural.capsule_arm``).

    Returns
    -------
    Rig
        A closed manifold mesh (690 vertices for the defaults) skinned to "shoulder", "elbow" and
        "wrist" (for three joints), unit normals in ``attributes["NORMAL"]``.

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> arm.vertices.shape, arm.faces.shape, arm.skeleton.names
    ((690, 3), (1376, 3), ['shoulder', 'elbow', 'wrist'])
    >>> cgaskin.capsule_arm(n_joints=5).skeleton.names[-1]
    'joint4'
    """
    from .rigs.procedural import capsule_arm as _capsule_arm
    return _capsule_arm(*args, **kwargs)


def show(rig, pose=None, clip=None, **options):
    """A viewer page for a rig: shown inline by a notebook, or saved as an offline .html file.

    Parameters
    ----------
    rig : Rig or str or os.PathLike
        The model, or a model file.
    pose : Pose, optional
        A pose of the rig to show, paused (not with ``clip``).
    clip : str or int, optional
        The clip to start with (default: the first).
    **options
        ``play``, ``time``, ``height``, ``skinning``: see ``cgaskin.view.show``.

    Returns
    -------
    cgaskin.view.View
        The page; ``.save(path)`` writes it.

    Examples
    --------
    >>> view = cgaskin.show(cgaskin.capsule_arm(), clip="wave")
    >>> view.save("arm.html")
    PosixPath('arm.html')
    """
    from .view import show as _show
    return _show(rig, pose=pose, clip=clip, **options)


def __getattr__(name):
    # the plain reference implementations (test oracles, benchmark baselines): production code never
    # imports them, so they load on first use
    if name == "baselines":
        import importlib
        return importlib.import_module(".baselines", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
