"""`cgaskin serve` in headless Chromium and over raw WebSockets: a drag across the playing Fox tears it
(each pointer step one stroke in the pose on screen), a click drills it or places a cutting plane that a
gizmo turns before the cut, undo restores the counts, the saved .glb has the slit and skins as the page
shows it, each stroke sends a small delta, two tabs keep their own sessions, and hostile messages get
error replies while the server goes on.

One server (a thread, port 0, 127.0.0.1) and one browser (tests/clients/js/serve_page.mjs) for the
page tests; the screenshot goes to $CGASKIN_VIEW_SCREENSHOTS when set (how docs/view/ is made)."""
import base64
import http.client
import json
import os
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest

import cgaskin
from cgaskin.app.cli import main
from cgaskin.serve import Server
from cgaskin.serve.protocol import MAX_MESSAGE, Cut, Drill, ProtocolError, Tear, parse
from cgaskin.view import rim_edges

from tests.helpers.requirements import require

from .conftest import SUMMARY

try:                                # (the [serve] extra: skipped without it, a failure under CGASKIN_CI=1)
    import websockets
    from websockets.exceptions import ConnectionClosed, InvalidStatus
    from websockets.sync.client import connect
    MISSING = [] if int(websockets.__version__.split(".")[0]) >= 14 else [f"websockets >= 14 (has {websockets.__version__})"]
except ImportError:
    MISSING = ["websockets >= 14 (pip install -e '.[serve]')"]

TOLERANCE = 1e-4          # of the bounding box diagonal: the page skins in float32
HIP, NECK, TAIL, SPINE = "b_Hip_01", "b_Neck_04", "b_Tail02_013", "b_Spine02_03"


@pytest.fixture(scope="module")
def fox(models_dir):
    path = Path(models_dir) / "Fox.glb"
    if not path.is_file():
        pytest.skip(f"{path} is not there")
    return path, cgaskin.load(path)


@pytest.fixture(scope="module")
def server(fox):
    require(MISSING, "cgaskin serve's tests")
    with Server(fox[1], port=0, clip="Walk") as running:
        yield running


STEPS = [
    [0, "call", "counts"], [0, "call", "setTool", "tear"],
    [0, "drag", HIP, NECK, 12, 40, 10],                                      # 2: across the playing body
    [0, "call", "counts"], [0, "call", "serveStats"], [0, "call", "pause"], [0, "call", "getTime"],
    [0, "call", "positions"], [0, "call", "saveGlb"], [0, "call", "snapshot"],
    [1, "call", "counts"], [1, "call", "undo"], [1, "call", "serveStats"],   # 10: a second tab
    [0, "call", "setTool", "cut"], [0, "click", TAIL, 0, 0], [0, "call", "cuttingPlane"],   # 13: the plane
    [0, "call", "turnPlane", [0, 1, 0], 0.4], [0, "call", "cutWithPlane"], [0, "call", "counts"],   # 16: the gizmo's turn
    [0, "call", "undo"], [0, "call", "counts"],                              # 19
    [0, "call", "setTool", "drill"], [0, "click", SPINE, 0, 0], [0, "call", "counts"],
    [0, "call", "undo"], [0, "call", "counts"], [0, "call", "serveStats"],   # 24
    [1, "call", "counts"], [0, "call", "cuttingPlane"],                      # 27
]


@pytest.fixture(scope="module")
def page(threejs, server, tmp_path_factory):
    work = tmp_path_factory.mktemp("serve")
    (work / "job.json").write_text(json.dumps({"url": server.url, "width": 1000, "height": 520, "steps": STEPS}))
    start = time.perf_counter()
    run = subprocess.run([threejs["node"], str(threejs["js"] / "serve_page.mjs"), str(work / "job.json"),
                          str(work / "out.json")], capture_output=True, text=True, timeout=120,
                         env={**os.environ, "CGASKIN_CHROMIUM": threejs["chromium"]})
    assert run.returncode == 0, f"serve_page.mjs failed:\n{run.stderr[-4000:]}"
    record = json.loads((work / "out.json").read_text())
    shots = Path(os.environ.get("CGASKIN_VIEW_SCREENSHOTS") or work)
    shots.mkdir(parents=True, exist_ok=True)
    drag = record["results"][2] if len(record["results"]) > 2 else None
    if isinstance(drag, dict) and drag["frames"]:
        _animation([_png(frame) for frame in drag["frames"]], shots / "serve_fox_tear.gif")
    SUMMARY.append(f"cgaskin serve: two tabs driven in one Chromium in {time.perf_counter() - start:.1f} s")
    return record


