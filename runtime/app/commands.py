"""Model subcommands of the ``cgaskin`` command line (demo, skin, cut, tear, drill; view and serve in
``web_commands``, batch in ``batch_command``)."""
from __future__ import annotations

import sys
import time
from contextlib import closing, nullcontext
from pathlib import Path

import numpy as np

from ..errors import CgaskinError, InvalidInputError
from .._shared.memory_budget import require_memory
from .options import add_memory_option, add_pose_options, check_output, check_pose_options, clip_of, clip_time, \
    edited, finite, finite_point, max_memory, pose_of

#: the longest line of a --strokes file (six numbers and a comment); a longer one is no blade position
#: (``/dev/zero`` is one endless line)
STROKES_LINE = 4096
#: the memory one blade position of a tear costs, measured: its parsed row (~450 B) and its stroke in
#: the session (~5 kB on the capsule arm: the rows it appends, its undo record), with room to spare
STROKE_BYTES = 8 << 10
#: lines of a --strokes file read between two checks of the memory they will need
_STROKES_CHECKED = 4096


def progress(iterable, total: int, label: str):
    """Yield from ``iterable`` while drawing a text progress bar on stderr."""
    start, drawn = time.perf_counter(), False
    try:
        for i, item in enumerate(iterable, 1):
            yield item
            done = int(30 * i / total)
            rate = i / max(time.perf_counter() - start, 1e-9)
            print(f"\r{label} [{'#' * done}{'.' * (30 - done)}] {i}/{total} ({rate:.0f}/s)", end="",
                  file=sys.stderr, flush=True)
            drawn = True
    finally:            # (closed early too: an error message then starts on a line of its own)
        if drawn:
            print(file=sys.stderr)


def _demo(args) -> int:
    from ..animation.skinning import skin
    from ..rigs import save
    from ..rigs.procedural import capsule_arm
    from .precompile import precompile
    from .render import render_strip
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)   # (a folder it cannot make fails before the compile)
    precompile(verbose=True)              # on a fresh install: every kernel the demo needs, on every core
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
    written += _demo_drill(rig, out)
    print("wrote " + ", ".join(map(str, written)))
    return 0


def _demo_cut(rig, out: Path) -> list:
    """Cut the bent arm across the forearm (capped), then animate both halves again."""
    from ..animation.skinning import skin
    from ..rigs import save
    from ..surgery.cut import cut
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
    from ..animation.skinning import skin
    from ..rigs import save
    from ..surgery.tear import tear
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


def _demo_drill(rig, out: Path) -> list:
    """A hole through the upper arm and a blind one into the bent forearm, walled, then animated again."""
    from ..animation.skinning import skin
    from ..rigs import save
    from ..surgery.drill import drill_details
    from .render import render_strip
    elbow = rig.skeleton.names[1]
    bent = rig.rest_pose().rotate(elbow, [0, 0, 1], np.radians(50))
    through = drill_details(rig, [0.5, 0.0, -1.0], [0.5, 0.0, 1.0], 0.12)
    forearm = bent.global_matrices()[1] @ np.array([0.5, 0.0, 0.0, 1.0])   # half way down the forearm
    blind = drill_details(through.rig, forearm[:3] + [0.0, 0.0, -1.0], forearm[:3] + [0.0, 0.0, 0.02], 0.1,
                          pose=bent)
    drilled = blind.rig
    marked = np.zeros(drilled.n_faces, bool)
    marked[drilled.n_faces - blind.wall_faces:] = True               # the blind hole's wall and bottom
    poses = {"drilled (through, rest; blind, bent)": bent, "elbow straight": drilled.rest_pose(),
             "clip 'wave' t=1s": drilled.pose("wave", 1.0)}
    frames = [(skin(drilled, p), drilled.faces, marked) for p in poses.values()]
    render_strip(frames, out / "drill.png", titles=list(poses), elev=-70.0)
    save(drilled, out / "drilled.glb")
    return [out / "drill.png", out / "drilled.glb"]


def _check_cut(args) -> None:
    check_pose_options(args)
    finite_point(args.normal, "--normal")
    finite_point(args.point, "--point")
    if not any(args.normal):
        raise InvalidInputError("--normal 0 0 0: give the plane's normal, a non-zero direction")
    for path in args.out:
        check_output(path)
    if Path(args.out[0]).resolve() == Path(args.out[1]).resolve():
        raise InvalidInputError(f"--out names one file twice ({args.out[0]}): the second half would "
                                f"overwrite the first; give two paths")


