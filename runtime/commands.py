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
    print(f"wrote {out / 'deform.png'} (rest, rotation, translation, dilation, all three, clip) "
          f"and {out / 'capsule_arm.glb'}")
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


def register(sub) -> None:
    """Add the model subcommands to the argparse subparsers ``sub``."""
    p = sub.add_parser("demo", help="deform the built-in capsule arm; write pictures and a .glb (no files needed)")
    p.add_argument("--out", default="cgaskin-demo", help="output folder (default: ./cgaskin-demo)")
    p.set_defaults(run=_demo)

    p = sub.add_parser("skin", help="skin a model at a clip time and write the posed mesh (.glb/.gltf)")
    p.add_argument("model")
    p.add_argument("--clip", default=None, help="clip name or index (default: the rest pose)")
    p.add_argument("--time", type=float, default=0.0, help="seconds into the clip")
    p.add_argument("--frames", type=int, default=1, help="bake this many frames from --time to --end")
    p.add_argument("--end", type=float, default=None, help="last time when baking (default: clip end)")
    p.add_argument("--out", required=True)
    p.set_defaults(run=_skin)
