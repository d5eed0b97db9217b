"""Options the model subcommands share: the pose (--rest, --clip/--time, --rotate/--translate/--dilate),
output files and numbers, checked before a model is read.

Every mistake here is the user's to fix on the command line, so the messages name the option and the
value as typed (``--time 0.3``, ``--out frames5``), not the library functions behind them; the CLI turns
them into one line and exit status 2.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from ..errors import CgaskinError, InvalidInputError

#: what ``save`` and ``save_mesh`` write (glTF 2.0)
OUTPUT_SUFFIXES = (".glb", ".gltf")
#: --max-memory's units (powers of 1024, as ``free -h`` and ``ulimit`` count)
_UNITS = {"": 1, "B": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}


class _Edit(argparse.Action):
    """Collects --rotate/--translate/--dilate into one list, in command-line order (the order in
    which they compose): (kind, joint, numbers, the option as typed)."""

    def __call__(self, parser, namespace, values, option_string=None):
        joint, *numbers = values
        try:
            numbers = [float(v) for v in numbers]
        except ValueError:
            parser.error(f"{option_string} {' '.join(values)}: after the joint, give numbers")
        typed = f"{option_string} {' '.join(values)}"
        namespace.edits = (namespace.edits or []) + [(self.dest, joint, numbers, typed)]


def add_pose_options(p, default: str) -> None:
    """The pose options of a subcommand whose pose is ``default`` when none is given; they are
    checked by ``check_pose_options`` (cli.main runs ``args.check_options`` before the command)."""
    g = p.add_argument_group(f"pose (default: {default}); edits apply after the clip, in order")
    g.add_argument("--rest", action="store_true",
                   help="the rest pose of the nodes (what a viewer shows; differs from the stored mesh "
                        "when the bind matrices are not the rest pose's, e.g. a mesh node with an offset); "
                        "not with --clip")
    g.add_argument("--clip", default=None, help="clip name or index")
    g.add_argument("--time", type=float, default=None, help="seconds into the clip (default 0; needs --clip)")
    g.add_argument("--rotate", action=_Edit, nargs=5, metavar=("JOINT", "AX", "AY", "AZ", "DEGREES"),
                   help="rotate JOINT about the axis (in its parent's frame); repeatable")
    g.add_argument("--translate", action=_Edit, nargs=4, metavar=("JOINT", "X", "Y", "Z"),
                   help="translate JOINT (in its parent's frame); repeatable")
    g.add_argument("--dilate", action=_Edit, nargs=2, metavar=("JOINT", "SCALE"),
                   help="scale JOINT and its subtree uniformly about the joint; repeatable")
    p.set_defaults(edits=[], pose_default=default, check_options=check_pose_options)


def check_pose_options(args) -> None:
    """Incomplete or conflicting pose options are refused (they would be ignored otherwise: a --time
    without a clip would give the default pose, --rest with --clip the clip's)."""
    if args.time is not None:
        finite(args.time, f"--time {args.time}", "seconds")
        if args.clip is None:
            raise InvalidInputError(f"--time {args.time:g} is a time in a clip: name the clip with --clip "
                                    f"(without it the pose is {args.pose_default})")
    if args.rest and args.clip is not None:
        raise InvalidInputError(f"--rest and --clip {args.clip} conflict: --rest is the rest pose, --clip the "
                                f"clip's pose at --time; give one of them (edits apply after either)")


def add_memory_option(p) -> None:
    """--max-memory SIZE, for a subcommand whose work grows with a size the user gives (frames,
    strokes, items); ``max_memory(args)`` reads it."""
    p.add_argument("--max-memory", metavar="SIZE", default=None,
                   help="refuse, before any work, what is estimated to need more memory than SIZE (bytes, or "
                        "with a unit K, M, G, T: powers of 1024, e.g. 2G); the memory available is always a limit")


def max_memory(args) -> int | None:
    """--max-memory in bytes (None when not given); InvalidInputError naming it when it is no size."""
    text = args.max_memory
    if text is None:
        return None
    value, unit = text.strip(), ""
    if value[-3:].upper() in ("KIB", "MIB", "GIB", "TIB"):
        value, unit = value[:-3], value[-3].upper()
    elif value[-1:].upper() in _UNITS:
        value, unit = value[:-1], value[-1].upper()
    try:
        number = float(value)
    except ValueError:
        number = math.nan
    if not (math.isfinite(number) and number * _UNITS[unit] >= 1):
        raise InvalidInputError(f"--max-memory {text}: give a size of at least one byte: a number of bytes, or "
                                f"with a unit K, M, G or T (e.g. --max-memory 2G)")
    return int(number * _UNITS[unit])


def clip_time(args) -> float:
    """--time, 0 when not given."""
    return 0.0 if args.time is None else args.time


def finite(value: float, typed: str, what: str) -> float:
    """``value`` when finite (argparse's float takes 'nan' and 'inf'), else InvalidInputError."""
    if not math.isfinite(value):
        raise InvalidInputError(f"{typed}: give a finite number of {what}")
    return value


def finite_point(values, option: str) -> list:
    """Three finite numbers given to ``option`` (--normal, --point)."""
    if not all(math.isfinite(v) for v in values):
        raise InvalidInputError(f"{option} {' '.join(f'{v:g}' for v in values)}: give three finite numbers")
    return values


def check_output(value: str, option: str = "--out", frames: int = 1) -> Path:
    """An output model file: a .glb or .gltf name (checked before anything is read or written)."""
    path = Path(value)
    if path.suffix.lower() in OUTPUT_SUFFIXES:
        return path
    example = path.with_name(path.name + ".glb") if not path.suffix else path.with_suffix(".glb")
    if frames > 1:
        raise InvalidInputError(f"{option} {value}: cgaskin writes .glb or .gltf; give a file name ending in "
                                f"one of them, e.g. {option} {example} (--frames {frames} writes "
                                f"{example.stem}_0000{example.suffix} ... one file per frame)")
    raise InvalidInputError(f"{option} {value}: cgaskin writes .glb or .gltf; give a file name ending in "
                            f"one of them, e.g. {option} {example}")


def clip_of(rig, args):
    """--clip as the rig names it: a clip name, else a digit string as an index (None: no clip)."""
    if args.clip is None or args.clip in [c.name for c in rig.clips] or not args.clip.isdigit():
        return args.clip
    return int(args.clip)


def joint_of(rig, name: str):
    """A joint named on the command line: its name, else a digit string as a node index."""
    return int(name) if name not in rig.skeleton.names and name.isdigit() else name


def pose_of(rig, args):
    """The pose named by --rest or --clip/--time and the --rotate/--translate/--dilate edits applied
    after it in the order given; None when none of them is given (the mesh as stored)."""
    clip = clip_of(rig, args)
    if clip is None and not args.edits and not args.rest:
        return None
    pose = rig.rest_pose() if clip is None else rig.pose(clip, clip_time(args))
    return edited(rig, pose, args)


def edited(rig, pose, args):
    """``pose`` with the --rotate/--translate/--dilate edits applied in the order given; an edit that
    fails is named as typed."""
    for kind, joint, values, typed in args.edits:
        try:
            joint = joint_of(rig, joint)
            if kind == "rotate":
                pose = pose.rotate(joint, values[:3], np.radians(values[3]))
            elif kind == "translate":
                pose = pose.translate(joint, values)
            else:
                pose = pose.dilate(joint, values[0])
        except CgaskinError as exc:
            raise type(exc)(f"{typed}: {exc}") from None
    return pose
