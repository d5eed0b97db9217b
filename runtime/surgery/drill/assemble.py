"""The drilled rig from the patch (steps 4 and 5 of ``api.py``): which input faces and vertices it keeps,
the new vertices' weights, attributes and rest positions, the wall rows' normals.

The bookkeeping over the whole mesh is one compiled pass (``_layout``), each per-vertex array one
compiled gather (``stacked``) into an array made here: the same work a cut does to assemble its halves.
"""
from __future__ import annotations

import math
from functools import partial
from typing import NamedTuple

import numpy as np

from ..._shared.frozen import kernel_array
from ..._shared.jit import B1, F1, F2, I1, I2, helper, i8, kernel
from ..._shared.memory import recycled_empty
from ..._shared.warn import warn
from ...animation.rig import Rig
from ...errors import PlacementWarning
from ...tolerances import tol
from ..gather import gather_rows
from ..new_vertices import LINEAR, NewVertices, attribute_rule, place_in_rest
from ..surface import mesh_arrays
from .patch import Patch, descriptions, row_skins, row_values
from .result import NEW_VERTEX, DrillResult
from .wall import WALL


class Layout(NamedTuple):
    """What ``_layout`` decides (it returns the fields as a plain tuple).

    faces : (G, 3) int64 the result's faces: the input faces kept, in order, then the patch's faces that
        are not an input face as it was ; made_in : (k,) int64 the input face each of those lies in (-1:
        a wall's) ; replaced : (t,) int64 the input faces not kept (ascending)
    kept_input : (a,) int64 the input vertices the result uses (ascending): its first vertices
    new_rows : (b,) int64 the patch's new rows it uses (ascending): its vertices after them
    skin_rows : (b,) int64 for each of those, the first of them at the same point (itself if none): the
        copies of a new vertex at one point skin alike ; positions : (b, 3) float64 their points
    on_wall : (b,) bool whether a wall face uses it ; row_out : (R,) int64 each row's output vertex (-1)
    """

    faces: np.ndarray
    made_in: np.ndarray
    replaced: np.ndarray
    kept_input: np.ndarray
    new_rows: np.ndarray
    skin_rows: np.ndarray
    positions: np.ndarray
    on_wall: np.ndarray
    row_out: np.ndarray


@kernel((I2, i8, I1, I2, I1, I1, I1, F2), cost=0.9)
def _layout(faces, n, taken, rows, sources, row_vertex, row_point, points):
    """The result's faces and vertices (``Layout``, as a plain tuple) from the input ``faces`` (m, 3) over
    ``n`` vertices, the input faces the patch ``taken`` (T,), the patch's faces ``rows`` (F, 3) from
    input faces ``sources`` (F,), its rows' input vertices ``row_vertex`` (R,) (-1: new) and points
    ``row_point`` (R,) of ``points`` (P, 3). A patch face that is its input face as it was (its corners, in
    their order) keeps that face's place."""
    m, n_rows = faces.shape[0], row_vertex.shape[0]
    kept = np.ones(m, np.bool_)
    kept[taken] = False
    changed = np.ones(rows.shape[0], np.bool_)
    for f in range(rows.shape[0]):
        s = sources[f]
        if s >= 0 and (row_vertex[rows[f, 0]] == faces[s, 0] and row_vertex[rows[f, 1]] == faces[s, 1]
                       and row_vertex[rows[f, 2]] == faces[s, 2]):
            changed[f], kept[s] = False, True
    # output ids: input vertices first (ascending), then the new rows used (ascending)
    uses_vertex, uses_row = np.zeros(n, np.bool_), np.zeros(n_rows, np.bool_)
    n_kept = 0
    for f in range(m):
        if kept[f]:
            uses_vertex[faces[f, 0]] = uses_vertex[faces[f, 1]] = uses_vertex[faces[f, 2]] = True
            n_kept += 1
    on_wall_row = np.zeros(n_rows, np.bool_)
    for f in range(rows.shape[0]):
        if changed[f]:
            for k in range(3):
                r = rows[f, k]
                if row_vertex[r] >= 0:
                    uses_vertex[row_vertex[r]] = True
                else:
                    uses_row[r] = True
                    if sources[f] <= WALL:
                        on_wall_row[r] = True
    vertex_out, kept_input = np.full(n, -1, np.int64), np.flatnonzero(uses_vertex)
    for i in range(kept_input.shape[0]):
        vertex_out[kept_input[i]] = i
    new_rows = np.flatnonzero(uses_row)
    row_out = np.full(n_rows, -1, np.int64)
    first_at_point = np.full(points.shape[0], -1, np.int64)
    skin_rows, on_wall = np.empty(new_rows.shape[0], np.int64), np.empty(new_rows.shape[0], np.bool_)
    positions = np.empty((new_rows.shape[0], 3))
    for j in range(new_rows.shape[0]):
        r, p = new_rows[j], row_point[new_rows[j]]
        row_out[r] = kept_input.shape[0] + j
        if first_at_point[p] < 0:
            first_at_point[p] = r
        skin_rows[j], on_wall[j] = first_at_point[p], on_wall_row[r]
        positions[j, 0], positions[j, 1], positions[j, 2] = points[p, 0], points[p, 1], points[p, 2]
    for r in range(n_rows):
        if row_vertex[r] >= 0:
            row_out[r] = vertex_out[row_vertex[r]]
    n_changed = 0
    for f in range(rows.shape[0]):
        n_changed += changed[f]
    out, made_in = np.empty((n_kept + n_changed, 3), np.int64), np.empty(n_changed, np.int64)
    at = 0
    for f in range(m):
        if kept[f]:
            for k in range(3):
                out[at, k] = vertex_out[faces[f, k]]
            at += 1
    for f in range(rows.shape[0]):
        if changed[f]:
            for k in range(3):
                out[at, k] = row_out[rows[f, k]]
            made_in[at - n_kept] = max(sources[f], -1)
            at += 1
    return out, made_in, np.flatnonzero(~kept), kept_input, new_rows, skin_rows, positions, on_wall, row_out


