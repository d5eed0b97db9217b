"""Run WGSL compute shaders on wgpu (PyPI ``wgpu``, wgpu-native) for the tests: one device per test
session (Mesa's lavapipe Vulkan adapter where there is one), shader modules validated by naga, and
compute passes over flat storage buffers read back as numpy arrays."""
from __future__ import annotations

import functools
import os
import tempfile

import numpy as np


class Unavailable(Exception):
    """wgpu or a Vulkan adapter is missing (the message says which)."""


@functools.lru_cache(maxsize=None)
def device():
    """(the wgpu device, the adapter's description): lavapipe (llvmpipe) if present, else the first
    Vulkan adapter, with the ``shader-f64`` feature where the adapter has it (``has_f64``). Raises
    ``Unavailable``."""
    # Mesa's Vulkan drivers complain on stderr without a runtime dir (headless CI has none)
    os.environ.setdefault("XDG_RUNTIME_DIR", tempfile.mkdtemp(prefix="cgaskin-xdg-"))
    try:
        import wgpu
    except ImportError as e:
        raise Unavailable(f"the Python package wgpu is not installed ({e})") from None
    try:
        adapters = [a for a in wgpu.gpu.enumerate_adapters_sync() if a.info["backend_type"] == "Vulkan"]
    except Exception as e:     # wgpu-native without any Vulkan loader raises here
        raise Unavailable(f"wgpu found no adapter: {e}") from None
    if not adapters:
        raise Unavailable("wgpu found no Vulkan adapter (Debian packages mesa-vulkan-drivers libvulkan1 "
                          "give lavapipe)")
    adapter = next((a for a in adapters if "llvmpipe" in a.info["device"]), adapters[0])
    features = ["shader-f64"] if "shader-f64" in adapter.features else []
    return (adapter.request_device_sync(required_features=features),
            f"{adapter.info['device']} ({adapter.info['description']})")


def has_f64() -> bool:
    """Whether the device runs f64 shaders (wgpu-native's ``shader-f64``)."""
    return "shader-f64" in device()[0].features


def compile_shader(source: str):
    """The shader module of ``source``, validated by naga (an invalid shader raises), and its
    compilation messages (list of text)."""
    dev, _ = device()
    module = dev.create_shader_module(code=source)
    messages = [str(m) for m in module.get_compilation_info_sync()]
    return module, messages


@functools.lru_cache(maxsize=None)
def _pipeline(module, entry: str):
    dev, _ = device()
    return dev.create_compute_pipeline(layout="auto", compute={"module": module, "entry_point": entry})


def dispatch(module, entry: str, bindings: dict, count: int, workgroup: int = 64, groups=None) -> dict:
    """Run ``entry`` of ``module`` for ``count`` invocations (ceil(count / workgroup) workgroups,
    or the (x, y) workgroups ``groups``) on group 0.

    bindings : {binding: (array, kind)} with kind "uniform", "read" or "read_write"; the arrays are
               sent as they are (give them the shader's dtype, e.g. float32, uint32)
    Returns {binding: bytes as a numpy array of the same dtype and shape} for the read_write ones.
    """
    import wgpu
    dev, _ = device()
    pipeline = _pipeline(module, entry)
    usage = {"uniform": wgpu.BufferUsage.UNIFORM,
             "read": wgpu.BufferUsage.STORAGE,
             "read_write": wgpu.BufferUsage.STORAGE | wgpu.BufferUsage.COPY_SRC}
    buffers, entries = {}, []
    for binding, (array, kind) in bindings.items():
        data = np.ascontiguousarray(array)
        # a zero-size binding is not allowed: pad empty arrays to 4 bytes
        raw = data.tobytes() if data.nbytes else bytes(4)
        buffers[binding] = dev.create_buffer_with_data(data=raw, usage=usage[kind])
        entries.append({"binding": binding, "resource": {"buffer": buffers[binding], "offset": 0,
                                                         "size": len(raw)}})
    group = dev.create_bind_group(layout=pipeline.get_bind_group_layout(0), entries=entries)
    encoder = dev.create_command_encoder()
    compute = encoder.begin_compute_pass()
    compute.set_pipeline(pipeline)
    compute.set_bind_group(0, group)
    compute.dispatch_workgroups(*(groups or (max(1, -(-count // workgroup)), 1)), 1)
    compute.end()
    dev.queue.submit([encoder.finish()])
    out = {}
    for binding, (array, kind) in bindings.items():
        if kind == "read_write":
            raw = dev.queue.read_buffer(buffers[binding])
            out[binding] = np.frombuffer(raw, dtype=array.dtype)[:array.size].reshape(array.shape).copy()
    return out


def kernel_harness(kernels, prefix: str, library_source: str, real: str = "f32") -> str:
    """A compute shader with one entry point ``run_<kernel>`` per kernel: row r of the flat input
    buffer (binding 0, ``real``, the kernel's inputs side by side) through ``<prefix>_<kernel>`` into
    row r of the output buffer (binding 1, ``real``, N per row). ``library_source`` is the rendered
    ``<prefix>.wgsl`` (or ``<prefix>_f64.wgsl`` with real="f64")."""
    lines = [library_source,
             f"@group(0) @binding(0) var<storage, read> harness_in: array<{real}>;",
             f"@group(0) @binding(1) var<storage, read_write> harness_out: array<{real}>;"]
    for k in kernels:
        width = sum(1 if i.kind == "scalar" else len(i.symbols) for i in k.inputs)
        n = len(k.outputs)
        args, at = [], 0
        for inp in k.inputs:
            if inp.kind == "scalar":
                args.append(f"harness_in[base + {at}u]")
                at += 1
            else:
                size = len(inp.symbols)
                args.append(f"array<{real}, {size}>(" + ", ".join(f"harness_in[base + {at + j}u]"
                                                                 for j in range(size)) + ")")
                at += size
        lines += ["@compute @workgroup_size(64)",
                  f"fn run_{k.name}(@builtin(global_invocation_id) gid: vec3<u32>) {{",
                  "    let r = gid.x;",
                  f"    if (r >= arrayLength(&harness_out) / {n}u) {{ return; }}",
                  f"    let base = r * {width}u;",
                  f"    let y = {prefix}_{k.name}({', '.join(args)});"]
        lines += [f"    harness_out[r * {n}u + {j}u] = y[{j}];" for j in range(n)]
        lines.append("}")
    return "\n".join(lines) + "\n"


def run_kernel(module, kernel, inputs, dtype=np.float32) -> np.ndarray:
    """(rows, N) float64: the shader's ``run_<kernel>`` on ``inputs`` (one float64 array per kernel
    input, (rows, size) or (rows,); sent as ``dtype``, the harness's real type)."""
    rows = len(inputs[0])
    flat = np.concatenate([np.asarray(a, np.float64).reshape(rows, -1) for a in inputs], axis=1)
    out = np.zeros((rows, len(kernel.outputs)), dtype)
    result = dispatch(module, f"run_{kernel.name}",
                      {0: (flat.astype(dtype), "read"), 1: (out, "read_write")}, rows)
    return result[1].astype(np.float64)
