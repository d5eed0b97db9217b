"""First use: cgaskin's kernels ship compiled for Blender's Python and NumPy, and load in a second.
Where they do not match (another Blender, NumPy or numba), they compile once (about two minutes on
two cores) in a subprocess, ``cgaskin precompile``, into numba's cache, while Blender stays
responsive: the operators' ``invoke`` starts ``CGASKIN_OT_prepare_kernels``, a modal operator that
shows the progress in the status bar and ends when the subprocess does. (A script calling an
operator's ``execute`` directly compiles in its own process, as any numba code does.)
"""
from __future__ import annotations

import os
import subprocess
import sys
import time

import bpy

#: whether every kernel loads without compiling (None: not checked yet in this Blender session)
_READY: list = [None]
#: the running compile: (process, start time, how many kernels)
_RUNNING: list = []


def ready() -> bool:
    """Whether the operators can run without compiling (checked once; loads the kernels it finds)."""
    if _READY[0] is None:
        from cgaskin.app.precompile import missing_kernels
        _READY[0] = not missing_kernels()
    return _READY[0]


def compiling() -> bool:
    return bool(_RUNNING) and _RUNNING[0][0].poll() is None


class CGASKIN_OT_prepare_kernels(bpy.types.Operator):
    """Compile cgaskin's kernels once, in the background (they did not ship compiled for this setup)"""

    bl_idname = "cgaskin.prepare_kernels"
    bl_label = "cgaskin: compile kernels"

    def invoke(self, context, event):
        if ready():
            return {"FINISHED"}
        if not compiling():
            from cgaskin.app.precompile import missing_kernels
            count = len(missing_kernels())
            # (the subprocess sees the same packages: Blender puts the extension's wheels on sys.path)
            env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
            process = subprocess.Popen([sys.executable, "-m", "cgaskin", "precompile"], env=env,
                                       stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
            _RUNNING[:] = [(process, time.monotonic(), count)]
        self._timer = context.window_manager.event_timer_add(0.5, window=context.window)
        context.window_manager.modal_handler_add(self)
        context.window_manager.progress_begin(0, 100)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        process, start, count = _RUNNING[0]
        elapsed = time.monotonic() - start
        # (numba does not report progress: the bar follows the time two cores take, ~1.5 s a kernel)
        context.window_manager.progress_update(min(99, int(100 * elapsed / max(1.5 * count, 1.0))))
        context.workspace.status_text_set(f"cgaskin: compiling {count} kernels once ({elapsed:.0f} s)")
        if process.poll() is None:
            return {"PASS_THROUGH"}
        context.window_manager.event_timer_remove(self._timer)
        context.window_manager.progress_end()
        context.workspace.status_text_set(None)
        _READY[0] = None
        if process.returncode or not ready():
            message = process.stderr.read().decode(errors="replace").strip().splitlines()
            self.report({"WARNING"}, "cgaskin: the kernels did not compile ahead "
                        f"({message[-1] if message else process.returncode}); they compile at first use")
            return {"CANCELLED"}
        self.report({"INFO"}, f"cgaskin: kernels compiled in {elapsed:.0f} s")
        return {"FINISHED"}


CLASSES = (CGASKIN_OT_prepare_kernels,)