def _png(data_url: str) -> bytes:
    return base64.b64decode(data_url.split(",", 1)[1])


def _animation(frames: list, path: Path) -> None:
    """The frames (PNG bytes) as a looping GIF, cropped to the model, 360 pixels wide (Pillow: matplotlib's
    dependency, installed with the [render] extra; without it the picture is not made)."""
    try:
        from PIL import Image
    except ImportError:
        return
    import io
    images = [Image.open(io.BytesIO(frame)).convert("RGB") for frame in frames]
    # cropped to where the model goes in any frame (the background's colour is the top-left pixel's)
    pixels = np.stack([np.asarray(image, np.int16) for image in images])
    rows, columns = np.nonzero((np.abs(pixels - pixels[0, 0, 0]).max(axis=3) > 12).any(axis=0))
    margin = 12
    box = (max(columns.min() - margin, 0), max(rows.min() - margin, 0),
           min(columns.max() + margin, images[0].width), min(rows.max() + margin, images[0].height))
    size = (360, round(360 * (box[3] - box[1]) / (box[2] - box[0])))
    images = [image.crop(box).resize(size, Image.LANCZOS).quantize(colors=64) for image in images]
    images[0].save(path, save_all=True, append_images=images[1:], duration=120, loop=0, optimize=True)


def test_the_page_loads_from_the_server_only_without_errors(page):
    assert page["requests"] == [], f"requests to elsewhere: {page['requests']}"
    assert page["errors"] == [], "\n".join(page["errors"])
    assert len(page["results"]) == len(STEPS)


def test_a_drag_on_the_playing_fox_tears_one_more_slit(page, fox, tmp_path):
    _, rig = fox
    r = page["results"]
    before, after, stats = r[0], r[3], r[4]
    strokes = [reply for reply in stats["replies"] if reply["op"] == "tear"]
    assert len(strokes) >= 3 and sum(reply["ok"] for reply in strokes) >= 3, strokes
    frames = r[2]["frames"]           # the canvas during and after the drag: the body walks on, torn
    assert len(frames) == 12 + 10 and len({frame for frame in frames}) > len(frames) // 2
    assert after["n_vertices"] > before["n_vertices"] and after["n_rims"] > before["n_rims"] == len(rim_edges(rig))
    saved = tmp_path / "torn.glb"
    saved.write_bytes(base64.b64decode(r[8]))
    torn = cgaskin.load(saved)
    assert (torn.n_vertices, torn.n_faces) == (after["n_vertices"], after["n_faces"])
    assert len(rim_edges(torn)) == after["n_rims"] > len(rim_edges(rig))     # the slit's two lips
    # what the page shows after the strokes, in the pose on screen, is cgaskin.skin of the saved rig
    shown = np.frombuffer(base64.b64decode(r[7]), "<f8").reshape(-1, 3)
    expected = cgaskin.skin(torn, torn.pose("Walk", r[6]))
    diagonal = np.linalg.norm(np.ptp(rig.vertices, axis=0))
    assert shown.shape == expected.shape
    assert np.abs(shown - expected).max() / diagonal < TOLERANCE
    # each stroke's reply is a small part of the whole mesh in the same encoding
    sizes = [reply["bytes"] for reply in strokes if reply["ok"]]
    SUMMARY.append(f"cgaskin serve: {len(sizes)} tear strokes from one drag on Fox (Walk playing): "
                   f"{min(sizes)}-{max(sizes)} bytes per stroke (median {int(np.median(sizes))}) against "
                   f"{stats['meshBytes']} for the whole mesh ({max(sizes) / stats['meshBytes']:.1%} at most)")
    assert max(sizes) < 0.1 * stats["meshBytes"]


def test_cut_and_drill_from_the_page_change_the_mesh_and_undo_restores_it(page):
    r = page["results"]
    torn, cut, after_cut_undo, drilled, after_drill_undo = r[3], r[18], r[20], r[23], r[25]
    key = lambda c: (c["n_vertices"], c["n_faces"], c["n_rims"])       # noqa: E731
    # the click placed the plane at the tail facing across the screen; the gizmo turned it 0.4 rad
    placed, turned = r[15], np.asarray(r[16])
    assert placed is not None and abs(np.linalg.norm(turned) - 1) < 1e-9
    assert np.degrees(np.arccos(np.clip(np.dot(placed["normal"], turned), -1, 1))) > 5
    assert r[17] is True and key(cut) != key(torn) and cut["n_rims"] > torn["n_rims"]   # the cut's rims
    assert drilled["n_faces"] > torn["n_faces"]                            # the hole's wall
    assert r[19] is True and r[24] is True
    assert key(after_cut_undo) == key(torn) and key(after_drill_undo) == key(torn)
    ops = [reply["op"] for reply in r[26]["replies"] if reply["ok"]]
    assert "cut" in ops and "drill" in ops
    assert r[28] is None                       # another tool put the plane away


