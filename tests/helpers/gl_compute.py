"""Run GLSL compute shaders headless: one moderngl EGL standalone context (Mesa llvmpipe on a machine
without a GPU: GL 4.5 core with fp64) per test session, shaders built from generated includes, inputs
and outputs in std430 storage buffers of flat arrays (vec3[] would have a 16-byte stride)."""
from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

LOCAL_SIZE = 64


def open_context():
    """(moderngl context, None) or (None, why it cannot be had)."""
    os.environ.setdefault("XDG_RUNTIME_DIR", tempfile.mkdtemp(prefix="cgaskin-xdg-"))  # silences Mesa
    try:
        import moderngl
    except ImportError as e:
        return None, f"moderngl is not installed ({e}): pip install moderngl"
    try:
        ctx = moderngl.create_standalone_context(backend="egl", require=430)
    except Exception as e:                         # no libEGL, no Mesa driver, GL < 4.3
        return None, (f"no EGL GL 4.3 context ({type(e).__name__}: {e}): install Debian "
                      f"libegl1 libegl-mesa0 libgl1-mesa-dri")
    return ctx, None


def kernel_shader(include: str, prefix: str, kernel, real: str) -> str:
    """A compute shader that runs ``<prefix>_<kernel.name>`` on row
    gl_GlobalInvocationID.x: input n from binding n (rows x its size, flat), the outputs to the next
    binding (rows x outputs, flat), the row count in uniform ``rows``."""
    lines = ["#version 430", f"layout(local_size_x = {LOCAL_SIZE}) in;"]
    for n, i in enumerate(kernel.inputs):
        lines.append(f"layout(std430, binding = {n}) readonly buffer Input{n} {{ {real} in{n}[]; }};")
    n_out = len(kernel.outputs)
    lines.append(f"layout(std430, binding = {len(kernel.inputs)}) writeonly buffer Output "
                 f"{{ {real} outputs[]; }};")
    lines += ["uniform uint rows;", include, "void main() {", "    uint row = gl_GlobalInvocationID.x;",
              "    if (row >= rows) return;"]
    args = []
    for n, i in enumerate(kernel.inputs):
        if i.kind == "scalar":
            args.append(f"in{n}[row]")
            continue
        size = len(i.symbols)
        lines.append(f"    {real} a{n}[{size}];")
        lines.append(f"    for (uint j = 0u; j < {size}u; j++) a{n}[j] = in{n}[row * {size}u + j];")
        args.append(f"a{n}")
    lines.append(f"    {real} r[{n_out}];")
    lines.append(f"    {prefix}_{kernel.name}({', '.join(args + ['r'])});")
    lines.append(f"    for (uint j = 0u; j < {n_out}u; j++) outputs[row * {n_out}u + j] = r[j];")
    lines.append("}")
    return "\n".join(lines) + "\n"


def function_shader(include: str, call: str, n_args: int, real: str) -> str:
    """A compute shader with outputs[row] = call(in0[row], ..., in<n_args-1>[row]) for a scalar function
    of the include (e.g. a ``<prefix>_lib_*`` helper); run with ``Runner.run_rows(..., 1, dtype)``."""
    lines = ["#version 430", f"layout(local_size_x = {LOCAL_SIZE}) in;"]
    lines += [f"layout(std430, binding = {n}) readonly buffer Input{n} {{ {real} in{n}[]; }};"
              for n in range(n_args)]
    lines += [f"layout(std430, binding = {n_args}) writeonly buffer Output {{ {real} outputs[]; }};",
              "uniform uint rows;", include, "void main() {", "    uint row = gl_GlobalInvocationID.x;",
              "    if (row >= rows) return;",
              f"    outputs[row] = {call}({', '.join(f'in{n}[row]' for n in range(n_args))});", "}"]
    return "\n".join(lines) + "\n"


