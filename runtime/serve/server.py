"""The server of ``cgaskin serve``: one port, plain HTTP for the page and a WebSocket for the surgery.

``websockets`` (>= 14, the ``serve`` extra) answers both: ``process_request`` sees every request first
and returns the page for ``GET /`` (built once: the viewer page of ``cgaskin view`` in its serve mode,
everything inlined, so the page makes no other request), 404 for any other path, and lets WebSocket
upgrades through to ``Server.connection``. No part of a URL or a message ever reaches the file system.

Why the checks on Host and Origin: a server on 127.0.0.1 is still reachable from any web page the
user opens (a script there may open ws://127.0.0.1:PORT, and a DNS name rebound to 127.0.0.1 may
fetch the page). A browser always sends Origin with a WebSocket handshake, so the handshake must come
from this server's own page; and on a loopback address the Host must name a loopback host.

The surgery runs on one worker thread (``_pool``): the event loop stays free to answer other tabs and
pings while a drill computes, and sessions never run at the same time (numba kernels and the shared
caches see one operation at a time).
"""
from __future__ import annotations

import asyncio
import http
import ipaddress
import threading
from concurrent.futures import ThreadPoolExecutor
from urllib.parse import urlsplit

from ..errors import InvalidInputError
from ..view.model import as_rig, clip_name, rig_glb, rim_edges
from ..view.page import page_html
from .tab import Tab

try:
    from websockets.exceptions import ConnectionClosed
except ImportError:                     # (Server says which extra to install when it starts)
    ConnectionClosed = OSError

#: websockets closes a connection on a frame larger than this (1009, "message too big"); messages up
#: to it that are over protocol.MAX_MESSAGE get an error reply
MAX_FRAME = 1 << 20
#: the only path that answers with something: the page
PAGE_PATH = "/"


def _websockets():
    try:
        from websockets.asyncio.server import serve
        from websockets.datastructures import Headers
        from websockets.http11 import Response
    except ImportError:
        raise InvalidInputError("cgaskin serve needs websockets >= 14: pip install 'cgaskin[serve]'") from None
    return serve, Headers, Response


def serve_page(rig, clip=None) -> str:
    """The page ``cgaskin serve`` sends: the viewer with the surgery panel, ``rig`` embedded, playing
    ``clip`` (default: the first)."""
    name = clip_name(rig, clip)
    return page_html(rig_glb(rig), name=rig.name or "model", rims=rim_edges(rig).reshape(-1), clip=name,
                     play=name is not None, skinning="cgaskin", serve=True)


def _loopback(host: str) -> bool:
    if host in ("localhost", "localhost."):
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


class Server:
    """``cgaskin serve`` on ``model`` (a Rig or a model path) at ``host``:``port`` (port 0: any free
    port). ``run()`` serves until interrupted; ``start()`` serves on a thread (tests, notebooks) until
    ``close()``; ``url`` is the page's address once bound."""

    def __init__(self, model, host: str = "127.0.0.1", port: int = 8765, clip=None):
        if not isinstance(port, int) or not 0 <= port <= 65535:
            raise InvalidInputError(f"port {port!r}: give 0 (any free port) to 65535")
        if not isinstance(host, str) or not host:
            raise InvalidInputError(f"host {host!r}: give a host name or address, e.g. 127.0.0.1")
        self.rig = as_rig(model)
        self.host, self.port = host, port
        self.page = serve_page(self.rig, clip).encode("utf-8")
        self.address = None               # (host, port) bound
        self.tabs = 0                     # connections served so far
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="cgaskin-surgery")
        self._thread = self._loop = self._stop = None

    @property
    def url(self) -> str:
        host, port = self.address
        return f"http://{f'[{host}]' if ':' in host else host}:{port}/"

    # ---- HTTP ---------------------------------------------------------------------------------------
    def _allowed(self, request) -> str | None:
        """Why a request is refused (None: allowed)."""
        host = request.headers.get("Host", "")
        if _loopback(self.host):
            hostname = urlsplit(f"//{host}").hostname or ""
            if not _loopback(hostname):
                return f"Host {host!r}: this server answers only to a loopback name"
        origin = request.headers.get("Origin")
        if origin is not None and origin != "null" and urlsplit(origin).netloc != host:
            return f"Origin {origin!r}: only this server's own page may connect"
        return None

    def process_request(self, connection, request):
        _, Headers, Response = _websockets()
        refused = self._allowed(request)
        if refused:
            return connection.respond(http.HTTPStatus.FORBIDDEN, refused + "\n")
        if request.headers.get("Upgrade", "").lower() == "websocket":
            return None                                          # (on to the handshake)
        if urlsplit(request.path).path != PAGE_PATH:
            return connection.respond(http.HTTPStatus.NOT_FOUND, "cgaskin serve has one page: /\n")
        headers = Headers([("Content-Type", "text/html; charset=utf-8"), ("Content-Length", str(len(self.page))),
                           ("Cache-Control", "no-store"), ("X-Content-Type-Options", "nosniff")])
        return Response(http.HTTPStatus.OK, "OK", headers, self.page)

    # ---- WebSocket ----------------------------------------------------------------------------------
    async def connection(self, websocket) -> None:
        """One tab: its own session; each message answered in order."""
        loop = asyncio.get_running_loop()
        self.tabs += 1
        tab = await loop.run_in_executor(self._pool, Tab, self.rig)
        try:
            async for message in websocket:
                await websocket.send(await loop.run_in_executor(self._pool, tab.handle, message))
        except ConnectionClosed:        # (a tab closed mid-reply, or a frame over MAX_FRAME: websockets closed it)
            pass

    async def _serve(self, ready=None) -> None:
        serve, _, _ = _websockets()
        self._loop, self._stop = asyncio.get_running_loop(), asyncio.get_running_loop().create_future()
        async with serve(self.connection, self.host, self.port, process_request=self.process_request,
                         max_size=MAX_FRAME, compression=None) as server:
            self.address = server.sockets[0].getsockname()[:2]
            if ready is not None:
                ready.set()
            await self._stop

    def run(self, announce=print) -> None:
        """Serve until interrupted (Ctrl-C); ``announce`` gets the page's URL once bound."""
        async def main():
            task = asyncio.ensure_future(self._serve(ready := asyncio.Event()))
            await ready.wait()
            announce(self.url)
            await task

        try:
            asyncio.run(main())
        except KeyboardInterrupt:
            pass
        finally:
            self._pool.shutdown(wait=False, cancel_futures=True)

    def start(self) -> "Server":
        """Serve on a daemon thread; returns once the port is bound."""
        ready, failed = threading.Event(), []

        def target():
            try:
                asyncio.run(self._serve(ready))
            except BaseException as exc:          # (a port in use: reported to start's caller)
                failed.append(exc)
                ready.set()

        self._thread = threading.Thread(target=target, name="cgaskin-serve", daemon=True)
        self._thread.start()
        ready.wait()
        if failed:
            raise failed[0]
        return self

    def close(self) -> None:
        if self._loop is not None and self._stop is not None:
            self._loop.call_soon_threadsafe(lambda: self._stop.done() or self._stop.set_result(None))
        if self._thread is not None:
            self._thread.join(timeout=10)
        self._pool.shutdown(wait=False, cancel_futures=True)

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.close()
