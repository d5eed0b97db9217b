"""Print a ``Kernel`` as a numba module function (straight-line code, no closures). The expressions
are printed by ``codegen.expressions`` in its Python dialect (the rules every target shares)."""
from __future__ import annotations

from .expressions import PYTHON, Dialect, kernel_body
from .ir import CodegenError, Kernel

#: a catalogue's kernels are cached by numba beside their module; cgaskin's own catalogue is printed with
#: ``RUNTIME_DECORATOR``: the runtime gives each of those kernels its own cache, which also loads the
#: compiled kernels shipped with the package (numba's cache=True would make its folder at import, and
#: fail the import where no folder is writable)
NUMBA_DECORATOR = "@njit(cache=True, error_model='numpy', nogil=True)"
RUNTIME_DECORATOR = "@njit(error_model='numpy', nogil=True)"


def docstring(kernel: Kernel, width: int = 110) -> list[str]:
    lines = ['    """' + kernel.doc.strip()]
    lines.append("")
    lines.append("    Symbolic expansion (before CSE):")
    for row in kernel.expansion:
        text = row if len(row) <= width else row[: width - 5] + " ..."
        lines.append("        " + text.replace("\\", "\\\\"))
    lines.append('    """')
    return lines


def print_kernel(kernel: Kernel, decorator: str = NUMBA_DECORATOR, name: str | None = None,
                 dialect: Dialect = PYTHON) -> str:
    """Source of ``@njit def name(inputs...) -> tuple`` (the scalar kernel). ``decorator``, ``name``
    and ``dialect`` let other Python targets (numba-cuda device functions) print the same body."""
    args = ", ".join(i.name for i in kernel.inputs)
    lines = [decorator, f"def {name or kernel.name}({args}):"]
    lines += docstring(kernel)
    for inp in kernel.inputs:
        if inp.kind == "scalar":
            continue
        for idx, sym in enumerate(inp.symbols):
            lines.append(f"    {sym.name} = {inp.name}[{idx}]")
    assigns, values = kernel_body(kernel, dialect)
    lines += [f"    {var} = {code}" for var, code, _ in assigns]
    if len(values) == 1:
        lines.append(f"    return {values[0]}")
    else:
        lines.append("    return (")
        lines += [f"        {v}," for v in values]
        lines.append("    )")
    return "\n".join(lines) + "\n"


def store_rows(call: str, n_out: int) -> list[str]:
    """The row loop's body: ``call`` (a kernel call) stored in row ``row`` of ``out``."""
    if n_out == 1:
        return [f"        out[row, 0] = {call}"]
    return [f"        r = {call}"] + [f"        out[row, {j}] = r[{j}]" for j in range(n_out)]


def print_batch(kernel: Kernel, decorator: str = NUMBA_DECORATOR) -> str:
    """Source of ``name_batch(inputs (N, ...)..., out (N, k))``: the scalar kernel over rows."""
    args = [i.name for i in kernel.inputs]
    if "row" in args:
        raise CodegenError(f"{kernel.name}: an input named 'row' would shadow the batch loop index")
    n_out = len(kernel.outputs)
    lines = [decorator,
             f"def {kernel.name}_batch({', '.join(args)}, out):",
             f'    """``{kernel.name}`` on every row: inputs (N, ...) or (N,), out (N, {n_out})."""',
             "    for row in range(out.shape[0]):"]
    call = f"{kernel.name}({', '.join(a + '[row]' for a in args)})"
    lines += store_rows(call, n_out)
    return "\n".join(lines) + "\n"