@kernel((F2, I1, F2, F2), (I2, I1, I2, I2), cost=0.3)
def _stacked_into(values, src, extra, out):
    """out (a + b, c) := the rows ``values[src]`` (values (n, c), src (a,)), then ``extra`` (b, c)."""
    a, c = src.shape[0], values.shape[1]
    gather_rows(values, src, out)
    for i in range(extra.shape[0]):
        for j in range(c):
            out[a + i, j] = extra[i, j]


def stacked(values, src, extra) -> np.ndarray:
    """A new per-vertex array: the rows ``values[src]`` (values (n, ...), src (a,)), then ``extra`` (b,
    ...), of values' dtype (float64 and int64 filled in compiled code, other dtypes through float64).
    It is made here (``recycled_empty``), so that the rig holds it as it is (``frozen`` copies a
    kernel's own array: it cannot tell one from a view of another's)."""
    values = kernel_array(np.asarray(values))
    shape = (len(src) + len(extra),) + values.shape[1:]
    flat = np.ascontiguousarray(values.reshape(len(values), -1))
    direct = flat.dtype in (np.float64, np.int64)
    if not direct:
        flat = flat.astype(np.float64)
    out, width = recycled_empty(shape, flat.dtype), flat.shape[1]       # (explicit widths: no rows at all)
    _stacked_into(flat, src, np.ascontiguousarray(np.asarray(extra, flat.dtype).reshape(len(extra), width)),
                  out.reshape(len(out), width))
    return out if direct else out.astype(values.dtype)


def assemble(rig: Rig, patch: Patch, rim, opened: int, walls: int, open_rims: int, unclosed: int, bit,
             tolerance: float, affines, diagonal: float) -> DrillResult:
    """The drilled rig: the input vertices it uses (bit for bit), then the new rows it uses; the input
    faces it keeps, then the patch's faces it made; with its bookkeeping. ``rim`` (r,) the patch's rim
    rows; ``opened``, ``walls``, ``open_rims``, ``unclosed`` (``unclosed_edges``), ``bit``, ``tolerance`` as
    ``DrillResult`` names them;
    ``affines`` the pose's bone maps (a posed drill: the new vertices are placed in rest space) or None.

    A new row's weights and attributes blend those of the two rows it was made between
    (``patch.row_skins``, ``patch.row_values``): a wall's rows the rim rows they lie between."""
    vertices, faces, joints, weights = mesh_arrays(rig)
    lay = Layout(*_layout(faces, len(vertices), patch.taken, patch.faces, patch.face_source, patch.row_vertex,
                          patch.row_point, patch.point_array()))
    made, new_positions = (patch.row_vertex, patch.row_parents, patch.row_t), lay.positions
    # the copies of a new vertex at one point (a seam's sides, a wall's row at its rim) skin alike: their
    # weights and rest position are the first copy's (``skin_rows``: blended from other rows, ties in
    # the blend could pick other bones), their attributes their own
    new_joints, new_weights = row_skins(*made, joints, weights, lay.skin_rows)
    new_rest, residual = new_positions, 0.0
    if affines is not None and len(lay.new_rows):
        guess = row_values(*made, vertices, LINEAR, lay.skin_rows)
        new_rest, residual = _placed(guess, new_positions, new_joints, new_weights, affines, diagonal)
    attributes = {}
    for name, values in rig.attributes.items():
        values = kernel_array(np.asarray(values))     # (read-only: its writeable buffer, one kernel type)
        flat = np.ascontiguousarray(values.reshape(len(values), -1), np.float64)
        extra = row_values(*made, flat, attribute_rule(name, flat.shape[1]), lay.new_rows)
        if name == "NORMAL" and values.shape[1:] == (3,):
            _wall_normals(extra, lay.on_wall, new_positions, bit, affines, new_joints, new_weights)
        attributes[name] = stacked(values, lay.kept_input, extra.reshape((len(extra),) + values.shape[1:]))
    out_vertices, out_joints, out_weights = (stacked(values, lay.kept_input, extra) for values, extra in
                                             ((vertices, new_rest), (joints, new_joints), (weights, new_weights)))
    result = Rig._of_checked(out_vertices, lay.faces, out_joints, out_weights, rig.skeleton, rig.clips, attributes,
                             f"{rig.name}_drilled")
    sources = np.concatenate([lay.kept_input, np.full(len(lay.new_rows), NEW_VERTEX, np.int64)])
    return DrillResult(result, sources, len(lay.kept_input), np.sort(lay.row_out[rim]), new_positions, opened,
                       lay.replaced, lay.made_in, walls, open_rims, unclosed, bit, tolerance, residual,
                       partial(_described, *(np.array(a) for a in made), lay.new_rows))


