"""The compiler's exception (its own module, so that every codegen module can raise it without an
import circle)."""


class CodegenError(Exception):
    """A kernel spec is inconsistent (e.g. its result has blades outside the declared type).

    What ``cgaskin build --catalogue`` and ``build_catalogue`` raise for a kernel they cannot compile;
    the message names the kernel and what is wrong.

    Examples
    --------
    >>> from cgaskin.codegen import CodegenError, cga
    >>> try:
    ...     cga.e1 * cga.e2
    ... except CodegenError as error:
    ...     print(error)
    cga values exist only while `cgaskin build` traces a kernel
    """
