"""The server of ``cgaskin serve``: one port, plain HTTP for the page and a WebSocket for the surgery.

``websockets`` (>= 14, the ``serve`` extra) answers both: ``process_request`` sees every request first
and returns the page for ``GET /`` (built once: the viewer page of ``cgaskin view`` in its serve mode,
everything inlined, so the page makes no other request), 404 for any other path, and lets WebSocket
upgrades through to ``Server.connection``. No part of a URL or a message ever reaches the file system.

Why the checks: a server on 127.0.0.1 is still reachable from any web page the user opens (a script
there may open ws://127.0.0.1:PORT, a sandboxed iframe or a file:// page sends ``Origin: null``, and a
DNS name rebound to this machine may fetch the page). So every request needs the per-launch secret
token of the URL the server prints (``?token=...``, as Jupyter does): neither a foreign page nor a
guessed port is enough. Besides, a request's one Host header must name this server (a loopback name
when it listens on loopback; else its address or this machine's names) at its port, and a browser's
Origin, which it always sends with a WebSocket handshake, must be this page's own (``null`` is not).
A client without a browser sends no Origin, and the token in the WebSocket's URL.

Each tab's operations run on a worker thread of their own (``_pool``, one per tab allowed), one at a
time per tab: the event loop stays free, and one tab's drill never holds up another tab's replies
(cgaskin's kernels release the GIL; the per-rig caches they share are built by whichever asks first).
What a tab may ask for is bounded by ``Limits`` (``limits.py``): tabs at once, an operation's
predicted size, a session's size and its undo memory.
"""
from __future__ import annotations

import asyncio
import functools
import hmac
import http
import ipaddress
import secrets
import socket
import threading
from concurrent.futures import ThreadPoolExecutor
from urllib.parse import parse_qs, urlsplit

from ..errors import InvalidInputError
from ..view.model import as_rig, clip_name, rig_glb, rim_edges
from ..view.page import page_html
from .limits import Limits
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
    """The page ``cgaskin serve`` sends: the viewer with the surgery panel, the model embedded.

    Parameters
    ----------
    rig : Rig
        The model.
    clip : str or int, optional
        The clip the page plays (default: the first).

    Returns
    -------
    str
        A self-contained HTML page (three.js and the model inside).

    Examples
    --------
    >>> page = cgaskin.serve.serve_page(cgaskin.capsule_arm(), clip="wave")
    >>> page.startswith("<!doctype html>")
    True
    """
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


def _address(host: str) -> str:
    """An address in one spelling (``::1`` and ``0:0::1`` alike); a name as it is, lower case."""
    try:
        return str(ipaddress.ip_address(host.strip("[]")))
    except ValueError:
        return host.lower().rstrip(".")


@functools.lru_cache(maxsize=1)
def _this_machine() -> frozenset:
    """This machine's names and the addresses they resolve to (what a request to a server listening on
    every interface names); looked up once, not at every request."""
    names = {socket.gethostname(), socket.getfqdn()}
    try:
        names |= {info[4][0] for name in list(names) for info in socket.getaddrinfo(name, None)}
    except OSError:
        pass
    return frozenset(_address(name) for name in names if name)


