"""The batch spec: a TOML file read into frozen records, every mistake an ``InvalidInputError`` that
names the file and the key (``operations[1].kind``).

A spec (the README's "Datasets: cgaskin batch" lists every key)::

    seed = 7
    [[models]]
    path = "models/*.glb"          # relative to the spec's folder (globs allowed) or absolute
    [[poses]]
    clip = "Walk"                  # a clip name or index, with times in seconds; or rest = true
    times = [0.0, 0.5]
    edits = { dilate = { joint = "b_Head_05", range = [0.8, 1.5] } }
    [[operations]]
    kind = "cut"                   # cut | tear | drill | none
    count = 3

Defaults are filled in here (an operation's parameters all appear in its record), so an item's id,
which hashes the record, changes when a default changes and the output would.
"""
from __future__ import annotations

import glob
import math
from dataclasses import dataclass
from pathlib import Path

from ..errors import InvalidInputError, ModelFormatError
from ..rigs._model_file import check_model_file

try:                                    # Python 3.11+: the standard library reads TOML
    import tomllib
except ImportError:                     # pragma: no cover (3.10: the [batch] extra installs tomli)
    import tomli as tomllib

__all__ = ["Spec", "ModelEntry", "PoseEntry", "EditEntry", "OperationEntry", "load_spec", "parse_spec",
           "OPERATIONS", "EDITS"]

#: per operation kind: its parameters and their defaults. Lengths are fractions of the posed mesh's
#: bounding-box diagonal in the item's pose (one spec fits models of any unit); a number or a
#: [low, high] range drawn uniformly per item.
OPERATIONS = {
    "cut": {"cap": False},
    "tear": {"length": 0.1, "opening": 0.0},
    "drill": {"radius": 0.03, "depth": 0.15, "wall": True},
    "none": {},
}
#: edit kinds, in the order they apply after the clip: dilate (a scale factor), rotate (degrees about
#: ``axis`` in the parent's frame, a random axis when none is given)
EDITS = ("dilate", "rotate")
_RANGES = {"length", "opening", "radius", "depth"}
_TOP = {"seed", "models", "poses", "operations"}


@dataclass(frozen=True)
class ModelEntry:
    """One model file: ``path`` absolute, ``name`` as the spec's folder sees it (the manifest's
    ``model``), ``key`` the spec key that gave it (``models[0].path``)."""

    path: str
    name: str
    key: str


@dataclass(frozen=True)
class EditEntry:
    """A random pose edit: ``kind`` in EDITS, ``joint`` a node name or index, ``range`` (low, high)
    the interval its value is drawn from, ``axis`` (3,) for rotate (None: random)."""

    kind: str
    joint: str | int
    range: tuple
    axis: tuple | None = None


@dataclass(frozen=True)
class PoseEntry:
    """A [[poses]] table: ``clip`` (name or index; None for the rest pose) at each of ``times``
    (``(None,)`` for the rest pose), then ``edits`` in order, drawn per item: many poses, not one
    (the spec's tables are ``*Entry`` records; ``serve.protocol.PoseSpec`` is one pose a page showed)."""

    clip: str | int | None
    times: tuple
    edits: tuple


@dataclass(frozen=True)
class OperationEntry:
    """An operation entry: ``kind``, ``count`` random instances, ``params`` ((name, value), ...)
    sorted by name with every default filled in; a range is a (low, high) tuple."""

    kind: str
    count: int
    params: tuple


@dataclass(frozen=True)
class Spec:
    """A validated spec: what ``load_spec`` and ``parse_spec`` return, with every default filled in.

    Parameters
    ----------
    seed : int
        The batch's seed (each item's generator hashes it in).
    models : tuple of ModelEntry
        The model files, globs expanded.
    poses : tuple of PoseEntry
        Clips and times (or the rest pose), with random edits.
    operations : tuple of OperationEntry
        What is done to each posed model, with its parameters.
    folder : str
        Where relative model paths were resolved.
    source : str, optional
        The spec's file name, in messages.

    Examples
    --------
    >>> spec = cgaskin.batch.parse_spec({"seed": 3, "models": [{"path": "arm.glb"}]}, folder=".")
    >>> spec.seed, spec.poses[0].clip, spec.operations[0].kind           # rest pose, no operation
    (3, None, 'none')
    """

    seed: int
    models: tuple
    poses: tuple
    operations: tuple
    folder: str
    source: str = "<spec>"


