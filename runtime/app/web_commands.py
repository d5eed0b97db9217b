"""``cgaskin view MODEL --out PAGE.html`` (one offline page that plays the model) and ``cgaskin serve
MODEL`` (a local page where the playing model is torn, cut and drilled); ``cgaskin.view`` and
``cgaskin.serve`` are imported only when the command runs."""
from __future__ import annotations

from pathlib import Path

from ..errors import InvalidInputError
from .options import clip_of, finite


def _check_view(args) -> None:
    if Path(args.out).suffix.lower() not in (".html", ".htm"):
        raise InvalidInputError(f"--out {args.out}: the view is a web page; give a file name ending in "
                                f".html, e.g. --out {Path(args.out).with_suffix('.html').name}")
    finite(args.time, f"--time {args.time}", "seconds")
    if args.time < 0:
        raise InvalidInputError(f"--time {args.time:g}: give seconds >= 0")


def _view(args) -> int:
    from ..rigs import load
    from ..view import show
    rig = load(args.model)
    view = show(rig, clip=clip_of(rig, args), play=not args.paused, time=args.time, skinning=args.skinning)
    view.save(args.out)
    clips = ", ".join(c.name for c in rig.clips) or "none"
    print(f"wrote {args.out}: {len(view.html) / 1e6:.1f} MB, {rig.n_vertices} vertices, clips: {clips} "
          f"(open it in a browser; it needs no network)")
    return 0


def _serve(args) -> int:
    from ..rigs import load
    from ..serve import Server
    rig = load(args.model)
    server = Server(rig, host=args.host, port=args.port, clip=clip_of(rig, args))
    server.run(announce=lambda url: print(f"cgaskin serve: {url} (Ctrl-C stops it)", flush=True))
    return 0


def register(sub) -> None:
    """Add ``view`` and ``serve`` to the argparse subparsers ``sub``."""
    p = sub.add_parser("view", help="write one self-contained web page (.html) that plays the model: "
                                    "clips, skeleton, weights, live dilation, cut rims; offline")
    p.add_argument("model", metavar="MODEL_OR_RIG", help="any model cgaskin.load reads (.glb, .gltf, .fbx, ...)")
    p.add_argument("--clip", default=None, help="clip name or index to start with (default: the first)")
    p.add_argument("--time", type=float, default=0.0, help="seconds into the clip to start at")
    p.add_argument("--paused", action="store_true", help="start paused")
    p.add_argument("--skinning", choices=("cgaskin", "three"), default="cgaskin",
                   help="who skins in the page first (it can switch): cgaskin's versors in generated GLSL ES "
                        "(default) or three.js's bone matrices")
    p.add_argument("--out", required=True, metavar="PAGE.html")
    p.set_defaults(run=_view, check_options=_check_view)

    p = sub.add_parser("serve", help="a local page where you tear (drag), cut and drill (click) the playing model; "
                                     "Python does the surgery, one session per tab")
    p.add_argument("model", metavar="MODEL", help="any model cgaskin.load reads (.glb, .gltf, .fbx, ...)")
    p.add_argument("--port", type=int, default=8765, help="port (default 8765; 0: any free port)")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1: this machine only; another only when given)")
    p.add_argument("--clip", default=None, help="clip name or index to play (default: the first)")
    p.set_defaults(run=_serve)