def _cut(args) -> int:
    from ..rigs import load, save
    from ..surgery.cut import cut
    rig = load(args.model)
    halves = cut(rig, args.normal, args.point, pose=pose_of(rig, args), cap=args.cap)
    for half, path in zip(halves, args.out):
        if half.n_faces:
            save(half, path)
            print(f"wrote {path}: {half.n_vertices} vertices, {half.n_faces} faces")
        else:
            print(f"{path}: that side of the plane is empty; not written")
    return 0


def _check_drill(args) -> None:
    check_pose_options(args)
    finite_point(args.start, "--start")
    finite_point(args.end, "--end")
    finite(args.radius, f"--radius {args.radius}", "model units")
    if args.radius <= 0:
        raise InvalidInputError(f"--radius {args.radius:g}: give the bit's radius, a length > 0 in model units")
    check_output(args.out)


def _drill(args) -> int:
    from ..rigs import load, save
    from ..surgery.drill import drill_details
    rig = load(args.model)
    result = drill_details(rig, args.start, args.end, args.radius, pose=pose_of(rig, args), wall=not args.no_wall)
    save(result.rig, args.out)
    hole = f"{result.wall_faces} wall faces" if result.wall_faces else "open"
    print(f"wrote {args.out}: {result.rig.n_vertices} vertices, {result.rig.n_faces} faces (the hole: "
          f"{len(result.rim)} rim vertices, {hole})")
    return 0


def _blades(args) -> list:
    """The blade positions in order: --from, every --stroke, the lines of --strokes, --to; each
    (label, (2, 3) array (handle, tip)), the label naming where the user gave it."""
    rows = [("--from", args.from_)] if args.from_ else []
    rows += [(f"--stroke #{k}", row) for k, row in enumerate(args.stroke or [], 1)]
    if args.strokes:
        rows += _stroke_lines(args.strokes, max_memory(args))
    rows += [("--to", args.to)] if args.to else []
    if len(rows) < 2:
        raise InvalidInputError("a tear needs the blade at two times at least: --from and --to, or "
                                "--stroke repeated, or a --strokes file")
    blades = []
    for label, row in rows:
        if not all(np.isfinite(row)):
            raise InvalidInputError(f"{label} {' '.join(f'{v:g}' for v in row)}: give 6 finite numbers")
        if list(row[:3]) == list(row[3:]):
            raise InvalidInputError(f"{label}: the handle and the tip coincide at {list(row[:3])}; the "
                                    f"blade must be a segment of non-zero length")
        blades.append((label, np.array(row, dtype=np.float64).reshape(2, 3)))
    return blades


