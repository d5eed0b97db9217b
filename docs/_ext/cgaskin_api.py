"""The public API the reference documents, and the reference's module pages written from it.

One definition of "public" serves the Sphinx build and ``tests/docs/test_inventory.py``: a module's
``__all__`` where it has one, else every attribute whose name does not start with ``_`` and that is
not a module (every module of the reference has an ``__all__`` now). Each module's page lists its
names under headings (``SECTIONS``); a name no heading claims goes under a heading of its kind
(functions, classes, exceptions, warnings, data), so a name added to the package shows up in the
reference without an edit here, and a heading naming a name that is no longer public fails the build.
"""
from __future__ import annotations

import importlib
import inspect
import types
from pathlib import Path

#: the modules of the reference, in the order of its index
MODULES = ("cgaskin", "cgaskin.versor", "cgaskin.errors", "cgaskin.codegen", "cgaskin.batch", "cgaskin.view",
           "cgaskin.serve", "cgaskin.tolerances")

#: one line under each module page's title
SUMMARIES = {
    "cgaskin": "Models, poses, skinning and surgery: what ``import cgaskin`` gives.",
    "cgaskin.versor": "Versors of CGA as float64 arrays: rotation, translation and uniform scale in one algebra.",
    "cgaskin.errors": "Every exception and warning cgaskin raises (the names at ``cgaskin.*`` are the same classes).",
    "cgaskin.codegen": "The kernel language and the build step that turns kernels into numba, C, GLSL, WGSL, "
                       "CUDA and JavaScript.",
    "cgaskin.batch": "Datasets of posed, cut, torn and drilled rigs, made on Dask (``cgaskin batch``).",
    "cgaskin.view": "The viewer: one self-contained HTML page that plays a rig (``cgaskin view``, "
                    "``cgaskin.show``).",
    "cgaskin.serve": "A local page where a user cuts, tears and drills a playing model (``cgaskin serve``).",
    "cgaskin.tolerances": "The one frozen object of relative tolerances.",
}

#: headings of a module's page and the names under them, in order
SECTIONS = {
    "cgaskin": [
        ("Models", ["load", "save", "capsule_arm", "Rig", "Skeleton", "Clip", "Channel", "check_mesh"]),
        ("Poses and clips", ["Pose", "Poses", "clip_from_poses"]),
        ("Skinning", ["skin", "skin_vertices", "skin_affine", "skin_normals"]),
        ("Surgery", ["cut", "cut_details", "tear", "tear_stroke", "drill", "drill_details", "Surgery",
                     "OperationCost", "CutResult", "TearResult", "StrokeResult", "DrillResult"]),
        ("Surface queries", ["Topology", "rig_topology", "TriangleBVH"]),
        ("Viewing", ["show"]),
        ("Compiled kernels", ["precompile"]),
    ],
    "cgaskin.versor": [
        ("Making versors", ["identity", "translator", "rotor", "rotor_from_quaternion", "dilator", "motor",
                            "from_matrix"]),
        ("Products and their inverses", ["compose", "reverse", "inverse", "normalise", "apply"]),
        ("Matrices", ["to_matrix", "to_affine"]),
        ("Logarithm, exponential and blending", ["log", "exp", "blend_linear", "blend_log"]),
        ("The clifford package", ["to_clifford", "from_clifford"]),
        ("Checks and layouts", ["is_versor", "VERSOR_BLADES", "LOG_BLADES"]),
    ],
    "cgaskin.codegen": [
        ("The kernel language", ["kernel", "cga", "pga", "KernelSpec", "ConformalAlgebra", "ProjectiveAlgebra"]),
        ("Building and verifying", ["build_catalogue", "verify_catalogue", "CodegenError"]),
        ("Algebras as data", ["Algebra", "InvalidAlgebraError"]),
    ],
    "cgaskin.batch": [
        ("Running a batch", ["run", "Manifest", "Row", "read_manifest"]),
        ("Specs and items", ["load_spec", "parse_spec", "Spec", "expand", "Item"]),
    ],
}

#: headings of the names no section claims, by kind
KIND_HEADINGS = {"function": "Functions", "class": "Classes", "exception": "Exceptions",
                 "warning": "Warnings", "data": "Data"}


def import_module(name: str) -> types.ModuleType:
    return importlib.import_module(name)


def public_names(module_name: str) -> list[str]:
    """The public names of ``module_name``: its ``__all__``, else its attributes that are neither
    private nor modules (sorted)."""
    module = import_module(module_name)
    names = getattr(module, "__all__", None)
    if names is not None:
        return list(names)
    return sorted(name for name, value in vars(module).items()
                  if not name.startswith("_") and not isinstance(value, types.ModuleType))


def kind(obj) -> str:
    """function, class, exception, warning or data: the heading an unclaimed name goes under."""
    if inspect.isclass(obj):
        if issubclass(obj, Warning):
            return "warning"
        return "exception" if issubclass(obj, BaseException) else "class"
    if callable(obj):
        return "function"
    return "data"


def sections(module_name: str) -> list[tuple[str, list[str]]]:
    """Headings and names of a module's page: every public name exactly once.

    Raises ValueError naming a heading's name that is not public (the page would document a name
    the package no longer has)."""
    module = import_module(module_name)
    names = public_names(module_name)
    claimed = [(title, list(listed)) for title, listed in SECTIONS.get(module_name, [])]
    stale = [n for _, listed in claimed for n in listed if n not in names]
    if stale:
        raise ValueError(f"docs/_ext/cgaskin_api.py SECTIONS[{module_name!r}] names {stale}, which "
                         f"{module_name} does not export: remove them")
    taken = {n for _, listed in claimed for n in listed}
    rest: dict[str, list[str]] = {}
    for name in names:
        if name not in taken:
            rest.setdefault(kind(getattr(module, name)), []).append(name)
    return claimed + [(KIND_HEADINGS[k], rest[k]) for k in KIND_HEADINGS if k in rest]


def page(module_name: str) -> str:
    """The reST of a module's reference page: its docstring, then an autosummary per heading."""
    title = f"``{module_name}``"
    lines = [title, "=" * len(title), "", SUMMARIES.get(module_name, ""), "",
             f".. automodule:: {module_name}", "   :no-members:", "",
             f".. currentmodule:: {module_name}", ""]
    for heading, names in sections(module_name):
        lines += [heading, "-" * len(heading), "", ".. autosummary::", "   :toctree: generated/",
                  "   :nosignatures:", ""]
        lines += [f"   {name}" for name in names] + [""]
    return "\n".join(lines)


def write_pages(api_dir: Path) -> list[Path]:
    """Write ``api_dir/<module>.rst`` for every module of the reference (only when its text changed,
    so that Sphinx rebuilds nothing it need not); returns the paths."""
    api_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for module_name in MODULES:
        path = api_dir / f"{module_name}.rst"
        text = page(module_name)
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
        written.append(path)
    return written


def expected_inventory() -> set[str]:
    """The names the built ``objects.inv`` must hold at module level: every module, and every public
    name of it as ``module.name``."""
    names = set(MODULES)
    for module_name in MODULES:
        names.update(f"{module_name}.{name}" for name in public_names(module_name))
    return names


def _config_inited(app, config):
    write_pages(Path(app.srcdir) / "api")


def setup(app):
    # before Sphinx lists the source files (and autosummary reads the pages to write its stubs)
    app.connect("config-inited", _config_inited)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
