"""What one ``cgaskin serve`` grants its pages: tabs at once, the size of an operation and of a
session, the memory of a session's undo log.

Any page that reaches the port (with the token) may ask for work, and a running compiled kernel
cannot be stopped, so the work is bounded before it runs: an operation whose predicted size is over
the budget gets an error reply (``LimitError``'s kind) and leaves the session unchanged.
What is predicted: a drill's new vertices from its bit and the mesh's resolution around it
(``surgery.drill.api.predicted_new_vertices``: the one operation whose size its parameters set);
a cut or a stroke makes at most a few vertices per face it crosses, so the session's own size bounds
them, and a session may grow to ``max_vertices`` (an operation starts only below it). A reply
carries about ``REPLY_BYTES_PER_VERTEX`` bytes per new vertex, so these bound the replies too.
"""
from __future__ import annotations

from typing import NamedTuple

from ..errors import InvalidInputError

#: the bytes of a delta per new vertex, about (position, normal, uv, joints, weights, labels in base64,
#: and the faces and rim edges that come with it)
REPLY_BYTES_PER_VERTEX = 120


class Limits(NamedTuple):
    """The bounds of one server; every field a positive integer.

    Parameters
    ----------
    max_tabs : int, optional
        Pages connected at once (one ``Surgery`` each); the next gets HTTP 503.
    max_new_vertices : int, optional
        The new vertices one operation may make (predicted before it runs).
    max_vertices : int, optional
        The vertices a tab's mesh may reach (an operation starts only below it; a model must have
        fewer).
    max_undo_bytes : int, optional
        The memory one tab's undo log may hold; past it the oldest operations can no longer be
        undone (a cut's record holds the whole mesh before it).

    Examples
    --------
    >>> limits = cgaskin.serve.Limits(max_tabs=2, max_vertices=100_000)
    >>> limits.max_new_vertices, limits.checked() is limits
    (250000, True)
    """

    max_tabs: int = 8
    max_new_vertices: int = 250_000
    max_vertices: int = 2_000_000
    max_undo_bytes: int = 256 << 20

    def checked(self) -> "Limits":
        for name, value in self._asdict().items():
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise InvalidInputError(f"Limits.{name} = {value!r}: give a positive integer")
        return self

    def check_model(self, n_vertices: int) -> None:
        """Refuse a model that leaves no room to operate.

        Parameters
        ----------
        n_vertices : int
            The model's vertex count.

        Raises
        ------
        InvalidInputError
            ``n_vertices`` is at least ``max_vertices``.
        """
        if n_vertices >= self.max_vertices:
            raise InvalidInputError(f"the model has {n_vertices} vertices, at least Limits.max_vertices "
                                    f"({self.max_vertices}): serve it with a higher max_vertices")