def test_two_tabs_do_not_affect_each_other(page, fox):
    _, rig = fox
    r = page["results"]
    original = {"n_vertices": rig.n_vertices, "n_faces": rig.n_faces, "n_rims": len(rim_edges(rig))}
    for counts in (r[10], r[27]):              # before and after the first tab's tears, cut and drill
        assert {k: counts[k] for k in original} == original
    assert r[11] is False                      # nothing to undo in the second tab
    assert "nothing to undo" in r[12]["replies"][-1]["error"]


def _ws(server):
    return server.url.replace("http://", "ws://")


def test_hostile_messages_get_error_replies_and_the_server_goes_on(server, fox):
    _, rig = fox
    hostile = ["{", "[1, 2]", "null", '"hello"', '{"op": "format c:"}', '{"op": "tear"}',
               '{"op": "tear", "from": [[0, 0, 0], [1, 1, NaN]], "to": [[0, 0, 0], [1, 1, 1]]}',
               '{"op": "tear", "from": "[[0,0,0],[1,1,1]]", "to": [[0, 0, 0], [1, 1, 1]]}',
               '{"op": "cut", "normal": [1, 0, 0], "point": [0, 0, 1e999]}',
               '{"op": "drill", "start": [0, 0, 0], "end": [0, 0, 1], "radius": true}',
               '{"op": "cut", "normal": [1, 0, 0], "point": [0, 0, 0], "clip": "../../etc/passwd"}',
               '{"op": "save", "path": "/tmp/x.glb"}', '{"id": {"a": 1}, "op": "hello"}',
               json.dumps({"op": "tear", "from": [[0.0] * 3] * 100000, "to": 1})[:MAX_MESSAGE + 10],
               json.dumps({"op": "tear", "from": [[[[[[1]]]]]] * 2, "to": 1}), "[" * 5000 + "]" * 5000,
               json.dumps({"op": "cut", "normal": [0, 0, 0], "point": [0, 0, 0]}),
               '{"op": "cut", "normal": [1, 0, 0], "point": [0, 0, 1' + "0" * 400 + ']}',
               '{"op": "cut", "normal": [1, 0, 0], "point": [0, 0, 0], "dilations": false}',
               '{"op": "cut", "normal": [1, 0, 0], "point": [0, 0, 0], "dilations": []}',
               '{"op": "cut", "normal": [1, 0, 0], "point": [0, 0, 0], "dilations": 0}',
               json.dumps({"op": "undo"}), b"\x00\x01binary"]
    with connect(_ws(server)) as ws:
        for message in hostile:
            ws.send(message)
            reply = json.loads(ws.recv(timeout=30))
            assert reply["ok"] is False and reply["error"], message
            assert reply["kind"] != "InternalError", reply
            text = message if isinstance(message, str) else ""
            if "0000000000" in text:            # a 400-digit integer: the range's error, not a crash
                assert reply["kind"] == "ProtocolError" and "within +-1e+12" in reply["error"], reply
            if '"dilations": ' in text:
                assert reply["kind"] == "ProtocolError" and "dilations must be an object" in reply["error"], reply
        ws.send(json.dumps({"id": 7, "op": "tear", "from": [[1e6, 0, 0], [1e6, 1, 0]],
                            "to": [[1e6, 0, 1], [1e6, 1, 1]], "clip": "Walk", "time": 0.2}))
        missed = json.loads(ws.recv(timeout=30))
        assert missed["id"] == 7 and missed["kind"] == "MissesMeshError"
        ws.send('{"id": "h", "op": "hello"}')
        hello = json.loads(ws.recv(timeout=30))
        assert hello["ok"] and hello["id"] == "h" and hello["operations"] == 0      # the session unchanged
        assert (hello["n_vertices"], hello["n_faces"]) == (rig.n_vertices, rig.n_faces)
    with pytest.raises(ConnectionClosed):          # a frame over websockets' limit closes that connection
        with connect(_ws(server)) as ws:
            ws.send("x" * (2 << 20))
            ws.recv(timeout=30)
    with connect(_ws(server)) as ws:              # and the server still serves
        ws.send('{"op": "hello"}')
        assert json.loads(ws.recv(timeout=30))["ok"] is True


