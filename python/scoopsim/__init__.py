"""scoopsim from Python: scenes, the run loop step by step, runs, the wrench table, the arm.

A thin layer over the C++ rooms (docs/python.md). Units are SI (m, s, N, N m, rad), quaternions
w x y z; bad input raises scoopsim.InputError (a ValueError) carrying file, line, key, expected and
got, whose str() is the command line's one line.

    import scoopsim
    scene = scoopsim.load_scene("scenes/tiny_dig.yaml", overrides={"dig.bite_depth": 0.03})
    world = scoopsim.World(scene)           # the bed poured (or loaded), the dig started
    while not world.done():
        world.step(100)
        print(world.time, world.scoop_wrench("l_scoop"))
"""

import numpy as np

from ._scoopsim import Arm, InputError, Scene, World, fault_names, load_scene
from ._scoopsim import _run, _Table
from .saved_run import open_run

InputError.__module__ = __name__

__all__ = ["Arm", "InputError", "Scene", "Table", "World", "fault_names", "load_scene", "open_run",
           "run"]


def run(path, out, overrides=None, threads=0, quiet=False, stop_after=0.0):
    """Runs a scene as `scoopsim run PATH -o OUT [--set K=V ...] [--threads N] [--stop-after S]`
    and returns OUT.

    Progress goes to stderr (quiet=True: none). Ctrl-C stops the run with its output closed and
    raises KeyboardInterrupt; a run that ends in another failure raises RuntimeError naming its
    exit status (sim/input/exit_status.h)."""
    status = _run(str(path), str(out), overrides, int(threads), bool(quiet), float(stop_after))
    if status != 0:
        raise RuntimeError(f"scoopsim run {path}: exit status {status}")
    return str(out)


class Table:
    """A wrench table (`scoopsim table` output, sim/files/wrench_table.h), read whole."""

    def __init__(self, path):
        self._table = _Table(str(path))
        self.path = str(path)
        self.materials = self._table.materials()
        self.bite_depths = np.array(self._table.bite_depths())  # [m]
        self.passes = np.array(self._table.passes())
        self.rho = np.array(self._table.rho())  # [m] grid

    def query(self, material, bite_depth, pass_, rho, clamp=False, frame="l_scoop"):
        """[Fx Fy Fz Tx Ty Tz] [N, N m] about the scoop's CoM in frame 'l_scoop' or 'body':
        exact in material and pass, linear in bite depth [m] and rho [m]. bite_depth, pass_ and
        rho broadcast against each other; returns shape broadcast + (6,). Out of the table's
        domain: InputError, unless clamp."""
        d, p, r = np.broadcast_arrays(np.asarray(bite_depth, dtype=float),
                                      np.asarray(pass_, dtype=np.int64),
                                      np.asarray(rho, dtype=float))
        w = self._table.query(material, d.ravel(), p.ravel(), r.ravel(), clamp, frame)
        return w.reshape(d.shape + (6,))
