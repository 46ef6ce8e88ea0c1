#!/usr/bin/python3
"""The XDMF sidecar of a coupled dig (scenes/fault/boulder.yaml: scoop, arm and a boulder) against
its HDF5 file. Runs `scoopsim run` for 0.4 s of dig with a snapshot every 2000 steps, then checks:
the sidecar parses (xml.etree) as XDMF 3 with one temporal collection each for the particles, the
scoop, the obstacles and the arm; each collection has a grid per snapshot at the snapshot's time;
every DataItem names a dataset of the HDF5 file that exists with the stated dimensions and number
type; a Triangle topology has NumberOfElements triangles of 3 indices into its points, and its
`part` attribute one value per triangle; and each part's points, taken back into its body frame by
the pose stored with them (x y z qw qx qy qz), are the same at every snapshot to 1e-12 m (the
triangles are one rigid mesh moved by the recorded pose)."""

import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np

from cli_check import test_dir

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TYPES = {("Float", "8"): np.float64, ("Int", "8"): np.int64, ("Int", "4"): np.int32}


def scene_text(folder):
    """scenes/fault/boulder.yaml with its files named absolutely (snapshots every 2000 steps are
    set on the command line)."""
    text = open(os.path.join(ROOT, "scenes", "fault", "boulder.yaml")).read()
    text = re.sub(r"(materials: |mesh: |urdf: )(\.\./[^\s,}]+)",
                  lambda m: m.group(1) + os.path.normpath(os.path.join(folder, m.group(2))), text)
    return text


def rotation(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def data_item(item, h5, h5_name):
    """The dataset a DataItem names, checked against its Dimensions and number type."""
    assert item.get("Format") == "HDF", item.attrib
    file_name, path = item.text.strip().split(":", 1)
    assert file_name == h5_name, (file_name, h5_name)
    assert path in h5, "%s: no dataset %s" % (h5_name, path)
    data = h5[path]
    dims = tuple(int(d) for d in item.get("Dimensions").split())
    assert data.shape == dims, "%s: shape %s, the XDMF says %s" % (path, data.shape, dims)
    want = TYPES[(item.get("NumberType"), item.get("Precision"))]
    assert data.dtype == want, "%s: %s, the XDMF says %s" % (path, data.dtype, want)
    return data[()]


def main():
    binary = sys.argv[1]
    with test_dir("xdmf") as d:
        scene = os.path.join(d, "boulder.yaml")
        with open(scene, "w") as f:
            f.write(scene_text(os.path.join(ROOT, "scenes", "fault")))
        out = os.path.join(d, "boulder.h5")
        env = dict(os.environ, OMP_WAIT_POLICY="passive")
        result = subprocess.run([binary, "run", scene, "-o", out, "--stop-after", "0.4",
                                 "--set", "output.snapshot_every=2000", "--threads", "1",
                                 "--quiet"], capture_output=True, text=True,
                                env=env)
        assert result.returncode == 0, result.stderr
        xdmf = os.path.join(d, "boulder.xdmf")
        root = ET.parse(xdmf).getroot()
        assert root.tag == "Xdmf" and root.get("Version") == "3.0", root.attrib
        domain = root.find("Domain")
        collections = {g.get("Name"): g for g in domain.findall("Grid")}
        assert sorted(collections) == ["arm", "obstacles", "particles", "scoop"], sorted(collections)
        with h5py.File(out, "r") as h5:
            times = {"/snapshots/" + k: h5["snapshots"][k].attrs["time"] for k in h5["snapshots"]}
            assert len(times) >= 3, times
            items = 0
            for name, collection in collections.items():
                assert collection.get("GridType") == "Collection", name
                assert collection.get("CollectionType") == "Temporal", name
                grids = collection.findall("Grid")
                assert len(grids) == len(times), (name, len(grids), len(times))
                body = {}  # part -> body-frame points at the first snapshot
                for grid in grids:
                    group = "/snapshots/" + grid.get("Name")
                    assert float(grid.find("Time").get("Value")) == times[group], (name, group)
                    for item in grid.iter("DataItem"):
                        data_item(item, h5, os.path.basename(out))
                        items += 1
                    topology = grid.find("Topology")
                    points = data_item(grid.find("Geometry/DataItem"), h5, os.path.basename(out))
                    cells = data_item(topology.find("DataItem"), h5, os.path.basename(out))
                    assert len(cells) == int(topology.get("NumberOfElements")), (name, group)
                    if name == "particles":
                        assert topology.get("TopologyType") == "Polyvertex"
                        continue
                    assert topology.get("TopologyType") == "Triangle", (name, group)
                    assert cells.shape[1] == 3 and cells.min() >= 0
                    assert cells.max() < len(points), (name, group)
                    part = data_item(grid.find("Attribute/DataItem"), h5, os.path.basename(out))
                    assert grid.find("Attribute").get("Center") == "Cell"
                    assert len(part) == len(cells), (name, group)
                    pose = h5[group + "/meshes/" + name + "/pose"][()]
                    assert part.min() == 0 and part.max() == len(pose) - 1, (name, group)
                    for p, (x, y, z, *q) in enumerate(pose):
                        vertices = np.unique(cells[part == p])
                        local = (points[vertices] - [x, y, z]) @ rotation(q)
                        if p not in body:
                            body[p] = local
                        err = np.abs(local - body[p]).max()
                        assert err < 1e-12, "%s %s part %d: moved %.3g m in its body" % (
                            name, group, p, err)
    print("xdmf_test: %d snapshots, 4 collections, %d data items checked" % (len(times), items))
    return 0


if __name__ == "__main__":
    sys.exit(main())
