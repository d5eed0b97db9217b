"""Names WGSL does not accept as identifiers, for the WGSL printer (codegen/targets/wgsl.py)."""
from __future__ import annotations

#: WGSL keywords and reserved words (WGSL spec §15.2, §15.3)
KEYWORDS = frozenset("""
alias break case const const_assert continue continuing default diagnostic discard else enable false
fn for if let loop override requires return struct switch true var while
NULL Self abstract active alignas alignof as asm asm_fragment async attribute auto await become
binding_array cast catch class co_await co_return co_yield coherent column_major common compile
compile_fragment concept const_cast consteval constexpr constinit crate debugger decltype delete demote
demote_to_helper do dynamic_cast enum explicit export extends extern external fallthrough filter final
finally friend from fxgroup get goto groupshared highp impl implements import inline instanceof
interface layout lowp macro macro_rules match mediump meta mod module move mut mutable namespace new nil
noexcept noinline nointerpolation noperspective null nullptr of operator package packoffset partition
pass patch pixelfragment precise precision premerge priv protected pub public readonly ref regardless
register reinterpret_cast require resource restrict self set shared sizeof smooth snorm static
static_assert static_cast std subroutine super target template this thread_local throw trait try type
typedef typeid typename typeof union unless unorm unsafe unsized use using varying virtual volatile
wgsl where with writeonly yield
""".split())

#: predeclared names a kernel body uses: a parameter or let of that name would shadow them
PREDECLARED = frozenset("""
f32 i32 u32 f16 bool array vec2 vec3 vec4 select bitcast sqrt sin cos atan2 acos log exp abs sign atanh
cosh sinh max min exp2 log2 pow
""".split())


def safe_name(name: str) -> str:
    """``name``, or ``name_`` when WGSL reserves it or a kernel body would lose a builtin to it
    (identifiers starting with ``__`` are reserved too: those get a leading ``x``)."""
    if name.startswith("__") or name == "_":
        name = "x" + name
    return name + "_" if name in KEYWORDS or name in PREDECLARED else name
