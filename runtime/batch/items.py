"""A spec expanded into items: one per (model, pose entry, time, operation entry, instance).

An item's id is a content hash of what defines its output: the model file's sha256 (not its path;
the path for a file that cannot be read), the pose entry's clip, time and edits, the operation's kind
and parameters (defaults filled in), the instance index, the global seed and cgaskin's version. So
the same spec gives the same ids on every machine, a changed spec changes only the ids of what it
changed, and an item's random draws (``Item.rng``) come from its id, never from the order in which
workers pick items up.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import asdict
from typing import NamedTuple

import numpy as np

from .._shared import version
from .._shared.memory_budget import require_memory
from .spec import Spec

__all__ = ["Item", "expand", "file_sha256", "item_count", "require_item_memory", "ID_LENGTH", "ITEM_BYTES",
           "UNREADABLE"]

#: hex digits of an item id (64 bits: a collision among a million items has odds ~3e-8)
ID_LENGTH = 16
#: bumped when the meaning of an item's parameters changes (so that old outputs are not kept); an id
#: also holds cgaskin's version: a resume after an upgrade (other algorithms) makes every item again
_VERSION = 1
#: the start of the "sha256" of a model file that cannot be read (then followed by why)
UNREADABLE = "unreadable:"


class Item(NamedTuple):
    """One output item, all a worker needs to make it (small: specs and seeds cross the network,
    rigs never do).

    Parameters
    ----------
    id : str
        ``ID_LENGTH`` hex digits: the item's name in the batch folder and the manifest.
    digest : str
        The full sha256 (hex) the id begins with; seeds the item's generator.
    model : str
        The model as the spec names it (the manifest's ``model``).
    path : str
        The model file's absolute path (read by the worker).
    model_sha256 : str
        The file's sha256 when the batch started.
    clip : str or int or None
        The clip posed, None for the rest pose.
    time : float or None
        Seconds into the clip.
    edits : tuple of EditEntry
        Random pose edits, drawn per item.
    operation : {"cut", "tear", "drill", "none"}
        What the item does to the posed model.
    params : tuple of (str, object)
        The operation entry's parameters.
    instance : int
        0 .. count - 1 among the entry's random instances.

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
    >>> item = cgaskin.batch.expand(cgaskin.batch.load_spec("spec.toml"))[1]
    >>> item.pose_label, item.operation, item.params, item.instance
    ('wave@0', 'cut', (('cap', False),), 1)
    """

    id: str
    digest: str
    model: str
    path: str
    model_sha256: str
    clip: object
    time: object
    edits: tuple
    operation: str
    params: tuple
    instance: int

    @property
    def pose_label(self) -> str:
        """The manifest's ``pose``: "rest" or "<clip>@<time>" (edits are in ``params``)."""
        return "rest" if self.clip is None else f"{self.clip}@{self.time:g}"

    def rng(self) -> np.random.Generator:
        """The item's own random generator, seeded from its whole digest (the global seed is in it).

        Returns
        -------
        numpy.random.Generator
            A new generator: the same draws for the same item, whatever process makes it.
        """
        return np.random.default_rng(int(self.digest, 16))


def file_sha256(path) -> str:
    """sha256 (hex) of a file's bytes, read in 1 MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _digest(definition: dict) -> str:
    text = json.dumps(definition, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


#: an expanded item's memory (its record, strings and digest: ~350 B measured, with room)
ITEM_BYTES = 1 << 10


def item_count(spec: Spec) -> int:
    """How many items ``spec`` expands to at most (before duplicates drop out), without expanding it."""
    times = sum(len(pose.times) for pose in spec.poses)
    return len(spec.models) * times * sum(op.count for op in spec.operations)


def require_item_memory(spec: Spec, item_bytes: int, limit: int | None = None) -> None:
    """MemoryLimitError, before any item is made, when ``spec``'s items at ``item_bytes`` each need more
    memory than is available (or than ``limit``)."""
    times = sum(len(pose.times) for pose in spec.poses)
    count = item_count(spec)
    require_memory(count * item_bytes, f"{spec.source}: {count} items ({len(spec.models)} model(s) x {times} "
                   f"pose(s) x {count // max(len(spec.models) * times, 1)} operation instances)",
                   "lower the operations' count (or the times, or the models), or split the spec", limit)


def expand(spec: Spec, hashes: dict | None = None) -> list:
    """The spec's items in spec order (models, poses, times, operations, instances), with their ids.

    An item that an earlier one duplicates (the same file listed twice, two equal entries) appears
    once. A model file that cannot be read is hashed as "unreadable:<reason>" (its ids from its
    path): its items still get ids and become error rows (a bad model is a row, not a failed batch).

    Parameters
    ----------
    spec : Spec
        The validated spec.
    hashes : dict, optional
        Model path -> sha256 of the files already hashed (filled in with the others).

    Returns
    -------
    list of Item

    Raises
    ------
    MemoryLimitError
        Before expanding, for more items than the memory available holds.

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
    >>> items = cgaskin.batch.expand(cgaskin.batch.load_spec("spec.toml"))
    >>> [(item.pose_label, item.instance) for item in items]   # 1 model x 2 times x 2 cuts
    [('wave@0', 0), ('wave@0', 1), ('wave@0.5', 0), ('wave@0.5', 1)]
    """
    require_item_memory(spec, ITEM_BYTES)
    hashes = {} if hashes is None else hashes
    items, seen = [], set()
    for model in spec.models:
        if model.path not in hashes:
            try:
                hashes[model.path] = file_sha256(model.path)
            except OSError as exc:
                hashes[model.path] = f"{UNREADABLE}{exc.strerror}"
        sha = hashes[model.path]
        # a file that cannot be read has no content to name it: its path does (two are two models)
        content = {"unreadable": model.path} if sha.startswith(UNREADABLE) else sha
        for pose in spec.poses:
            edits = [asdict(e) for e in pose.edits]
            for time in pose.times:
                for op in spec.operations:
                    for instance in range(op.count):
                        digest = _digest({"v": _VERSION, "cgaskin": version.VERSION, "seed": spec.seed,
                                          "model": content, "pose": {"clip": pose.clip, "time": time, "edits": edits},
                                          "operation": {"kind": op.kind, **dict(op.params)},
                                          "instance": instance})
                        if digest in seen:
                            continue
                        seen.add(digest)
                        items.append(Item(digest[:ID_LENGTH], digest, model.name, model.path, sha, pose.clip,
                                          time, pose.edits, op.kind, op.params, instance))
    return items
