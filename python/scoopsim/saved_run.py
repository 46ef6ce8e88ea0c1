"""scoopsim.open_run: a saved run's datasets by name, as numpy arrays with their attributes."""

import h5py
import numpy as np


class Dataset(np.ndarray):
    """A dataset's values with its HDF5 attributes (units, frame, columns, quaternion_order...)
    in .attrs."""

    def __new__(cls, values, attrs):
        a = np.asarray(values).view(cls)
        a.attrs = attrs
        return a

    def __array_finalize__(self, obj):
        self.attrs = getattr(obj, "attrs", {})


def _value(v):
    return v.decode() if isinstance(v, bytes) else v


class SavedRun:
    """The datasets of a `scoopsim run` output by their path without the leading '/'
    ('scoop/force_world', 'arm/q'), read whole; the root attributes (state_hash, start_time,
    scene_yaml, ...) in .attrs."""

    def __init__(self, path):
        self.path = str(path)
        self._datasets = {}
        with h5py.File(self.path, "r") as f:
            self.attrs = {k: _value(v) for k, v in f.attrs.items()}

            def visit(name, obj):
                if isinstance(obj, h5py.Dataset):
                    self._datasets[name] = None

            f.visititems(visit)

    def keys(self):
        return list(self._datasets)

    def __contains__(self, name):
        return name.lstrip("/") in self._datasets

    def __getitem__(self, name):
        name = name.lstrip("/")
        if name not in self._datasets:
            raise KeyError(f"{self.path}: no dataset {name}")
        if self._datasets[name] is None:
            with h5py.File(self.path, "r") as f:
                d = f[name]
                self._datasets[name] = Dataset(d[()], {k: _value(v) for k, v in d.attrs.items()})
        return self._datasets[name]


def open_run(path):
    """The saved run at `path` (an HDF5 file of `scoopsim run`): run["scoop/force_world"] is a
    numpy array, its .attrs the dataset's attributes."""
    return SavedRun(path)