def test_http_serves_the_page_and_nothing_else(server):
    with urllib.request.urlopen(server.url) as response:
        assert response.headers["Content-Type"].startswith("text/html") and b"cgaskin serve" in response.read()
    base = f"http://127.0.0.1:{server.address[1]}/"
    for path in ("etc/passwd", "../pyproject.toml", "runtime/serve/server.py", "assets/viewer/main.js", "%2e%2e/"):
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(f"{base}{path}?token={server.token}")
        assert refused.value.code == 404
    other = urllib.request.Request(server.url, headers={"Host": "attacker.example"})   # (DNS rebinding)
    with pytest.raises(urllib.error.HTTPError) as refused:
        urllib.request.urlopen(other)
    assert refused.value.code == 403
    with pytest.raises(InvalidStatus):            # a WebSocket from another site's page
        connect(_ws(server), origin="http://attacker.example")


def _status(port: int, path: str, headers: list) -> tuple[int, str]:
    """(status, body) of a GET with exactly these headers (Host included, as given: none, or twice)."""
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    connection.putrequest("GET", path, skip_host=True, skip_accept_encoding=True)
    for name, value in headers:
        connection.putheader(name, value)
    connection.endheaders()
    response = connection.getresponse()
    status, body = response.status, response.read().decode()
    connection.close()
    return status, body


def test_every_request_needs_the_token_its_own_origin_and_one_host(server):
    port, token = server.address[1], server.token
    host = ("Host", f"127.0.0.1:{port}")
    assert _status(port, f"/?token={token}", [host])[0] == 200
    for path in ("/", "/?token=", f"/?token={token[:-1]}", f"/?token={token}x", "/?token=a&token=b"):
        status, body = _status(port, path, [host])
        assert status == 403 and "token" in body, path
    for headers in ([], [host, host], [("Host", "["), ], [("Host", "127.0.0.1:notaport")]):
        status, body = _status(port, f"/?token={token}", headers)
        assert status == 400 and "Host" in body, headers
    assert _status(port, f"/?token={token}", [("Host", f"127.0.0.1:{port + 1}")])[0] == 403
    for origin in ("null", f"http://127.0.0.2:{port}", f"https://127.0.0.1:{port}", "file://"):
        assert _status(port, f"/?token={token}", [host, ("Origin", origin)])[0] == 403, origin
    # WebSockets: the page's own Origin or none (a client without a browser), and the token, or no handshake
    with connect(_ws(server), origin=f"http://127.0.0.1:{port}") as ws:
        ws.send('{"op": "hello"}')
        assert json.loads(ws.recv(timeout=30))["ok"] is True
    for url, origin in ((f"ws://127.0.0.1:{port}/", None), (f"ws://127.0.0.1:{port}/?token=guess", None),
                        (_ws(server), "null")):
        with pytest.raises(InvalidStatus) as refused:
            connect(url, origin=origin)
        assert refused.value.response.status_code == 403


# a page on another loopback address (another site): a sandboxed iframe (Origin: null) tries the server's
# WebSocket without the token, with a guessed one, and with the real one (which another site cannot know)
FOREIGN = """<!doctype html><meta charset="utf-8"><title>another site</title>
<iframe sandbox="allow-scripts" srcdoc="<script>
const attempt = (url) => new Promise((done) => {
    const ws = new WebSocket(url);
    ws.onopen = () => ws.send(JSON.stringify({op: 'hello'}));
    ws.onmessage = (event) => done('answered: ' + event.data.slice(0, 60));
    ws.onerror = () => done('refused');
});
(async () => parent.postMessage({none: await attempt('ws://127.0.0.1:PORT/'),
                                 guessed: await attempt('ws://127.0.0.1:PORT/?token=guess'),
                                 known: await attempt('ws://127.0.0.1:PORT/?token=TOKEN')}, '*'))();
</script>"></iframe>
<script>addEventListener('message', (event) => { window.result = event.data; });</script>
"""


def test_a_page_of_another_site_cannot_drive_the_server(threejs, server, tmp_path):
    import functools
    import http.server
    import threading
    port = server.address[1]
    (tmp_path / "index.html").write_text(FOREIGN.replace("PORT", str(port)).replace("TOKEN", server.token))
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(tmp_path))
    with http.server.ThreadingHTTPServer(("127.0.0.2", 0), handler) as site:
        threading.Thread(target=site.serve_forever, daemon=True).start()
        try:
            done = subprocess.run([threejs["node"], str(threejs["js"] / "page_result.mjs"),
                                   f"http://127.0.0.2:{site.server_address[1]}/index.html", str(tmp_path / "out.json")],
                                  capture_output=True, text=True, timeout=120,
                                  env={**os.environ, "CGASKIN_CHROMIUM": threejs["chromium"]})
        finally:
            site.shutdown()
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads((tmp_path / "out.json").read_text())["result"]
    assert result == {"none": "refused", "guessed": "refused", "known": "refused"}, result


