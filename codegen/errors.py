"""The compiler's exception (its own module, so that every codegen module can raise it without an
import circle)."""


class CodegenError(Exception):
    """A kernel spec is inconsistent (e.g. its result has blades outside the declared type)."""
