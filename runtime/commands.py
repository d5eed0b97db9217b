"""Model subcommands of the ``cgaskin`` command line (demo, skin)."""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np


def progress(iterable, total: int, label: str):
    """Yield from ``iterable`` while drawing a text progress bar on stderr."""
    start = time.perf_counter()
    for i, item in enumerate(iterable, 1):
        yield item
        done = int(30 * i / total)
        rate = i / max(time.perf_counter() - start, 1e-9)
        print(f"\r{label} [{'#' * done}{'.' * (30 - done)}] {i}/{total} ({rate:.0f}/s)", end="",
              file=sys.stderr, flush=True)
    print(file=sys.stderr)


def _demo(args) -> int:
    from . import capsule_arm, skin, save
    from .render import render_strip
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rig = capsule_arm()
    elbow = rig.skeleton.names[1]
    rest = rig.rest_pose()
    poses = {
        "rest": rest,
        f"rotate {elbow} 60°": rest.rotate(elbow, [0, 0, 1], np.radians(60)),
        f"translate {elbow}": rest.translate(elbow, [0, 0.4, 0]),
        f"dilate {elbow} x1.6": rest.dilate(elbow, 1.6),
        "all three": rest.rotate(elbow, [0, 0, 1], np.radians(60)).translate(elbow, [0, 0.4, 0]).dilate(elbow, 1.6),
        "clip 'wave' t=1s": rig.pose("wave", 1.0),
    }
    frames = [(skin(rig, p), rig.faces) for p in poses.values()]
    render_strip(frames, out / "deform.png", titles=list(poses))
    save(rig, out / "capsule_arm.glb")
    written = [out / "deform.png", out / "capsule_arm.glb"]
    written += _demo_cut(rig, out)
    written += _demo_tear(rig, out)
    print("wrote " + ", ".join(map(str, written)))
    return 0


def _demo_cut(rig, out: Path) -> list:
    """Cut the bent arm across the forearm (capped), then animate both halves again."""
    from . import cut, save, skin
    from .render import render_strip
    bent = rig.rest_pose().rotate(rig.skeleton.names[1], [0, 0, 1], np.radians(50))
    joints = bent.global_matrices()[:, :3, 3]
    elbow, wrist = joints[1], joints[2]
    # across the middle of the forearm, tilted a little so that the cap is an ellipse
    normal = (elbow - wrist) + np.array([0.0, 0.0, 0.3])
    upper, lower = cut(rig, normal, (elbow + wrist) / 2, pose=bent, cap=True)
    frames, titles = [], []
    for name, half in (("upper half", upper), ("lower half", lower)):
        frames.append((skin(half, bent), half.faces))
        titles.append(f"{name}, cut posed")
    again = bent.rotate(rig.skeleton.names[1], [0, 0, 1], np.radians(-80)).dilate(rig.skeleton.names[-1], 1.4)
    for name, half in (("upper half", upper), ("lower half", lower)):
        frames.append((skin(half, again), half.faces))
        titles.append(f"{name}, re-posed + dilated")
    render_strip(frames, out / "cut.png", titles=titles, columns=2)
    save(upper, out / "cut_upper.glb")
    save(lower, out / "cut_lower.glb")
    return [out / "cut.png", out / "cut_upper.glb", out / "cut_lower.glb"]


def _demo_tear(rig, out: Path) -> list:
    """Two scalpel strokes along the top of the arm (one slit), opened, then animated again."""
    from . import save, skin, tear
    from .render import render_strip
    # the blade stands vertically (handle above the skin, tip at the axis) and moves along x
    stroke = [([x, 0.05, 1.0], [x, 0.05, 0.0]) for x in (0.6, 1.2, 1.8)]
    torn = tear(rig, stroke[0], stroke[1], opening=0.06)
    torn = tear(torn, stroke[1], stroke[2], opening=0.06)
    new = np.zeros(torn.n_vertices, bool)
    new[rig.n_vertices:] = True
    marked = new[torn.faces].any(axis=1)
    poses = {"torn (2 strokes, opened)": torn.rest_pose(),
             "torn, elbow bent -40°": torn.rest_pose().rotate(torn.skeleton.names[1], [0, 0, 1], np.radians(-40)),
             "torn, clip 'wave' t=1.5s": torn.pose("wave", 1.5)}
    frames = [(skin(torn, p), torn.faces, marked) for p in poses.values()]
    render_strip(frames, out / "tear.png", titles=list(poses), elev=80.0)
    save(torn, out / "torn.glb")
    return [out / "tear.png", out / "torn.glb"]