def test_listening_on_every_interface_answers_only_to_this_machines_names(fox):
    require(MISSING, "cgaskin serve's tests")
    with Server(fox[1], host="0.0.0.0", port=0) as everywhere:     # (requests only from loopback here)
        port, token = everywhere.address[1], everywhere.token
        assert _status(port, f"/?token={token}", [("Host", f"127.0.0.1:{port}")])[0] == 200
        assert _status(port, f"/?token={token}", [("Host", f"{socket.gethostname()}:{port}")])[0] == 200
        for rebound in ("attacker.example", "192.0.2.7", f"attacker.example:{port}"):    # DNS rebinding
            assert _status(port, f"/?token={token}", [("Host", rebound)])[0] == 403, rebound


def test_a_port_in_use_exits_with_one_line(fox):
    require(MISSING, "cgaskin serve's tests")
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        done = subprocess.run([sys.executable, "-m", "cgaskin", "serve", str(fox[0]), "--port",
                               str(taken.getsockname()[1])], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.count("\n") == 1 and "address already in use" in done.stderr and "--port" in done.stderr


def test_it_binds_localhost_unless_told(fox, monkeypatch, capsys):
    require(MISSING, "cgaskin serve's tests")
    path, _ = fox
    bound = []

    def once(self, announce=print):               # (run() serves until Ctrl-C: bind, announce, stop)
        with self:
            bound.append(self.address[0])
            announce(self.url)

    monkeypatch.setattr(Server, "run", once)
    assert main(["serve", str(path), "--port", "0"]) == 0
    assert main(["serve", str(path), "--port", "0", "--host", "127.0.0.2", "--clip", "Run"]) == 0
    out = capsys.readouterr().out
    assert bound == ["127.0.0.1", "127.0.0.2"]
    assert "cgaskin serve: http://127.0.0.1:" in out and "http://127.0.0.2:" in out
    assert main(["serve", str(path), "--clip", "Jump"]) == 2


def test_the_protocol_checks_every_field():
    tear = parse('{"id": 3, "op": "tear", "from": [[0, 0, 0], [0, 0, 1]], "to": [[1, 0, 0], [1, 0, 1]], '
                 '"clip": "Walk", "time": 0.5, "dilations": {"b_Head_05": 1.5}}')
    assert isinstance(tear, Tear) and tear.id == 3 and tear.scalpel_to.shape == (2, 3)
    assert tear.scalpel_from.dtype == np.float64 and tear.pose == ("Walk", 0.5, (("b_Head_05", 1.5),))
    assert isinstance(parse('{"op": "cut", "normal": [1, 0, 0], "point": [0, 0, 0], "cap": true}'), Cut)
    drill = parse('{"op": "drill", "start": [0, 0, 0], "end": [0, 0, 1], "radius": 0.1}')
    assert isinstance(drill, Drill) and drill.wall is True and drill.pose.clip is None
    bad = {'{"op": "tear", "from": [[0, 0], [0, 0, 1]], "to": [[1, 0, 0], [1, 0, 1]]}': "from[0] must be a list of 3",
           '{"op": "cut", "normal": [1, 0, false], "point": [0, 0, 0]}': "normal[2] must be a number",
           '{"op": "cut", "normal": [1, 0, 0], "point": [0, 0, 0], "time": -1}': "time must be >= 0",
           '{"op": "cut", "normal": [1, 0, 0], "point": [0, 0, 0], "dilations": {"a": 0}}': "give a factor",
           '{"op": "cut", "normal": [1, 0, 0], "point": [0, 0, Infinity]}': "not a JSON number",
           '{"op": "cut", "normal": [1, 0, 0], "point": [0, 0, 1e13]}': "within",
           '{"op": "drill", "start": [0, 0, 0], "end": [0, 0, 1], "radius": 0}': "radius must be > 0",
           '{"op": "undo", "path": "x"}': "unknown field",
           '{"op": "tear", "id": 1.5}': "id 1.5",
           '{"op": "cut", "normal": [1, 0, 0], "point": [0, 0, 0], "clip": ""}': "clip must be a string"}
    for text, words in bad.items():
        with pytest.raises(ProtocolError, match=words.replace("[", r"\[").replace("]", r"\]")):
            parse(text)
    with pytest.raises(ProtocolError, match="limit"):
        parse(" " * (MAX_MESSAGE + 1))
    try:
        parse('{"id": 9, "op": "drill"}')
    except ProtocolError as exc:
        assert exc.id == 9                        # (the error reply names the request)