def _described(vertex, parents, t, new_rows) -> NewVertices:
    """The rows ``new_rows`` (k,) as input vertices and coefficients (``patch.descriptions``)."""
    src, coef = descriptions(vertex, parents, t)
    return NewVertices(src[new_rows], coef[new_rows])


def _wall_normals(normals, on_wall, points, bit, affines, joints, weights) -> None:
    """Point the new vertices' ``normals`` (k, 3) float64 that lie ``on_wall`` (k,) into the bit, from
    their ``points`` (k, 3), in place; a posed drill's carried to rest by their ``joints``, ``weights``
    (k, 4) in the pose's bone ``affines`` (B, 12)."""
    _inward_into(normals, on_wall, points, bit.start, bit.end)
    if affines is not None:
        _to_rest_into(normals, on_wall, joints, weights, affines)


@kernel((F2, B1, F2, F1, F1), cost=0.2)
def _inward_into(normals, on_wall, points, start, end):
    """Where ``on_wall`` (k,), the unit vector from row i of ``points`` (k, 3) to the nearest point of the
    bit's travel start -> end (its axis, or a round end's centre) into ``normals`` (k, 3): a wall faces
    the hole."""
    for i in range(points.shape[0]):
        if on_wall[i]:
            _put_inward(points, i, start, end, normals, i)


@kernel((F2, B1, I2, F2, F2), cost=0.2)
def _to_rest_into(normals, on_wall, joints, weights, affines):
    """Carry the rows of posed ``normals`` (k, 3) that lie ``on_wall`` (k,) to rest, in place: by the
    transpose of the row's blended linear map (sum of w A over its ``joints``, ``weights`` (k, 4), the
    bone ``affines`` (B, 12) row-major 3x4; a normal transforms by the inverse transpose), unit length."""
    for i in range(normals.shape[0]):
        if not on_wall[i]:
            continue
        n0, n1, n2 = normals[i, 0], normals[i, 1], normals[i, 2]
        x = y = z = 0.0
        for s in range(joints.shape[1]):
            w, b = weights[i, s], joints[i, s]
            if w != 0.0:
                x += w * (affines[b, 0] * n0 + affines[b, 4] * n1 + affines[b, 8] * n2)
                y += w * (affines[b, 1] * n0 + affines[b, 5] * n1 + affines[b, 9] * n2)
                z += w * (affines[b, 2] * n0 + affines[b, 6] * n1 + affines[b, 10] * n2)
        norm = math.sqrt(x * x + y * y + z * z)
        normals[i, 0], normals[i, 1], normals[i, 2] = x / norm, y / norm, z / norm


@helper
def _put_inward(points, i, start, end, out, row):
    """Write the unit vector from row i of ``points`` to the nearest point of start -> end to ``out[row]``."""
    ux, uy, uz = end[0] - start[0], end[1] - start[1], end[2] - start[2]
    s = ((points[i, 0] - start[0]) * ux + (points[i, 1] - start[1]) * uy + (points[i, 2] - start[2]) * uz) / \
        (ux * ux + uy * uy + uz * uz)
    s = min(max(s, 0.0), 1.0)
    dx, dy, dz = start[0] + s * ux - points[i, 0], start[1] + s * uy - points[i, 1], start[2] + s * uz - points[i, 2]
    norm = math.sqrt(dx * dx + dy * dy + dz * dz)
    out[row, 0], out[row, 1], out[row, 2] = dx / norm, dy / norm, dz / norm


def _placed(guess, targets, new_joints, new_weights, affines, diagonal: float):
    """Rest positions of the new vertices of a posed drill (``place_in_rest`` from their interpolated
    rest positions ``guess`` (k, 3)), and the largest residual (a ``PlacementWarning`` when some miss
    where they were made)."""
    rest, residuals = place_in_rest(targets, guess, new_joints, new_weights, affines)
    residual = float(residuals.max()) if len(residuals) else 0.0
    if residual > tol.placement * diagonal:
        warn(f"{int(np.count_nonzero(residuals > tol.placement * diagonal))} new vertices of the drill miss "
             f"where they were made in the pose by more than {tol.placement:g} of the diagonal (largest "
             f"{residual:.3g}): a singular blended transform; they keep their interpolated rest positions",
             PlacementWarning)
    return rest, residual
