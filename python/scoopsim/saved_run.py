"""scoopsim.open_run: a saved run's datasets by name, as numpy arrays with their attributes."""

import h5py
import numpy as np


class Dataset(np.ndarray):
    """A dataset's values with its attributes in .attrs: `units` and `frame` (SI, from the
    layout) and the file's own (columns, quaternion_order...)."""

    def __new__(cls, values, attrs):
        a = np.asarray(values).view(cls)
        a.attrs = attrs
        return a

    def __array_finalize__(self, obj):
        self.attrs = getattr(obj, "attrs", {})


def _value(v):
    return v.decode() if isinstance(v, bytes) else v


# Units and frames of a run's datasets (SI; the layout of sim/files/h5_output.h and
# docs/outputs.md), given as the attributes `units` and `frame` of what open_run returns; an
# attribute the file itself has wins. The wrench is about the scoop's centre of mass: `body` is
# the scoop mesh's own frame, `l_scoop` the arm's last link's, `world` the box's.
_SCOOP_WRENCH = {"force": "N", "torque": "N m"}
_UNITS = {
    "scoop/time": ("s", None), "scoop/pass": ("1", None),
    "scoop/rho": ("m", "along the trench"), "scoop/rho_path": ("m", "along the trench"),
    "scoop/pose": ("m, 1 (x y z qw qx qy qz)", "l_scoop in world"),
    "scoop/contacts": ("1", None), "scoop/collected_count": ("1", None),
    "scoop/collected_mass": ("kg", None),
    "series/time": ("s", None), "series/kinetic_energy": ("J", None),
    "series/contacts": ("1", None), "series/awake": ("1", None),
    "series/wall_force": ("N", "world (x y z per wall)"),
    "arm/time": ("s", None), "arm/joint_position": ("rad", "joint"),
    "arm/joint_reference": ("rad", "joint"), "arm/joint_velocity": ("rad/s", "joint"),
    "arm/torque_applied": ("N m", "joint"), "arm/torque_demanded": ("N m", "joint"),
    "arm/effort_limit": ("N m", "joint"), "arm/effort_derate": ("1", "joint"),
    "arm/ft_sensor": ("N, N m", "sensor joint's child link"),
    "arm/fault_bits": ("bit mask", None), "arm/fault_latched": ("bit mask", None),
    "arm/tracking_error": ("m", "world"),
    "arm/report/peak_torque": ("N m", "joint"), "arm/report/effort_limit": ("N m", "joint"),
    "arm/report/effort_derate": ("1", "joint"), "arm/report/margin": ("1", "joint"),
    "arm/report/saturation_time": ("s", "joint"),
    "bonds/time": ("s", None), "bonds/intact": ("1", None),
    "bonds/broken/time": ("s", None), "bonds/broken/pair": ("1 (persistent ids a < b)", None),
    "bonds/broken/position": ("m", "world"), "bonds/broken/mode": ("1 (1 tension, 2 shear)", None),
    "bonds/broken/stress": ("Pa", None),
}
for _kind, _unit in _SCOOP_WRENCH.items():
    for _frame in ("body", "scoop", "world"):
        _UNITS[f"scoop/{_kind}_{_frame}"] = (_unit, "l_scoop" if _frame == "scoop" else _frame)
_SNAPSHOT_UNITS = {"position": ("m", "world"), "velocity": ("m/s", "world"),
                   "angular_velocity": ("rad/s", "world"), "radius": ("m", None),
                   "speed": ("m/s", None), "points": ("m", "world"),
                   "pose": ("m, 1 (x y z qw qx qy qz)", "body in world")}


def _known(name):
    """(units, frame) of dataset `name` (no leading '/'), or None where the layout says none."""
    if name in _UNITS:
        return _UNITS[name]
    if name.startswith("snapshots/"):
        return _SNAPSHOT_UNITS.get(name.rsplit("/", 1)[-1])
    return None


def _attributes(name, file_attrs):
    attrs = {}
    known = _known(name)
    if known:
        attrs["units"] = known[0]
        if known[1]:
            attrs["frame"] = known[1]
    attrs.update({k: _value(v) for k, v in file_attrs.items()})
    return attrs


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
                self._datasets[name] = Dataset(d[:_rows(f, name)] if d.shape else d[()],
                                               _attributes(name, d.attrs))
        return self._datasets[name]


def _rows(f, name):
    """How many rows of dataset `name` to read: a series of a group with a time (scoop, arm,
    series, bonds, bonds/broken) is cut to time's rows. scoopsim writes a group's time last in
    each flush, so a file read while its run writes, or killed in a flush, may hold more rows
    of the others (docs/files.md, "Crash-safe output")."""
    group = name.rsplit("/", 1)[0] if "/" in name else ""
    time = group + "/time"
    if group and name != time and time in f and name not in _NOT_SERIES:
        return min(f[name].shape[0], f[time].shape[0])
    return f[name].shape[0]


# Datasets of a group with a time that are not one row per sample: the fault events (one row
# per event, written when the run ends). One row per pass (collected_mass) is never cut by min.
_NOT_SERIES = {"arm/fault_events"}


def open_run(path):
    """The saved run at `path` (an HDF5 file of `scoopsim run`): run["scoop/force_world"] is a
    numpy array, its .attrs the dataset's attributes."""
    return SavedRun(path)
