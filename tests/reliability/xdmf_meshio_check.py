# Opens a run's results.xdmf with a real XDMF reader (meshio's TimeSeriesReader) and checks what
# it reads against results.h5 read directly with h5py: the point count and positions, the time of
# every frame, and at every frame and subset the fields of /dic, /kinematics and /strain; that the
# file lists exactly the fields results.h5 holds, and copies no data (every DataItem refers to
# results.h5; the per-frame datasets are HDF5 virtual datasets). Run by xdmf_reader_test.cc:
#   python3 xdmf_meshio_check.py RUN_FOLDER      (prints "xdmf-ok" and exits 0 when all hold)
import os
import sys
import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np

folder = sys.argv[1]
xdmf = os.path.join(folder, "results.xdmf")
h5 = h5py.File(os.path.join(folder, "results.h5"), "r")
t_ms = h5["/time/t_ms"][:]
x, y = h5["/dic/x_px"][:], h5["/dic/y_px"][:]
F, N = t_ms.size, x.size

# What the XDMF must show: every [F x N] scalar field, and the vectors whose two parts exist.
scalars = {}
for path in ["/dic/status", "/dic/zncc", "/dic/sigma_px", "/dic/dudx_warp", "/dic/dudy_warp",
             "/dic/dvdx_warp", "/dic/dvdy_warp"] + [
                 "/strain/" + name for name in (h5["/strain"] if "/strain" in h5 else [])]:
    if path in h5 and h5[path].shape == (F, N):
        scalars[path.rsplit("/", 1)[1]] = path
vectors = {}
for name, px, py in [("displacement_px", "/dic/u_px", "/dic/v_px"),
                     ("displacement_mm", "/kinematics/ux_mm", "/kinematics/uy_mm"),
                     ("velocity_mm_s", "/kinematics/vx_mm_s", "/kinematics/vy_mm_s"),
                     ("acceleration_mm_s2", "/kinematics/ax_mm_s2", "/kinematics/ay_mm_s2")]:
    if px in h5 and py in h5:
        vectors[name] = (px, py)
assert "displacement_px" in vectors and "velocity_mm_s" in vectors, sorted(vectors)
assert "acceleration_mm_s2" in vectors, "no acceleration in results.h5"
assert "status" in scalars and "zncc" in scalars and "sigma_px" in scalars, sorted(scalars)


def same(a, b, what):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape, (what, a.shape, b.shape)
    assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), (what, a[:5], b[:5])


with meshio.xdmf.TimeSeriesReader(xdmf) as reader:
    points, cells = reader.read_points_cells()
    same(points, np.column_stack([x, y]), "points")
    assert len(cells) == 1 and cells[0].type == "vertex", cells
    same(cells[0].data.ravel(), np.arange(N), "vertices")
    assert reader.num_steps == F, (reader.num_steps, F)
    for f in range(F):
        t, point_data, cell_data = reader.read_data(f)
        assert t == t_ms[f], (f, t, t_ms[f])
        assert not cell_data, cell_data
        assert set(point_data) == set(scalars) | set(vectors), (f, sorted(point_data))
        for name, path in scalars.items():
            same(point_data[name], h5[path][f], f"{name} in frame {f}")
        for name, (px, py) in vectors.items():
            v = point_data[name]
            same(v[:, 0], h5[px][f], f"{name} x in frame {f}")
            same(v[:, 1], h5[py][f], f"{name} y in frame {f}")
            same(v[:, 2], np.zeros(N), f"{name} z in frame {f}")

# A known subset: the first valid one in the middle frame, by value.
f = F // 2
k = int(np.flatnonzero(h5["/dic/status"][f] == 0)[0])
with meshio.xdmf.TimeSeriesReader(xdmf) as reader:
    reader.read_points_cells()
    _, point_data, _ = reader.read_data(f)
u = point_data["displacement_px"][k]
assert u[0] == h5["/dic/u_px"][f, k] and u[1] == h5["/dic/v_px"][f, k], (k, u)
assert np.isfinite(u[0]) and abs(u[0]) + abs(u[1]) > 0, (k, u)

# No data copied: all heavy data in results.h5, the per-frame datasets virtual (views).
root = ET.parse(xdmf).getroot()
for item in root.iter("DataItem"):
    assert item.get("Format") == "HDF", item.attrib
    assert item.text.strip().startswith("results.h5:/xdmf/"), item.text
for name, group in h5["/xdmf"].items():
    if name.startswith("frame_"):
        for ds in group.values():
            assert ds.is_virtual, ds.name
assert h5["/xdmf/points_px"].is_virtual
print("xdmf-ok", F, "frames", N, "subsets", len(scalars) + len(vectors), "fields")