def _stroke_lines(name: str, limit) -> list:
    """The blade positions of the --strokes file ``name``: (label, six numbers) per line that holds
    any, read a line at a time (a device or a pipe may never end: its lines are bounded, and what
    they will cost is checked as they come)."""
    rows = []
    try:
        with open(name, encoding="utf-8") as f:
            for number, line in enumerate(iter(lambda: f.readline(STROKES_LINE + 1), ""), 1):
                if len(line) > STROKES_LINE:
                    raise InvalidInputError(f"--strokes {name}, line {number}: longer than {STROKES_LINE} "
                                            f"characters; give 6 numbers per line (handle AX AY AZ, tip BX BY BZ)")
                if number % _STROKES_CHECKED == 0:
                    require_memory(len(rows) * STROKE_BYTES, f"--strokes {name} ({len(rows)} blade positions "
                                   f"by line {number})", "tear with fewer strokes", limit)
                words = line.split("#")[0].replace(",", " ").split()
                if not words:
                    continue
                try:
                    values = [float(v) for v in words]
                except ValueError:
                    values = []
                if len(values) != 6:
                    raise InvalidInputError(f"--strokes {name}, line {number}: give 6 numbers (handle AX AY AZ, "
                                            f"tip BX BY BZ), got {' '.join(words)[:80]!r}")
                rows.append((f"--strokes {name} line {number}", values))
    except OSError as exc:
        raise InvalidInputError(f"--strokes {name}: cannot read it ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise InvalidInputError(f"--strokes {name}: not UTF-8 text; give 6 numbers per line") from None
    require_memory(len(rows) * STROKE_BYTES, f"--strokes {name} ({len(rows)} blade positions)",
                   "tear with fewer strokes", limit)
    return rows


def _check_tear(args) -> None:
    check_pose_options(args)
    finite(args.opening, f"--opening {args.opening}", "units of length")
    if args.opening < 0:
        raise InvalidInputError(f"--opening {args.opening:g}: give a distance >= 0 (0 leaves the slit closed)")
    max_memory(args)
    check_output(args.out)


def _tear(args) -> int:
    from ..rigs import load, save
    from ..surgery.session import Surgery
    blades = _blades(args)
    rig = load(args.model)
    pose = pose_of(rig, args)
    session = Surgery(rig, pose)                    # one progressive tear: each stroke continues the slit,
    steps = zip(blades[:-1], blades[1:])            # at the cost of what it touches
    bar = closing(progress(steps, len(blades) - 1, "tearing")) if len(blades) > 2 else nullcontext(steps)
    with bar as steps:
        for (label_from, blade_from), (label_to, blade_to) in steps:
            try:
                session.tear(blade_from, blade_to, opening=args.opening)
            except CgaskinError as exc:
                # the library names its parameters; the user gave blade positions by option
                message = str(exc).replace("scalpel scalpel_from", f"blade at {label_from}")
                message = message.replace("scalpel scalpel_to", f"blade at {label_to}")
                raise type(exc)(f"the stroke from {label_from} to {label_to}: {message}") from None
    torn = session.rig
    save(torn, args.out)
    print(f"wrote {args.out}: {len(blades) - 1} stroke(s), {torn.n_vertices} vertices "
          f"({torn.n_vertices - rig.n_vertices} new), {torn.n_faces} faces")
    return 0


def _check_skin(args) -> None:
    check_pose_options(args)
    if args.frames < 1:
        raise InvalidInputError(f"--frames must be at least 1, got {args.frames}")
    if args.frames > 1 and args.clip is None:
        raise InvalidInputError(f"--frames {args.frames} bakes a clip over time: name it with --clip")
    if args.end is not None:
        finite(args.end, f"--end {args.end}", "seconds")
        if args.frames == 1:
            raise InvalidInputError(f"--end {args.end:g} is the last time of the frames --frames N bakes: "
                                    f"give --frames N (N > 1) with it, or leave --end out")
    max_memory(args)
    check_output(args.out, frames=args.frames)


def _write_mesh(vertices, faces, path: Path, normals) -> None:
    """``save_mesh``, its refusal named by the file the user asked for (e.g. a pose whose skinned
    positions float32 cannot hold)."""
    from ..rigs.export import save_mesh
    try:
        save_mesh(vertices, faces, path, normals=normals)
    except InvalidInputError as exc:
        raise InvalidInputError(f"writing {path}: the skinned mesh cannot be stored: {exc}") from None


def _frames_bytes(rig, frames: int, edits: bool) -> int:
    """The memory ``cgaskin skin --frames`` holds at once for ``frames`` frames: their times, poses
    (versors, matrices, flags: 233 B a joint) and bone maps (96 B a bone), and every frame's skinned
    positions (one call) or, with edits, every frame's edited pose."""
    joints, bones = rig.skeleton.n_nodes, rig.skeleton.n_bones
    pose = 8 + 233 * joints
    return frames * (pose + 96 * bones + (pose + 512 if edits else 24 * rig.n_vertices))


def _skin(args) -> int:
    from ..animation.skinning import skin, skin_normals
    from ..rigs import load
    rig = load(args.model)
    out = Path(args.out)
    if args.frames == 1:
        pose = pose_of(rig, args)
        normals = skin_normals(rig, pose) if "NORMAL" in rig.attributes else None
        _write_mesh(skin(rig, pose), rig.faces, out, normals)
        print(f"wrote 1 file(s): {out}")
        return 0
    # every frame's pose in one compiled call, then (without edits) every frame's skin in another: what
    # that holds is checked before any of it is made
    require_memory(_frames_bytes(rig, args.frames, bool(args.edits)), f"--frames {args.frames} of {rig.name!r}",
                   "bake fewer frames at a time (--time and --end choose the part of the clip)", max_memory(args))
    clip = clip_of(rig, args)
    end = args.end if args.end is not None else rig.clips[rig.clip_index(clip)].duration
    poses = rig.poses(clip, np.linspace(clip_time(args), end, args.frames))
    posed = [edited(rig, poses[i], args) for i in range(args.frames)] if args.edits else None
    vertices = skin(rig, poses) if posed is None else None
    with closing(progress(range(args.frames), args.frames, "skinning")) as frames:
        for i in frames:
            pose = poses[i] if posed is None else posed[i]
            normals = skin_normals(rig, pose) if "NORMAL" in rig.attributes else None
            _write_mesh(skin(rig, pose) if vertices is None else vertices[i], rig.faces, _frame_path(out, i), normals)
    print(f"wrote {args.frames} file(s): {_frame_path(out, 0)} ...")
    return 0


def _frame_path(out: Path, i: int) -> Path:
    """Frame ``i``'s file of ``--out``: o_0000.glb, o_0001.glb, ..."""
    return out.with_name(f"{out.stem}_{i:04d}{out.suffix}")


def register(sub) -> None:
    """Add the model subcommands to the argparse subparsers ``sub``."""
    p = sub.add_parser("demo", help="deform the built-in capsule arm; write pictures and a .glb (no files needed)")
    p.add_argument("--out", default="cgaskin-demo", help="output folder (default: ./cgaskin-demo)")
    p.set_defaults(run=_demo)

    p = sub.add_parser("skin", help="skin a model at a clip time and write the posed mesh (.glb/.gltf)")
    p.add_argument("model")
    add_pose_options(p, "the rest pose of the nodes")
    p.add_argument("--frames", type=int, default=1, help="bake this many frames from --time to --end")
    p.add_argument("--end", type=float, default=None, help="last time when baking (default: clip end)")
    add_memory_option(p)
    p.add_argument("--out", required=True)
    p.set_defaults(run=_skin, check_options=_check_skin)

    p = sub.add_parser("cut", help="cut a model by a plane into two rigs (.glb)")
    p.add_argument("model")
    p.add_argument("--normal", type=float, nargs=3, required=True, metavar=("X", "Y", "Z"))
    p.add_argument("--point", type=float, nargs=3, required=True, metavar=("X", "Y", "Z"))
    p.add_argument("--cap", action="store_true", help="close each half with a cap on the plane")
    add_pose_options(p, "the mesh as stored")
    p.add_argument("--out", nargs=2, required=True, metavar=("POSITIVE.glb", "NEGATIVE.glb"),
                   help="the half the normal points to, then the other")
    p.set_defaults(run=_cut, check_options=_check_cut)

    p = sub.add_parser("drill", help="drill a hole through a model (.glb): a bit of --radius travelling from "
                                     "--start to --end; the hole gets a wall where the bit passes inside")
    p.add_argument("model")
    p.add_argument("--start", type=float, nargs=3, required=True, metavar=("X", "Y", "Z"))
    p.add_argument("--end", type=float, nargs=3, required=True, metavar=("X", "Y", "Z"),
                   help="where the bit's round tip stops")
    p.add_argument("--radius", type=float, required=True)
    p.add_argument("--no-wall", action="store_true", help="leave the hole open (its rims a boundary)")
    add_pose_options(p, "the mesh as stored")
    p.add_argument("--out", required=True)
    p.set_defaults(run=_drill, check_options=_check_drill)

    p = sub.add_parser("tear", help="tear a model along the path of a moving scalpel (.glb); the blade "
                                    "positions in order: --from, each --stroke, the --strokes file, --to")
    p.add_argument("model")
    blade = ("AX", "AY", "AZ", "BX", "BY", "BZ")
    p.add_argument("--from", dest="from_", type=float, nargs=6, metavar=blade,
                   help="the scalpel (handle A, tip B) at the start of the stroke")
    p.add_argument("--stroke", type=float, nargs=6, action="append", metavar=blade,
                   help="a further blade position; repeat it: consecutive positions are strokes of one "
                        "progressive tear, each continuing the slit")
    p.add_argument("--strokes", metavar="FILE",
                   help="a text file of blade positions, one per line (6 numbers; '#' comments)")
    p.add_argument("--to", type=float, nargs=6, metavar=blade, help="the scalpel at the end of the stroke")
    p.add_argument("--opening", type=float, default=0.0, help="push the two sides apart by this distance")
    add_memory_option(p)
    add_pose_options(p, "the mesh as stored")
    p.add_argument("--out", required=True)
    p.set_defaults(run=_tear, check_options=_check_tear)

    from . import web_commands                        # cgaskin view and cgaskin serve (the page)
    web_commands.register(sub)

    from . import batch_command                       # cgaskin batch (a dataset on Dask)
    batch_command.register(sub)