class Runner:
    """Compiles each shader once (cached by source) and runs it on numpy arrays."""

    def __init__(self, ctx):
        self.ctx = ctx
        self._shaders = {}

    def shader(self, source: str):
        if source not in self._shaders:
            self._shaders[source] = self.ctx.compute_shader(source)
        return self._shaders[source]

    def run_rows(self, source: str, inputs, n_out: int, dtype) -> np.ndarray:
        """Run ``source`` (from ``kernel_shader``) over every row of ``inputs`` in one dispatch:
        returns (rows, n_out) of ``dtype``."""
        rows = len(inputs[0])
        buffers = [self.ctx.buffer(np.ascontiguousarray(a, dtype).tobytes()) for a in inputs]
        out = self.ctx.buffer(reserve=max(rows * n_out, 1) * np.dtype(dtype).itemsize)
        for n, b in enumerate(buffers + [out]):
            b.bind_to_storage_buffer(n)
        cs = self.shader(source)
        cs["rows"] = rows
        cs.run(group_x=(rows + LOCAL_SIZE - 1) // LOCAL_SIZE)
        self.ctx.finish()
        result = np.frombuffer(out.read(), dtype=dtype).reshape(rows, n_out).copy()
        for b in buffers + [out]:
            b.release()
        return result

    def dispatch(self, source: str, arrays: dict, block: bytes, groups) -> dict:
        """Run ``source`` on ``arrays`` {binding: numpy array (its dtype as stored)} bound as storage
        buffers, ``block`` as the uniform block at binding 0, ``groups`` = (x, y) work groups; returns
        {binding: bytes read back}."""
        buffers = {n: self.ctx.buffer(np.ascontiguousarray(a).tobytes()) for n, a in arrays.items()}
        ubo = self.ctx.buffer(block)
        for n, b in buffers.items():
            b.bind_to_storage_buffer(n)
        ubo.bind_to_uniform_block(0)
        self.shader(source).run(group_x=groups[0], group_y=groups[1])
        self.ctx.finish()
        out = {n: b.read() for n, b in buffers.items()}
        for b in [*buffers.values(), ubo]:
            b.release()
        return out

    def transform(self, vertex_source: str, varying: str, attributes, n: int, arrays: dict, block: bytes):
        """Transform feedback of ``varying`` (vec3) of a vertex shader over ``n`` points: attributes
        [(numpy array, moderngl format, name)], storage ``arrays`` {binding: array}, uniform block 0;
        returns (n, 3) float32."""
        import moderngl
        program = self.ctx.program(vertex_shader=vertex_source, varyings=[varying])
        vbos = [(self.ctx.buffer(np.ascontiguousarray(a).tobytes()), fmt, name) for a, fmt, name in attributes]
        vao = self.ctx.vertex_array(program, vbos)
        buffers = {k: self.ctx.buffer(np.ascontiguousarray(a).tobytes()) for k, a in arrays.items()}
        for k, b in buffers.items():
            b.bind_to_storage_buffer(k)
        ubo = self.ctx.buffer(block)
        ubo.bind_to_uniform_block(0)
        out = self.ctx.buffer(reserve=n * 12)
        framebuffer = self.ctx.simple_framebuffer((1, 1))     # a standalone context has no default one,
        framebuffer.use()                                   # and drawing without one is an error
        vao.transform(out, mode=moderngl.POINTS, vertices=n)
        self.ctx.finish()
        result = np.frombuffer(out.read(), dtype=np.float32).reshape(n, 3).copy()
        assert self.ctx.error == "GL_NO_ERROR", self.ctx.error
        for obj in [framebuffer, out, ubo, vao, program, *buffers.values(), *(v[0] for v in vbos)]:
            obj.release()
        return result


def validator() -> str | None:
    return shutil.which("glslangValidator")


def validate(source: str, stage: str, spirv: bool) -> str:
    """glslangValidator's output on ``source`` (a whole shader of ``stage``: comp, vert) in GL mode
    or as SPIR-V for Vulkan (``-V``, the module then checked by spirv-val); raises AssertionError with
    the output when it does not pass."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"shader.{stage}"
        path.write_text(source)
        args = [validator(), "-V", "-o", str(Path(tmp) / "out.spv")] if spirv else [validator()]
        proc = subprocess.run(args + [str(path)], capture_output=True, text=True)
        output = (proc.stdout + proc.stderr).replace(str(path), f"shader.{stage}").strip()
        if proc.returncode != 0:
            raise AssertionError(f"glslangValidator {'-V ' if spirv else ''}failed:\n{output}")
        if spirv:
            val = subprocess.run(["spirv-val", str(Path(tmp) / "out.spv")], capture_output=True, text=True)
            if val.returncode != 0:
                raise AssertionError(f"spirv-val failed:\n{val.stdout}{val.stderr}")
        return output