def _pose_of(rig, args):
    """The pose named by --clip/--time (None: rest pose)."""
    if args.clip is None:
        return None
    clip = int(args.clip) if args.clip.isdigit() else args.clip
    return rig.pose(clip, args.time)


def _cut(args) -> int:
    from . import cut, load, save
    rig = load(args.model)
    halves = cut(rig, args.normal, args.point, pose=_pose_of(rig, args), cap=args.cap)
    for half, path in zip(halves, args.out):
        if half.n_faces:
            save(half, path)
            print(f"wrote {path}: {half.n_vertices} vertices, {half.n_faces} faces")
        else:
            print(f"{path}: that side of the plane is empty; not written")
    return 0


def _tear(args) -> int:
    from . import load, save, tear
    rig = load(args.model)
    pose = _pose_of(rig, args)
    torn = tear(rig, (args.from_[:3], args.from_[3:]), (args.to[:3], args.to[3:]), pose=pose,
                opening=args.opening)
    save(torn, args.out)
    print(f"wrote {args.out}: {torn.n_vertices} vertices ({torn.n_vertices - rig.n_vertices} new), "
          f"{torn.n_faces} faces")
    return 0


def _skin(args) -> int:
    from . import load, skin
    from .rigs.export import save_mesh
    rig = load(args.model)
    clip = int(args.clip) if args.clip is not None and args.clip.isdigit() else args.clip
    times = [args.time] if args.frames <= 1 else list(np.linspace(args.time, args.end if args.end is not None
                                                                  else rig.clips[rig.clip_index(clip)].duration,
                                                                  args.frames))
    out = Path(args.out)
    paths = [out] if len(times) == 1 else [out.with_name(f"{out.stem}_{i:04d}{out.suffix}") for i in range(len(times))]
    items = zip(times, paths)
    if len(times) > 1:
        items = progress(items, len(times), "skinning")
    for t, path in items:
        pose = rig.rest_pose() if clip is None else rig.pose(clip, t)
        save_mesh(skin(rig, pose), rig.faces, path)
    print(f"wrote {len(paths)} file(s): {paths[0]}{' ...' if len(paths) > 1 else ''}")
    return 0


def _add_pose_options(p) -> None:
    p.add_argument("--clip", default=None, help="pose: clip name or index (default: the rest pose)")
    p.add_argument("--time", type=float, default=0.0, help="pose: seconds into the clip")


def register(sub) -> None:
    """Add the model subcommands to the argparse subparsers ``sub``."""
    p = sub.add_parser("demo", help="deform the built-in capsule arm; write pictures and a .glb (no files needed)")
    p.add_argument("--out", default="cgaskin-demo", help="output folder (default: ./cgaskin-demo)")
    p.set_defaults(run=_demo)

    p = sub.add_parser("skin", help="skin a model at a clip time and write the posed mesh (.glb/.gltf)")
    p.add_argument("model")
    _add_pose_options(p)
    p.add_argument("--frames", type=int, default=1, help="bake this many frames from --time to --end")
    p.add_argument("--end", type=float, default=None, help="last time when baking (default: clip end)")
    p.add_argument("--out", required=True)
    p.set_defaults(run=_skin)

    p = sub.add_parser("cut", help="cut a model by a plane into two rigs (.glb)")
    p.add_argument("model")
    p.add_argument("--normal", type=float, nargs=3, required=True, metavar=("X", "Y", "Z"))
    p.add_argument("--point", type=float, nargs=3, required=True, metavar=("X", "Y", "Z"))
    p.add_argument("--cap", action="store_true", help="close each half with a cap on the plane")
    _add_pose_options(p)
    p.add_argument("--out", nargs=2, required=True, metavar=("POSITIVE.glb", "NEGATIVE.glb"),
                   help="the half the normal points to, then the other")
    p.set_defaults(run=_cut)

    p = sub.add_parser("tear", help="tear a model along the path of a moving scalpel (.glb)")
    p.add_argument("model")
    p.add_argument("--from", dest="from_", type=float, nargs=6, required=True,
                   metavar=("AX", "AY", "AZ", "BX", "BY", "BZ"),
                   help="the scalpel (handle A, tip B) at the start of the stroke")
    p.add_argument("--to", type=float, nargs=6, required=True, metavar=("AX", "AY", "AZ", "BX", "BY", "BZ"),
                   help="the scalpel at the end of the stroke")
    p.add_argument("--opening", type=float, default=0.0, help="push the two sides apart by this distance")
    _add_pose_options(p)
    p.add_argument("--out", required=True)
    p.set_defaults(run=_tear)
