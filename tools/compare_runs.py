#!/usr/bin/python3
"""Compares the content of spall output directories: every history dataset and root attribute,
every frame's grid names, fragment metadata and exact index-to-world map, every density voxel.

Usage: /usr/bin/python3 tools/compare_runs.py REFERENCE OTHER [OTHER ...]
Exits 0 when every OTHER holds exactly REFERENCE's content, else 1 naming the first difference.
(The .vdb bytes themselves differ between runs: OpenVDB writes a random UUID in each header.)
Needs Debian's python3-h5py, python3-numpy and python3-openvdb.
"""
import glob
import os
import sys

import h5py
import numpy as np
import pyopenvdb as vdb


def history(out):
    arrays = {}
    with h5py.File(os.path.join(out, "history.h5"), "r") as h:
        h.visititems(lambda name, obj: arrays.__setitem__(name, obj[()]) if isinstance(obj, h5py.Dataset) else None)
        attrs = {k: str(h.attrs[k]) for k in h.attrs}
    return arrays, attrs


def frame(path):
    metas = vdb.readAllGridMetadata(path)
    # Four points fix the affine index-to-world map.
    corners = ((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1))
    fragments = sorted((m.name, m.metadata["voxel_count"], tuple(m.metadata["centre_of_mass_m"]),
                        tuple(m.metadata["linear_velocity_m_s"]), tuple(m.metadata["angular_velocity_rad_s"]),
                        m.metadata.get("mesh_key"), tuple(tuple(m.transform.indexToWorld(p)) for p in corners))
                       for m in metas if m.name.startswith("fragment_"))
    density = []
    if any(m.name == "density" for m in metas):
        density = sorted(tuple(v.min) for v in vdb.read(path, "density").citerOnValues())
    return sorted(m.name for m in metas), fragments, density


def differences(reference, other):
    """Yields a line per difference, first the history's, then each frame's."""
    a, attrs_a = history(reference)
    b, attrs_b = history(other)
    if a.keys() != b.keys():
        yield f"history datasets differ: {sorted(set(a) ^ set(b))}"
    for key in sorted(set(a) & set(b)):
        if a[key].shape != b[key].shape or not np.array_equal(a[key], b[key]):
            yield f"history dataset {key} differs"
    if attrs_a != attrs_b:
        yield f"history attributes differ: {sorted(k for k in set(attrs_a) | set(attrs_b) if attrs_a.get(k) != attrs_b.get(k))}"
    frames_a = sorted(os.path.basename(p) for p in glob.glob(os.path.join(reference, "fragments.*.vdb")))
    frames_b = sorted(os.path.basename(p) for p in glob.glob(os.path.join(other, "fragments.*.vdb")))
    if frames_a != frames_b:
        yield f"frame files differ: {len(frames_a)} against {len(frames_b)}"
    for name in frames_a:
        if name not in frames_b:
            continue
        names_a, fragments_a, density_a = frame(os.path.join(reference, name))
        names_b, fragments_b, density_b = frame(os.path.join(other, name))
        if names_a != names_b:
            yield f"{name}: grid names differ"
        if fragments_a != fragments_b:
            yield f"{name}: fragment metadata or transforms differ"
        if density_a != density_b:
            yield f"{name}: density voxels differ"


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    same = True
    for other in sys.argv[2:]:
        for line in differences(sys.argv[1], other):
            print(f"{other} against {sys.argv[1]}: {line}", file=sys.stderr)
            same = False
    sys.exit(0 if same else 1)


if __name__ == "__main__":
    main()
