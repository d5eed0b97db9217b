"""What one `cgaskin serve` grants its pages (``cgaskin.serve.Limits``): tabs at once, an operation's
predicted size and a session's, the undo log's memory; and one tab's long work never holds up another
tab's replies. Over a limit: an error reply (kind ``LimitError``) and the session as it was."""
import json
import time

import numpy as np
import pytest

import cgaskin
from cgaskin.errors import InvalidInputError
from cgaskin.serve import Limits, Server, Tab

from tests.helpers.requirements import require

from .test_serve import MISSING

ARM = dict(rings_per_segment=12, segments_around=16)


def _blade(x, y):
    return [[x, y, 1.0], [x, y, 0.0]]


def _send(tab, **message):
    return json.loads(tab.handle(json.dumps(message)))


def test_an_operation_starts_only_below_the_sessions_vertex_limit_and_over_it_changes_nothing():
    rig = cgaskin.capsule_arm(**ARM)
    tab = Tab(rig, Limits(max_vertices=rig.n_vertices + 1))
    first = _send(tab, id=1, op="tear", **{"from": _blade(1.0, 0.05), "to": _blade(1.5, 0.05)})
    assert first["ok"], first
    grown = tab.surgery.n_vertices
    assert grown > rig.n_vertices + 1
    over = _send(tab, id=2, op="tear", **{"from": _blade(0.4, 0.05), "to": _blade(0.8, 0.05)})
    assert over["ok"] is False and over["kind"] == "LimitError" and f"{grown} vertices" in over["error"], over
    assert tab.surgery.n_vertices == grown and tab.surgery.n_operations == 1
    assert _send(tab, id=3, op="undo")["ok"] and tab.surgery.n_vertices == rig.n_vertices   # undo is always granted


def test_a_drill_predicted_over_the_operation_limit_is_refused_before_it_runs():
    rig = cgaskin.capsule_arm(**ARM)
    bit = {"op": "drill", "start": [1.0, 0, -1.0], "end": [1.0, 0, 1.0], "radius": 0.1}
    granted = _send(Tab(rig), id=1, **bit)
    assert granted["ok"], granted
    made = granted["delta"]["n_vertices"] - rig.n_vertices
    tab = Tab(rig, Limits(max_new_vertices=made - 1))      # (the prediction bounds what a drill makes)
    refused = _send(tab, id=2, **bit)
    assert refused["ok"] is False and refused["kind"] == "LimitError" and "new vertices" in refused["error"], refused
    assert tab.surgery.n_operations == 0 and tab.surgery.n_vertices == rig.n_vertices


def test_a_model_at_the_vertex_limit_and_limits_that_are_not_positive_integers_are_refused():
    rig = cgaskin.capsule_arm(**ARM)
    with pytest.raises(InvalidInputError, match="max_vertices"):
        Server(rig, port=0, limits=Limits(max_vertices=rig.n_vertices))
    for bad in (Limits(max_tabs=0), Limits(max_undo_bytes=-1), Limits(max_new_vertices=1.5), Limits(max_tabs=True)):
        with pytest.raises(InvalidInputError, match="Limits"):
            Server(rig, port=0, limits=bad)


def test_the_undo_log_keeps_within_its_bytes_and_undo_still_restores_what_it_keeps():
    rig = cgaskin.capsule_arm(**ARM)
    planes = [([1, 0, 0], [x, 0, 0]) for x in (0.7, 1.4, 2.1)]
    unbounded = cgaskin.Surgery(rig)
    states = []
    for normal, point in planes:
        states.append(unbounded.rig)
        unbounded.cut(normal, point)
    one_cut = cgaskin.Surgery(rig)._state()         # what one record of a cut holds: the whole mesh before it
    from cgaskin.surgery.session_undo import held_bytes
    bounded = cgaskin.Surgery(rig, max_undo_bytes=int(1.5 * held_bytes(one_cut)))
    for normal, point in planes:
        bounded.cut(normal, point)
    assert unbounded.n_operations == 3 and unbounded.undo_dropped == 0
    assert bounded.n_operations == 1 and bounded.undo_dropped == 2
    np.testing.assert_array_equal(bounded.rig.vertices, unbounded.rig.vertices)
    bounded.undo()                                  # back to before the third cut
    np.testing.assert_array_equal(bounded.rig.vertices, states[2].vertices)
    np.testing.assert_array_equal(bounded.rig.faces, states[2].faces)
    with pytest.raises(InvalidInputError, match="nothing to undo"):
        bounded.undo()
    with pytest.raises(InvalidInputError, match="max_undo_bytes"):
        cgaskin.Surgery(rig, max_undo_bytes=-1)


def test_a_tab_over_the_limit_gets_503_and_a_closed_tab_frees_its_place():
    require(MISSING, "cgaskin serve's tests")
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect
    with Server(cgaskin.capsule_arm(**ARM), port=0, limits=Limits(max_tabs=2)) as server:
        url = server.url.replace("http://", "ws://")
        with connect(url) as first, connect(url) as second:
            for ws in (first, second):
                ws.send('{"op": "hello"}')
                assert json.loads(ws.recv(timeout=30))["limits"]["max_tabs"] == 2
            with pytest.raises(InvalidStatus) as refused:
                connect(url)
            assert refused.value.response.status_code == 503 and b"tabs are open" in refused.value.response.body
            first.close()
            deadline = time.monotonic() + 10
            while server.open_tabs > 1 and time.monotonic() < deadline:
                time.sleep(0.02)
            with connect(url) as third:
                third.send('{"op": "hello"}')
                assert json.loads(third.recv(timeout=30))["ok"]


def test_one_tabs_long_work_does_not_hold_up_another_tabs_replies():
    require(MISSING, "cgaskin serve's tests")
    from websockets.sync.client import connect
    rig = cgaskin.capsule_arm(rings_per_segment=120, segments_around=128)        # 46k vertices: a cut ~0.5 s
    with Server(rig, port=0) as server:
        url = server.url.replace("http://", "ws://")
        with connect(url, max_size=None) as busy, connect(url, max_size=None) as other:
            for ws in (busy, other):
                ws.send('{"op": "hello"}')
                assert json.loads(ws.recv(timeout=120))["ok"]
            started = time.perf_counter()
            busy.send(json.dumps({"id": "cut", "op": "cut", "normal": [1, 0, 0], "point": [1.1, 0, 0]}))
            time.sleep(0.05)                          # (the cut under way)
            sent = time.perf_counter()
            other.send('{"id": "undo", "op": "undo"}')   # (nothing to undo: an instant error reply)
            quick = json.loads(other.recv(timeout=120))
            waited = time.perf_counter() - sent
            assert quick["id"] == "undo" and quick["ok"] is False and "nothing to undo" in quick["error"]
            cut = json.loads(busy.recv(timeout=120))
            took = time.perf_counter() - started
            assert cut["ok"] and cut["operations"] == 1
            # (with one worker for every tab, the undo's reply waited for the rest of the cut: 0.36 s of 0.45)
            assert waited < took / 3, (waited, took)
