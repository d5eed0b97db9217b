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


def load(path, **options):
    """Load a model as a ``Rig``: .glb/.gltf natively, every other format assimp reads (.fbx, .dae, .obj,
    .stl, ...) through it; a mesh without a skin loads with its mesh nodes as rigid bones."""
    from .rigs import load as _load
    return _load(path, **options)


def save(rig, path):
    """Save a ``Rig`` as skinned glTF 2.0 (.glb or .gltf), clips included."""
    from .rigs import save as _save
    return _save(rig, path)


def capsule_arm(*args, **kwargs):
    """The built-in procedural rig (a capsule arm with a joint chain and a "wave" clip)."""
    from .rigs.procedural import capsule_arm as _capsule_arm
    return _capsule_arm(*args, **kwargs)


def show(rig, pose=None, clip=None, **options):
    """A viewer page for ``rig`` (a ``Rig`` or a model path) that a notebook shows inline and
    ``.save(path)`` writes as an offline .html file: ``cgaskin.view.show``."""
    from .view import show as _show
    return _show(rig, pose=pose, clip=clip, **options)


def __getattr__(name):
    # the plain reference implementations (test oracles, benchmark baselines): production code never
    # imports them, so they load on first use
    if name == "baselines":
        import importlib
        return importlib.import_module(".baselines", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
