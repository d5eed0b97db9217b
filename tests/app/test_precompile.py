"""cgaskin.precompile: the kernel list is complete (after it, skinning, cutting and tearing, also in
an editing session, compile nothing), the work is shared out evenly, and the command line runs it."""
import importlib
import os
import subprocess
import sys
import textwrap

import pytest

from cgaskin import InvalidInputError, precompile
from cgaskin.app.cli import main

pc = importlib.import_module("cgaskin.app.precompile")     # the module (cgaskin.precompile is the function)

# Runs in a fresh interpreter: precompile(), then the main operations on the built-in rig and a real
# model, recording what numba compiles (loading from the cache is not compiling: numba fires
# "numba:compile" only when it compiles).
WORKLOAD = textwrap.dedent("""
    import sys
    import numpy as np
    from numba.core import event
    import cgaskin
    from cgaskin.app.precompile import precompile

    from cgaskin._shared import shipped
    if sys.argv[2] == "empty":                    # an empty cache: it compiles, or loads the shipped kernels
        assert precompile() > 0 or shipped.LOADED
    else:                                         # the session's cache, as its precompile left it
        assert precompile() == 0
    # a fused kernel loaded its callees: no callee was compiled for other types too (numba's cache index
    # of a kernel holds one entry per compiled signature)
    pc = sys.modules["cgaskin.app.precompile"]
    listed = {}
    for i, signature in enumerate(pc.KERNELS):
        dispatcher = pc._dispatcher(i)[0]
        if dispatcher.targetoptions.get("no_cpython_wrapper"):
            listed[dispatcher] = listed.get(dispatcher, 0) + 1
    extra = [d.py_func.__name__ for d, n in listed.items() if len(d._cache.disk()._cache_file._load_index()) > n]
    assert listed and not extra, f"callees compiled again for other types by the kernels that call them: {extra}"
    compiled = []

    class Recorder(event.Listener):
        def on_start(self, ev):
            f = ev.data["dispatcher"].py_func
            if f.__module__.startswith("cgaskin"):
                compiled.append(f"{f.__module__}.{f.__name__}")

        def on_end(self, ev):
            pass

    event.register("numba:compile", Recorder())
    # (rig, joint, a scalpel stroke in three positions across its surface)
    cases = [(cgaskin.capsule_arm(), 1, [([x, 0.05, 1.0], [x, 0.05, 0.0]) for x in (0.6, 1.2, 1.8)])]
    if sys.argv[1]:
        cases.append((cgaskin.load(sys.argv[1]), "b_Spine01_02", [([0, 120, z], [0, 40, z]) for z in (0, 10, 20)]))
    for rig, joint, blade in cases:
        posed = rig.rest_pose().rotate(joint, [1, 0, 0], 0.1).translate(joint, [0.01, 0, 0]).dilate(joint, 1.05)
        for pose in (rig.rest_pose(), posed) + ((rig.pose(0, 0.25),) if rig.clips else ()):
            cgaskin.skin(rig, pose)
        if rig.clips:                             # many frames: sampled, their bone maps and skins
            cgaskin.skin(rig, rig.poses(0, np.linspace(0.0, 1.0, 5)))
        for pose in (None, posed):
            centre = cgaskin.skin(rig, posed).mean(axis=0)
            cgaskin.cut(rig, [0.3, 1, 0.1], centre, pose=pose, cap=True)
            torn = cgaskin.tear(rig, blade[0], blade[1], pose=pose, opening=0.01)
            torn = cgaskin.tear(torn, blade[1], blade[2], pose=pose)
            cgaskin.skin(torn, posed)
            session = cgaskin.Surgery(rig, pose)
            session.tear(blade[0], blade[1], opening=0.01)
            session.tear(blade[1], blade[2])
            session.undo()
            session.cut([0.3, 1, 0.1], centre)
            session.undo()
            cgaskin.skin(session.rig, posed)
            cgaskin.Surgery(rig).tear(blade[0], blade[1], pose=posed)   # a stroke in a pose the session is not in
            # holes through a surface vertex along z: through, open, and blind from either side
            at = rig.vertices if pose is None else cgaskin.skin(rig, pose)
            v, size = at[np.argmin(np.linalg.norm(at - at.mean(axis=0), axis=1))], float(np.ptp(at, axis=0).max())
            z = np.array([0.0, 0.0, size])
            cgaskin.drill(rig, v - z, v + z, 0.03 * size, pose=pose)
            cgaskin.drill(rig, v - z, v + z, 0.03 * size, pose=pose, wall=False)
            for side in (1.0, -1.0):
                cgaskin.drill(rig, v - side * z, v + side * 0.01 * z, 0.03 * size, pose=pose)
            session.drill(v - z, v + z, 0.03 * size)
            session.undo()
    from cgaskin import versor                  # the versor API, as its docs call it
    V = versor.compose(versor.motor([0, 0, 1], 0.5, [1, 0, 0]), versor.dilator(2.0))
    versor.apply(V, [[1.0, 0, 0]])
    versor.apply(versor.normalise(versor.inverse(V)), [1.0, 2, 3])
    versor.from_matrix(versor.to_matrix(V) @ np.eye(4))
    versor.exp(versor.log(V))
    print(" ".join(sorted(set(compiled))))
""")