def load_spec(path) -> Spec:
    """Read and validate a batch spec file (TOML); model paths resolve from its folder.

    Parameters
    ----------
    path : str or os.PathLike
        The spec file.

    Returns
    -------
    Spec

    Raises
    ------
    InvalidInputError
        A file that cannot be read, is not TOML, or has a bad key (the message names the key).

    Examples
    --------
    >>> cgaskin.save(cgaskin.capsule_arm(), "arm.glb")
    PosixPath('arm.glb')
    >>> with open("spec.toml", "w") as file:
    ...     _ = file.write('''
    ... seed = 7
    ... [[models]]
    ... path = "arm.glb"
    ... [[poses]]
    ... clip = "wave"
    ... times = [0.0, 0.5]
    ... [[operations]]
    ... kind = "cut"
    ... count = 2
    ... ''')
    >>> spec = cgaskin.batch.load_spec("spec.toml")
    >>> spec.seed, spec.poses[0].times, spec.operations[0].params
    (7, (0.0, 0.5), (('cap', False),))
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise InvalidInputError(f"{path}: cannot read the spec ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise InvalidInputError(f"{path}: the spec is not UTF-8 text") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InvalidInputError(f"{path}: not valid TOML: {exc}") from None
    return parse_spec(data, path.resolve().parent, source=str(path))


def parse_spec(data: dict, folder, source: str = "<spec>") -> Spec:
    """Validate a spec already parsed from TOML (a dict), filling in every default.

    Parameters
    ----------
    data : dict
        The spec's tables: seed, models, poses, operations.
    folder : str or os.PathLike
        Where relative model paths and globs resolve from.
    source : str, optional
        The spec's name in messages.

    Returns
    -------
    Spec

    Raises
    ------
    InvalidInputError
        A bad key or value, named (``operations[1].kind``).

    Examples
    --------
    >>> try:
    ...     cgaskin.batch.parse_spec({"models": [{"path": "arm.glb"}], "sed": 1}, folder=".")
    ... except cgaskin.InvalidInputError as error:
    ...     print(error)
    <spec>: sed: unknown key; a spec has models, operations, poses, seed
    """
    def fail(key, message):
        raise InvalidInputError(f"{source}: {key}: {message}")

    if not isinstance(data, dict):
        fail("(top level)", "give a table of seed, models, poses, operations")
    for key in data:
        if key not in _TOP:
            fail(key, f"unknown key; a spec has {', '.join(sorted(_TOP))}")
    seed = data.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        fail("seed", f"give a whole number >= 0, got {seed!r}")
    folder = Path(folder)
    models = _models(_tables(data, "models", fail, required=True), folder, fail)
    poses = tuple(_pose(t, f"poses[{i}]", fail) for i, t in
                  enumerate(_tables(data, "poses", fail) or [{"rest": True}]))
    operations = tuple(_operation(t, f"operations[{i}]", fail) for i, t in
                       enumerate(_tables(data, "operations", fail) or [{"kind": "none"}]))
    return Spec(seed, models, poses, operations, str(folder), source)


def _tables(data, key, fail, required=False) -> list:
    value = data.get(key)
    if value is None:
        if required:
            fail(key, "missing: give at least one [[" + key + "]] table")
        return []
    if not isinstance(value, list) or not value or not all(isinstance(t, dict) for t in value):
        fail(key, f"give a non-empty array of tables ([[{key}]]), got {value!r}")
    return value


def _known(table, key, allowed, fail) -> None:
    for name in table:
        if name not in allowed:
            fail(f"{key}.{name}", f"unknown key; {key} takes {', '.join(sorted(allowed))}")


def _models(tables, folder: Path, fail) -> tuple:
    """Each [[models]] path: a file, or a glob of files (sorted), relative to ``folder`` unless absolute."""
    out, seen = [], set()
    for i, table in enumerate(tables):
        key = f"models[{i}]"
        _known(table, key, {"path"}, fail)
        pattern = table.get("path")
        if not isinstance(pattern, str) or not pattern:
            fail(f"{key}.path", f"give the model's path (a string), got {pattern!r}")
        full = folder / pattern                 # (an absolute pattern stays itself)
        if any(c in pattern for c in "*?["):        # a glob (the characters glob.glob expands)
            found = sorted(p for p in glob.glob(str(full), recursive=True) if Path(p).is_file())
            if not found:
                fail(f"{key}.path", f"{pattern!r} matches no file (relative to {folder})")
        else:
            try:                                 # missing, a folder, a device: said as the loaders say it
                check_model_file(full, empty_ok=True)
            except ModelFormatError as exc:
                fail(f"{key}.path", str(exc))
            found = [str(full)]
        for p in found:
            resolved = Path(p).resolve()
            if resolved in seen:
                continue                         # (two patterns naming one file: one model)
            seen.add(resolved)
            try:
                name = str(Path(p).relative_to(folder))
            except ValueError:                   # given explicitly outside the folder
                name = p
            out.append(ModelEntry(str(resolved), name, f"{key}.path"))
    return tuple(out)


def _number(value, key, fail, positive=False, at_least=None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        fail(key, f"give a finite number, got {value!r}")
    if positive and value <= 0:
        fail(key, f"give a number > 0, got {value!r}")
    if at_least is not None and value < at_least:
        fail(key, f"give a number >= {at_least:g}, got {value!r}")
    return float(value)


def _range(value, key, fail, positive=False, at_least=None) -> tuple:
    """A number (a fixed value) or [low, high] with low <= high: returned as (low, high)."""
    if isinstance(value, list):
        if len(value) != 2:
            fail(key, f"give [low, high], got {value!r}")
        low, high = (_number(v, key, fail, positive, at_least) for v in value)
        if low > high:
            fail(key, f"low {low:g} > high {high:g}")
        return low, high
    value = _number(value, key, fail, positive, at_least)
    return value, value


def _pose(table, key, fail) -> PoseEntry:
    _known(table, key, {"clip", "times", "rest", "edits"}, fail)
    rest = table.get("rest", False)
    if not isinstance(rest, bool):
        fail(f"{key}.rest", f"give true or false, got {rest!r}")
    clip = table.get("clip")
    if rest and clip is not None:
        fail(key, "give either rest = true or a clip, not both")
    if rest:
        if "times" in table:
            fail(f"{key}.times", "the rest pose has no time: leave times out, or name a clip")
        times = (None,)
    else:
        if clip is None:
            fail(key, "give a clip (its name or index) with times, or rest = true")
        if isinstance(clip, bool) or not isinstance(clip, (str, int)) or clip == "" or \
                (isinstance(clip, int) and clip < 0):
            fail(f"{key}.clip", f"give the clip's name or index (>= 0), got {clip!r}")
        times = table.get("times")
        if not isinstance(times, list) or not times:
            fail(f"{key}.times", f"give a non-empty array of times in seconds, got {times!r}")
        times = tuple(_number(t, f"{key}.times[{k}]", fail) for k, t in enumerate(times))
    edits = table.get("edits", {})
    if not isinstance(edits, dict):
        fail(f"{key}.edits", f"give a table of {', '.join(EDITS)}, got {edits!r}")
    _known(edits, f"{key}.edits", set(EDITS), fail)
    parsed = []
    for kind in EDITS:                            # (a fixed order: TOML tables are unordered by intent)
        entries = edits.get(kind, [])
        entries = [entries] if isinstance(entries, dict) else entries
        if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
            fail(f"{key}.edits.{kind}", f"give a table or an array of tables, got {entries!r}")
        for k, entry in enumerate(entries):
            parsed.append(_edit(kind, entry, f"{key}.edits.{kind}" + (f"[{k}]" if len(entries) > 1 else ""), fail))
    return PoseEntry(None if rest else clip, times, tuple(parsed))


def _edit(kind, entry, key, fail) -> EditEntry:
    _known(entry, key, {"joint", "range", "axis"} if kind == "rotate" else {"joint", "range"}, fail)
    joint = entry.get("joint")
    if isinstance(joint, bool) or not isinstance(joint, (str, int)) or joint == "":
        fail(f"{key}.joint", f"give the joint's name or index, got {joint!r}")
    if "range" not in entry:
        fail(f"{key}.range", "missing: give [low, high] (or one number)")
    value = _range(entry["range"], f"{key}.range", fail, positive=kind == "dilate")
    axis = entry.get("axis")
    if axis is not None:
        if not isinstance(axis, list) or len(axis) != 3:
            fail(f"{key}.axis", f"give [x, y, z], got {axis!r}")
        axis = tuple(_number(a, f"{key}.axis", fail) for a in axis)
        if not any(axis):
            fail(f"{key}.axis", "the axis is zero: give a direction")
    return EditEntry(kind, joint, value, axis)


def _operation(table, key, fail) -> OperationEntry:
    kind = table.get("kind")
    if kind not in OPERATIONS:
        fail(f"{key}.kind", f"give one of {', '.join(OPERATIONS)}, got {kind!r}")
    defaults = OPERATIONS[kind]
    _known(table, key, {"kind", "count", *defaults}, fail)
    count = table.get("count", 1)
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        fail(f"{key}.count", f"give a whole number >= 1, got {count!r}")
    params = {}
    for name, default in defaults.items():
        value = table.get(name, default)
        if isinstance(default, bool):
            if not isinstance(value, bool):
                fail(f"{key}.{name}", f"give true or false, got {value!r}")
        else:
            value = _range(value, f"{key}.{name}", fail, positive=name != "opening", at_least=0.0)
        params[name] = value
    return OperationEntry(kind, count, tuple(sorted(params.items())))
