"""The JavaScript target (codegen/targets/js.py) run by node: every kernel of the built-in and of a user
catalogue equals its numba kernel on hypothesis-drawn inputs within 1e-12 of the row's scale
(``assert_rows_close``: JavaScript numbers are float64, so the printed kernel computes what numba
computes, to rounding); the module parses as an ES module, and a kernel writes into a caller's ``out``.
One node process per drawn example runs every kernel of the catalogue."""
from __future__ import annotations

import base64
import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cgaskin.codegen.targets import js as js_target
from tests.helpers.requirements import require
from tests.helpers.target_cases import builtin_kernels, input_arrays, reference

from ._c_cuda_common import assert_rows_close, user_catalogue

ROWS = 6
TOL = 1e-12
HERE = Path(__file__).resolve().parent
GENERATED = HERE.parents[1] / "generated" / "js" / "cgaskin.mjs"


@pytest.fixture(scope="module")
def node() -> str:
    path = shutil.which("node")
    require([] if path else ["node (Debian nodejs)"], "the JavaScript target's tests")
    return path


@pytest.fixture(scope="module")
def modules(tmp_path_factory):
    """{catalogue: (module path, prefix, kernels, numba module, uniform)}: the built-in catalogue's
    committed generated/js/cgaskin.mjs, and the README's user catalogue printed here."""
    kernels, module = builtin_kernels()
    user, user_uniform, user_module = user_catalogue(tmp_path_factory)
    directory = tmp_path_factory.mktemp("js_user")
    for name, text in js_target.render(user, prefix="userkernels", header=["test"], uniform=user_uniform).items():
        (directory / name).write_text(text)
    return {"builtin": (GENERATED, "cgaskin", kernels, module, {}),
            "user": (directory / "userkernels.mjs", "userkernels", user, user_module, user_uniform)}


def run_node(node, module_path, prefix, jobs, work: Path) -> list:
    """Each job's (rows, outputs) float64 result of the module's kernels (``run_kernels.mjs``)."""
    encoded = [{"kernel": kernel.name, "rows": len(inputs[0]), "outputs": len(kernel.outputs),
                "inputs": [[base64.b64encode(np.ascontiguousarray(a, np.float64).tobytes()).decode(),
                            0 if a.ndim == 1 else a.shape[1]] for a in inputs]} for kernel, inputs in jobs]
    (work / "jobs.json").write_text(json.dumps(encoded))
    run = subprocess.run([node, str(HERE / "js" / "run_kernels.mjs"), str(module_path), prefix, str(work / "jobs.json"),
                          str(work / "out.json")], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    results = json.loads((work / "out.json").read_text())
    return [np.frombuffer(base64.b64decode(text), np.float64).reshape(len(inputs[0]), len(kernel.outputs))
            for (kernel, inputs), text in zip(jobs, results)]


@pytest.mark.parametrize("catalogue", ["builtin", "user"])
def test_every_kernel_equals_numba(node, modules, catalogue, tmp_path):
    module_path, prefix, kernels, module, uniform = modules[catalogue]

    @settings(max_examples=8, deadline=None)
    @given(data=st.data(), magnitude=st.sampled_from([1.0, 10.0, 1e4]))
    def check(data, magnitude):
        jobs = []
        for kernel in kernels:
            inputs = data.draw(input_arrays(kernel, ROWS, magnitude), label=kernel.name)
            # an input the catalogue takes once is the same on every row (as the numba batch form sees it)
            inputs = tuple(np.broadcast_to(a[:1], a.shape).copy() if i.name in uniform.get(kernel.name, ()) else a
                           for i, a in zip(kernel.inputs, inputs))
            jobs.append((kernel, inputs))
        for (kernel, inputs), got in zip(jobs, run_node(node, module_path, prefix, jobs, tmp_path)):
            assert_rows_close(f"JS {prefix}_{kernel.name}", got, reference(module, kernel, inputs), TOL, inputs)

    check()


def test_a_kernel_writes_into_the_callers_array(node, tmp_path):
    script = tmp_path / "out.mjs"
    script.write_text(f"""import {{ cgaskin_versor_translator, cgaskin_versor_to_affine }} from '{GENERATED.as_uri()}';
const into = new Float64Array(12);
const same = cgaskin_versor_to_affine(cgaskin_versor_translator([1, 2, 3]), into);
console.log(JSON.stringify({{same: same === into, affine: Array.from(into)}}));
""")
    run = subprocess.run([node, str(script)], capture_output=True, text=True, timeout=30)
    assert run.returncode == 0, run.stderr
    result = json.loads(run.stdout)
    assert result["same"]
    np.testing.assert_allclose(np.reshape(result["affine"], (3, 4)), [[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3]], atol=1e-15)


def test_reserved_names_are_renamed():
    assert js_target._js_name("in") == "v_in" and js_target._js_name("out") == "v_out"
    assert js_target._js_name("angle") == "angle" and js_target._js_name("x0") == "x0"