def test_after_precompile_nothing_compiles(models_dir, tmp_path, precompiled_cache):
    # a cache that precompile alone filled, so that nothing compiled earlier can stand in for a kernel
    # missing from the list: the session's when its precompile started from empty (tests/conftest.py
    # runs this test first), else an empty one of its own (NUMBA_CACHE_DIR); the workers inherit it
    state = "precompiled" if precompiled_cache else "empty"
    env = {**os.environ, **({} if precompiled_cache else {"NUMBA_CACHE_DIR": str(tmp_path)})}
    done = subprocess.run([sys.executable, "-c", WORKLOAD, str(models_dir / "Fox.glb"), state], capture_output=True,
                          text=True, timeout=900, env=env)
    assert done.returncode == 0, done.stderr
    compiled = done.stdout.split()
    assert compiled == [], f"kernels missing from cgaskin.precompile.KERNELS: {compiled}"


def test_shares_are_even_and_complete():
    indices = list(range(len(pc.KERNELS)))
    kernel_cost = {}
    for signature in pc.KERNELS:
        key = signature.module, signature.name
        kernel_cost[key] = kernel_cost.get(key, 0.0) + signature.cost
    for jobs in (1, 2, 3, 8):
        shares = pc._shares(indices, jobs)
        assert sorted(i for share in shares for i in share) == indices and len(shares) == jobs
        # the signatures of one kernel in one share (one process writes its cache index)
        owner = {}
        for s, share in enumerate(shares):
            for i in share:
                assert owner.setdefault(pc.KERNELS[i][:2], s) == s
        # largest first, to the least loaded: no share exceeds another by more than one kernel's cost
        loads = [sum(pc.KERNELS[i][3] for i in share) for share in shares]
        assert max(loads) - min(loads) <= max(kernel_cost.values())


def test_every_listed_kernel_exists():
    for index, signature in enumerate(pc.KERNELS):
        dispatcher, _ = pc._dispatcher(index)
        assert len(signature.argtypes) == dispatcher.py_func.__code__.co_argcount and signature.cost > 0
    assert any(signature.fused for signature in pc.KERNELS)


def test_fused_kernels_compile_after_the_others(monkeypatch):
    """A fused kernel's callees must be in the cache before it compiles: its stage comes second."""
    stages = []
    monkeypatch.setattr(pc, "_is_cached", lambda dispatcher, argtypes: False)
    monkeypatch.setattr(pc, "_in_parallel", lambda shares: stages.append(sorted(i for s in shares for i in s)) or [])
    assert precompile(jobs=2) == len(pc.KERNELS)
    fused = [i for i, signature in enumerate(pc.KERNELS) if signature.fused]
    assert stages == [sorted(set(range(len(pc.KERNELS))) - set(fused)), fused]


def test_command_line(capsys):
    assert main(["precompile", "--jobs", "0"]) == 2
    assert "cgaskin precompile: error: jobs must be a whole number of processes >= 1, got 0" in capsys.readouterr().err
    assert main(["precompile", "--jobs", "1"]) == 0
    assert main(["precompile"]) == 0                   # the second time: all cached
    assert "every kernel is compiled and cached already" in capsys.readouterr().out


@pytest.mark.parametrize("jobs", [0, -2, 1.5, "2", True, [2]])
def test_bad_jobs(jobs):
    with pytest.raises(InvalidInputError, match="jobs must be a whole number of processes >= 1"):
        precompile(jobs=jobs)


def test_failures_cost_time_not_results(tmp_path):
    """A kernel that does not compile with its listed types, and a worker process that dies, are
    reported and left to compile at their first call; the rest is compiled."""
    script = textwrap.dedent("""
        import importlib
        from numba import types
        pc = importlib.import_module("cgaskin.app.precompile")
        listed = {k[1]: k for k in pc.KERNELS}
        wrong = pc.Signature("cgaskin.generated.kernels", "segment_plane", (types.float64,) * 3, 1.0)
        pc.KERNELS = [listed["reverse_versor"], wrong]
        assert pc.precompile(jobs=1, verbose=True) == 2
        print("cached", [pc._is_cached(*pc._dispatcher(i)) for i in range(2)])
        pc.KERNELS = [listed["versor_log"], listed["plane_from_normal_distance"]]
        pc._WORKER = "raise SystemExit('worker broke')"
        assert pc.precompile(jobs=2, verbose=True) == 2
        print("cached", [pc._is_cached(*pc._dispatcher(i)) for i in range(2)])
    """)
    # (without the shipped kernels: this is about what compiles)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "CGASKIN_SHIPPED_KERNELS": "0"}
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 0, done.stderr
    assert "not precompiled (cgaskin.generated.kernels.segment_plane: TypingError" in done.stdout
    assert "not precompiled (a compile worker: worker broke); compiled at its first call instead" in done.stdout
    # what could be compiled was: the first share is this process's (the costlier kernel)
    assert "cached [True, False]\ncompiling" in done.stdout and done.stdout.rstrip().endswith("cached [True, False]")
