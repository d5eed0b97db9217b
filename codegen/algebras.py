"""Any geometric algebra G(p, q, r) up to 6 dimensions, as exact numeric product tables.

    Algebra(signature=(p, q, r), basis="orthonormal" | "null", names=None, display=None)

p basis vectors square to +1, q to −1 and r to 0 (degenerate, as PGA's e0). Blades are bitmasks over
the basis vectors (bit k = vector k); the blade of mask m is the *outer* product of its vectors in
index order (so in a null basis e∞0 = e∞∧e0, not e∞e0).

Order of the basis vectors (the same as clifford's ``Cl(p, q, r)``): the r degenerate ones first, then
the p positive ones, then the q negative ones. ``basis="null"`` (needs p ≥ 1 and q ≥ 1) replaces the
last positive vector e+ and the last negative one e− by the null pair, put last:

    e∞ = e− + e+,   eo = (e− − e+)/2      (e∞² = eo² = 0, e∞·eo = −1; design.md §2)

so ``Algebra((4, 1, 0), "null")`` is exactly the CGA of ``codegen.algebra``: e1 e2 e3 e∞ e0.

Vector names are single characters; a blade's identifier-safe name is 'e' + its vectors' names
('s' for the scalar) and its display name 'e' + their display names ('1' for the scalar). Defaults:
vectors numbered from 1, or from 0 in an orthonormal basis with a degenerate vector (so PGA
G(3,0,1) is e0 e1 e2 e3, the klein / bivector.net convention, e0² = 0); the null pair is named
'i', 'o' and displayed '∞', '0'.

The metric is diagonal in the orthonormal basis, where the product of two basis blades is one basis
blade with a sign (0 when they share a degenerate vector). Every table is made by expanding the
blades into that basis, multiplying there, and expanding back. All coefficients are exact fractions.
"""
from __future__ import annotations

from fractions import Fraction

from ..errors import InvalidInputError

MAX_DIMENSION = 6
BASES = ("orthonormal", "null")
KINDS = ("gp", "outer", "lcontract")      # geometric, outer, left contraction (a ⌋ b)


class InvalidAlgebraError(InvalidInputError):
    """``Algebra(...)`` got a signature, basis or names it cannot build (the message names which).

    Examples
    --------
    >>> from cgaskin.codegen import Algebra, InvalidAlgebraError
    >>> try:
    ...     Algebra(signature=(7, 0, 0))
    ... except InvalidAlgebraError as error:
    ...     print(error)
    Algebra: signature=(7, 0, 0) has dimension p + q + r = 7; supported: 1 to 6
    """


def grade(mask: int) -> int:
    return bin(mask).count("1")


def reorder_sign(a: int, b: int) -> int:
    """Sign of moving the vectors of blade b past those of blade a into index order.

    Parameters
    ----------
    a, b : int
        Blade masks (bit k: basis vector k).

    Returns
    -------
    int
        +1 or -1: the sign of the product of the two blades' vectors sorted into index order.
    """
    swaps = 0
    a >>= 1
    while a:
        swaps += grade(a & b)
        a >>= 1
    return -1 if swaps & 1 else 1


