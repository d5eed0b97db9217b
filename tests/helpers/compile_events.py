"""Source lines for a probe process (``python -c``) that records what numba compiles: after them,
``compiled`` lists "module.qualname" of every function numba compiles in that process."""

RECORD_COMPILES = '''
from numba.core import event
compiled = []


class Recorder(event.Listener):
    def on_start(self, ev):
        f = ev.data["dispatcher"].py_func
        compiled.append(f"{f.__module__}.{f.__qualname__}")

    def on_end(self, ev):
        pass


event.register("numba:compile", Recorder())
'''