class Server:
    """``cgaskin serve``: the page and its WebSocket, one ``Tab`` (one ``Surgery``) per connection.

    ``run()`` serves until interrupted; ``start()`` serves on a thread (tests, notebooks) until
    ``close()`` (or as a context manager); ``url`` is the page's address once bound, with the token
    every request needs.

    Parameters
    ----------
    model : Rig or str or os.PathLike
        The model, or a model file.
    host : str, optional
        The address to listen on (default: loopback only).
    port : int, optional
        0 for any free port.
    clip : str or int, optional
        The clip the page plays (default: the first).
    limits : Limits, optional
        What the server grants its pages.

    Raises
    ------
    InvalidInputError
        A bad port, host or limits, or a model at least ``limits.max_vertices`` large.

    Examples
    --------
    >>> import urllib.request
    >>> with cgaskin.serve.Server(cgaskin.capsule_arm(), port=0) as server:
    ...     with urllib.request.urlopen(server.url) as reply:
    ...         print(reply.status, server.url.startswith("http://127.0.0.1:"))
    200 True
    """

    def __init__(self, model, host: str = "127.0.0.1", port: int = 8765, clip=None, limits: Limits = Limits()):
        if not isinstance(port, int) or not 0 <= port <= 65535:
            raise InvalidInputError(f"port {port!r}: give 0 (any free port) to 65535")
        if not isinstance(host, str) or not host:
            raise InvalidInputError(f"host {host!r}: give a host name or address, e.g. 127.0.0.1")
        if not isinstance(limits, Limits):
            raise InvalidInputError(f"limits must be a cgaskin.serve.Limits, got {type(limits).__name__}")
        self.rig, self.limits = as_rig(model), limits.checked()
        limits.check_model(self.rig.n_vertices)
        self.host, self.port = host, port
        self.page = serve_page(self.rig, clip).encode("utf-8")
        self.address = None               # (host, port) bound
        self.token = secrets.token_urlsafe(24)      # in the URL: every request must carry it
        self.tabs = 0                     # connections served so far
        self.open_tabs = 0                # connections open now
        self._pool = ThreadPoolExecutor(max_workers=limits.max_tabs, thread_name_prefix="cgaskin-surgery")
        self._thread = self._loop = self._stop = None

    @property
    def url(self) -> str:
        """The page's address, with the token every request needs."""
        host, port = self.address
        return f"http://{f'[{host}]' if ':' in host else host}:{port}/?token={self.token}"

    # ---- HTTP ---------------------------------------------------------------------------------------
    def _refused(self, request) -> tuple | None:
        """(HTTP status, why) when ``request`` does not name this server, comes from another page than
        its own, or lacks the token; None when it may go on."""
        hosts = request.headers.get_all("Host")
        if len(hosts) != 1:
            return http.HTTPStatus.BAD_REQUEST, f"{len(hosts)} Host headers: a request has one"
        try:
            named = urlsplit(f"//{hosts[0]}")
            hostname, port = named.hostname or "", named.port
        except ValueError:
            return http.HTTPStatus.BAD_REQUEST, f"Host {hosts[0]!r} is no host[:port]"
        if port not in (None, self.address[1]) or not self._serves(hostname):
            return http.HTTPStatus.FORBIDDEN, f"Host {hosts[0]!r}: not this server's address"
        origins = request.headers.get_all("Origin")
        if origins and (len(origins) > 1 or origins[0].lower() != f"http://{hosts[0]}".lower()):
            return http.HTTPStatus.FORBIDDEN, f"Origin {', '.join(origins)!r}: only this server's own page connects"
        try:
            token = parse_qs(urlsplit(request.path).query).get("token", [""])[-1]
        except ValueError:
            token = ""
        if not hmac.compare_digest(token.encode(), self.token.encode()):
            return http.HTTPStatus.FORBIDDEN, "open the address that cgaskin serve printed (its token)"
        return None

    def _serves(self, hostname: str) -> bool:
        """Whether a request naming ``hostname`` is for this server (a DNS name rebound to its address is
        not): a loopback name when it listens on loopback, else its address or this machine's names."""
        if _loopback(self.host):
            return _loopback(hostname)
        if _address(hostname) == _address(self.host) or _loopback(hostname):
            return True
        wildcard = _address(self.host) in ("0.0.0.0", "::")
        return wildcard and _address(hostname) in _this_machine()

    def process_request(self, connection, request):
        _, Headers, Response = _websockets()
        refused = self._refused(request)
        if refused is not None:
            return connection.respond(refused[0], f"{refused[1]}\n")
        if request.headers.get("Upgrade", "").lower() == "websocket":
            if self.open_tabs >= self.limits.max_tabs:
                return connection.respond(http.HTTPStatus.SERVICE_UNAVAILABLE, f"{self.open_tabs} tabs are open, this "
                                          f"server's limit (close one, or serve with a higher max_tabs)\n")
            return None                                          # (on to the handshake)
        if urlsplit(request.path).path != PAGE_PATH:
            return connection.respond(http.HTTPStatus.NOT_FOUND, "cgaskin serve has one page: /\n")
        headers = Headers([("Content-Type", "text/html; charset=utf-8"), ("Content-Length", str(len(self.page))),
                           ("Cache-Control", "no-store"), ("X-Content-Type-Options", "nosniff")])
        return Response(http.HTTPStatus.OK, "OK", headers, self.page)

    # ---- WebSocket ----------------------------------------------------------------------------------
    async def connection(self, websocket) -> None:
        """Serve one tab: its own session; each message answered in order, on a worker thread.

        Parameters
        ----------
        websocket : websockets.asyncio.server.ServerConnection
            The tab's connection.
        """
        loop = asyncio.get_running_loop()
        self.tabs += 1
        self.open_tabs += 1
        try:
            tab = await loop.run_in_executor(self._pool, Tab, self.rig, self.limits)
            async for message in websocket:
                await websocket.send(await loop.run_in_executor(self._pool, tab.handle, message))
        except ConnectionClosed:        # (a tab closed mid-reply, or a frame over MAX_FRAME: websockets closed it)
            pass
        finally:
            self.open_tabs -= 1

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
        """Serve until interrupted (Ctrl-C).

        Parameters
        ----------
        announce : callable, optional
            Called with the page's URL once bound (default: ``print``).

        Raises
        ------
        InvalidInputError
            The address cannot be bound (a port in use, say).
        """
        async def main():
            task = asyncio.ensure_future(self._serve(ready := asyncio.Event()))
            waiting = asyncio.ensure_future(ready.wait())
            await asyncio.wait({task, waiting}, return_when=asyncio.FIRST_COMPLETED)
            if task.done():                 # (it failed before it was bound)
                waiting.cancel()
                task.result()
            announce(self.url)
            await task

        try:
            asyncio.run(main())
        except KeyboardInterrupt:
            pass
        except OSError as exc:
            raise self._unbound(exc) from None
        finally:
            self._pool.shutdown(wait=False, cancel_futures=True)

    def _unbound(self, exc: OSError) -> InvalidInputError:
        """The error for an address that cannot be served."""
        why = (exc.strerror or str(exc)).split(": ")[-1]
        return InvalidInputError(f"cannot serve on {self.host}:{self.port}: {why}; give another --port "
                                 "(0: any free one) or --host")

    def start(self) -> "Server":
        """Serve on a daemon thread until ``close()``; returns once the port is bound.

        Returns
        -------
        Server
            This server.
        """
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
            raise self._unbound(failed[0]) if isinstance(failed[0], OSError) else failed[0]
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