def reverse_sign(mask: int) -> int:
    """Sign of the reverse of a basis blade: (−1)^(g(g−1)/2).

    Parameters
    ----------
    mask : int
        The blade's mask, of grade g.

    Returns
    -------
    int
        +1 or -1.
    """
    g = grade(mask)
    return -1 if (g * (g - 1) // 2) & 1 else 1


def involution_sign(mask: int) -> int:
    """Sign of the grade involution of a basis blade: (−1)^g.

    Parameters
    ----------
    mask : int
        The blade's mask, of grade g.

    Returns
    -------
    int
        +1 or -1.
    """
    return -1 if grade(mask) & 1 else 1


def _wedge_expand(vectors: tuple[int, ...], change: tuple[dict, ...]) -> dict[int, Fraction]:
    """Outer product of basis vectors rewritten in another basis: {mask: coefficient}."""
    terms = {0: Fraction(1)}
    for v in vectors:
        nxt: dict[int, Fraction] = {}
        for mask, coef in terms.items():
            for w, c in change[v].items():
                bit = 1 << w
                if mask & bit:
                    continue                      # repeated vector: the wedge vanishes
                key = mask | bit
                nxt[key] = nxt.get(key, 0) + coef * c * reorder_sign(mask, bit)
        terms = {k: c for k, c in nxt.items() if c}
    return terms


def _signature(signature) -> tuple[int, int, int]:
    def bad(why):
        return InvalidAlgebraError(f"Algebra: signature={signature!r} {why}")
    try:
        p, q, r = signature
    except (TypeError, ValueError):
        raise bad("must be three counts (p, q, r)") from None
    for x in (p, q, r):
        if isinstance(x, bool) or not isinstance(x, int):
            raise bad("must hold integers")
        if x < 0:
            raise bad("must hold counts >= 0")
    if not 1 <= p + q + r <= MAX_DIMENSION:
        raise bad(f"has dimension p + q + r = {p + q + r}; supported: 1 to {MAX_DIMENSION}")
    return p, q, r


def _names(given, default, what):
    if given is None:
        return default
    names = tuple(given)
    if len(names) != len(default):
        raise InvalidAlgebraError(f"Algebra: {what}={given!r} must name {len(default)} vectors")
    for n in names:
        if not isinstance(n, str) or len(n) != 1 or n.isspace():
            raise InvalidAlgebraError(f"Algebra: {what}={given!r} must be single characters, got {n!r}")
    if len(set(names)) != len(names):
        raise InvalidAlgebraError(f"Algebra: {what}={given!r} has a repeated name")
    return names


class Algebra:
    """G(p, q, r) with exact product tables, in an orthonormal or a null basis.

    Parameters
    ----------
    signature : tuple of 3 int
        (p, q, r): how many basis vectors square to +1, −1 and 0; 1 <= p + q + r <= 6.
    basis : {"orthonormal", "null"}
        "null" replaces the last +1 and −1 vectors by the null pair e∞, e0 (needs p, q >= 1).
    names : sequence of str, optional
        One identifier-safe character per vector (default: numbers, and "i", "o" for e∞, e0).
    display : sequence of str, optional
        One character per vector for readable names (default: ``names``, "∞" and "0" for e∞, e0).

    Raises
    ------
    InvalidAlgebraError
        A signature, basis or names it cannot build.

    Notes
    -----
    Holds: ``signature`` (p, q, r), ``basis``, ``dimension`` n, ``n_blades`` 2^n, ``pseudoscalar``
    (mask), ``vector_names`` / ``display_names`` (one character per vector), ``orthonormal_metric``
    (the squares of the orthonormal vectors the tables multiply in), ``metric`` (n × n exact inner
    products of the basis vectors: diagonal, or with e∞·eo = −1 in a null basis), ``to_orthonormal`` /
    ``from_orthonormal`` (the change of basis, {vector: coefficient} per vector), and computes on
    first use ``product_table(kind)`` for kind in ``KINDS``.

    Examples
    --------
    >>> from cgaskin.codegen import Algebra
    >>> sta = Algebra(signature=(1, 3, 0))                  # spacetime algebra
    >>> sta.n_blades, sta.blade_display(sta.pseudoscalar)
    (16, 'e1234')
    >>> print(Algebra((4, 1, 0), "null"))                   # CGA, the algebra of every kernel
    G(4,1,0), null basis e1 e2 e3 e∞ e0
    """

    def __init__(self, signature=(4, 1, 0), basis="orthonormal", names=None, display=None):
        p, q, r = self.signature = _signature(signature)
        if basis not in BASES:
            raise InvalidAlgebraError(f"Algebra: basis={basis!r} is not one of {BASES}")
        if basis == "null" and not (p >= 1 and q >= 1):
            raise InvalidAlgebraError(f"Algebra: basis='null' needs one +1 and one -1 vector (p >= 1 and q >= 1), "
                                      f"got signature={self.signature}")
        self.basis = basis
        n = self.dimension = p + q + r
        self.n_blades = 1 << n
        self.pseudoscalar = self.n_blades - 1
        null = basis == "null"
        # orthonormal vectors: degenerate, positive, negative (for a null basis e+ and e− last)
        if null:
            squares = (0,) * r + (1,) * (p - 1) + (-1,) * (q - 1) + (1, -1)
        else:
            squares = (0,) * r + (1,) * p + (-1,) * q
        self.orthonormal_metric = squares
        first = 0 if r and not null else 1
        default = tuple(str(first + k) for k in range(n - 2 * null)) + (("i", "o") if null else ())
        self.vector_names = _names(names, default, "names")
        default_display = default[:n - 2] + ("∞", "0") if null and names is None else self.vector_names
        self.display_names = _names(display, default_display, "display")
        self._lookup = {}
        for k, (a, b) in enumerate(zip(self.vector_names, self.display_names)):
            for ch in (a, b):
                if self._lookup.setdefault(ch, k) != k:
                    raise InvalidAlgebraError(f"Algebra: names={self.vector_names!r} and "
                                              f"display={self.display_names!r} use {ch!r} for two vectors")
        ident = tuple({k: 1} for k in range(n))
        if null:
            # e∞ = e− + e+, eo = (e− − e+)/2;  e+ = e∞/2 − eo, e− = e∞/2 + eo
            i, o = n - 2, n - 1
            self.to_orthonormal = ident[:i] + ({o: 1, i: 1}, {o: Fraction(1, 2), i: Fraction(-1, 2)})
            self.from_orthonormal = ident[:i] + ({i: Fraction(1, 2), o: -1}, {i: Fraction(1, 2), o: 1})
        else:
            self.to_orthonormal = self.from_orthonormal = ident
        self.metric = tuple(tuple(sum((Fraction(c) * self.to_orthonormal[b].get(k, 0) * squares[k]
                                       for k, c in self.to_orthonormal[a].items()), Fraction(0))
                                  for b in range(n)) for a in range(n))
        self._tables: dict[str, dict] = {}

    # -- blades --------------------------------------------------------------------------------
    grade = staticmethod(grade)
    reorder_sign = staticmethod(reorder_sign)
    reverse_sign = staticmethod(reverse_sign)
    involution_sign = staticmethod(involution_sign)

    def vectors_of(self, mask: int) -> tuple[int, ...]:
        return tuple(k for k in range(self.dimension) if mask >> k & 1)

    @property
    def blades(self) -> tuple[int, ...]:
        """Every blade mask, by grade then by vectors (1, e1, e2, ..., e12, ...)."""
        return tuple(sorted(range(self.n_blades), key=lambda m: (grade(m), self.vectors_of(m))))

    def blade_name(self, mask: int) -> str:
        """Identifier-safe name of a blade: 's' for the scalar, else e.g. 'e12i' for e1∧e2∧e∞.

        Parameters
        ----------
        mask : int
            The blade's mask.

        Returns
        -------
        str
        """
        return "s" if mask == 0 else "e" + "".join(self.vector_names[k] for k in self.vectors_of(mask))

    def blade_display(self, mask: int) -> str:
        """Readable name of a blade, for docstrings and messages: '1', 'e12∞', 'e∞0'.

        Parameters
        ----------
        mask : int
            The blade's mask.

        Returns
        -------
        str
        """
        return "1" if mask == 0 else "e" + "".join(self.display_names[k] for k in self.vectors_of(mask))

    def mask_of(self, name: str) -> int:
        """The mask of a blade named as ``blade_name`` or ``blade_display`` names it.

        Parameters
        ----------
        name : str
            's' or '1' for the scalar, else 'e' + the names of its vectors ('e12i', 'e∞0').

        Returns
        -------
        int

        Raises
        ------
        InvalidAlgebraError
            A name that is not 'e' + distinct vector names.
        """
        if name in ("s", "1"):
            return 0
        if not isinstance(name, str) or not name.startswith("e") or len(name) < 2:
            raise InvalidAlgebraError(f"{self!r}: blade name {name!r} is not 's', '1' or 'e' + vector names")
        mask = 0
        for ch in name[1:]:
            k = self._lookup.get(ch)
            if k is None or mask >> k & 1:
                raise InvalidAlgebraError(f"{self!r}: blade name {name!r}: {ch!r} is not a vector "
                                          f"({''.join(self.vector_names)}) or is repeated")
            mask |= 1 << k
        return mask

    # -- products ------------------------------------------------------------------------------
    def _ortho_product(self, a: int, b: int, kind: str) -> tuple[int, int] | None:
        """Product of two orthonormal basis blades: (mask, sign) or None when it vanishes."""
        if kind == "outer" and a & b:
            return None
        if kind == "lcontract" and a & b != a:
            return None
        sign = reorder_sign(a, b)
        for k in self.vectors_of(a & b):
            sign *= self.orthonormal_metric[k]
        return (a ^ b, sign) if sign else None

    def product_table(self, kind: str) -> dict[tuple[int, int], tuple[tuple[int, Fraction], ...]]:
        """The exact product of every pair of basis blades, computed on first use.

        Parameters
        ----------
        kind : {"gp", "outer", "lcontract"}
            Geometric product, outer product or left contraction.

        Returns
        -------
        dict
            ``{(mask_a, mask_b): ((mask, Fraction), ...)}``: the blades of a b and their coefficients.
        """
        if kind not in KINDS:
            raise InvalidAlgebraError(f"{self!r}.product_table: kind={kind!r} is not one of {KINDS}")
        if kind not in self._tables:
            self._tables[kind] = self._make_table(kind)
        return self._tables[kind]

    def _make_table(self, kind):
        blades = range(self.n_blades)
        to_ortho = [_wedge_expand(self.vectors_of(m), self.to_orthonormal) for m in blades]
        to_basis = [_wedge_expand(self.vectors_of(m), self.from_orthonormal) for m in blades]
        table = {}
        for a in blades:
            for b in blades:
                ortho: dict[int, Fraction] = {}
                for oa, ca in to_ortho[a].items():
                    for ob, cb in to_ortho[b].items():
                        hit = self._ortho_product(oa, ob, kind)
                        if hit:
                            ortho[hit[0]] = ortho.get(hit[0], 0) + ca * cb * hit[1]
                out: dict[int, Fraction] = {}
                for om, c in ortho.items():
                    for nm, cn in to_basis[om].items():
                        out[nm] = out.get(nm, 0) + c * cn
                table[a, b] = tuple(sorted((m, Fraction(c)) for m, c in out.items() if c))
        return table

    # -- identity ------------------------------------------------------------------------------
    def _key(self):
        return self.signature, self.basis, self.vector_names, self.display_names

    def __eq__(self, other):
        return isinstance(other, Algebra) and self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def __repr__(self):
        return f"Algebra(signature={self.signature}, basis={self.basis!r})"

    def __str__(self):
        p, q, r = self.signature
        vectors = " ".join("e" + d for d in self.display_names)
        return f"G({p},{q},{r}), {self.basis} basis {vectors}"


cga = Algebra(signature=(4, 1, 0), basis="null")
"""Conformal G(4,1): e1 e2 e3 e∞ e0 (e∞ = e− + e+, e0 = (e− − e+)/2) — the algebra of every kernel."""

pga = Algebra(signature=(3, 0, 1))
"""Projective G(3,0,1): e0 e1 e2 e3 with the degenerate e0 first (e0² = 0), as klein and clifford's Cl(3, 0, 1)."""
