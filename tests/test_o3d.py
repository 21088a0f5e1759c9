"""floorscan.o3d: Open3D without its ml and visualization subpackages."""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHECK = r"""
import sys
import numpy as np
from floorscan.o3d import o3d
loaded = sorted(m for m in ("open3d.ml", "open3d.visualization", "sklearn", "dash") if m in sys.modules)
# the library works: ICP recovers a 0.2 m shift of a random cloud (point-to-point)
rng = np.random.default_rng(0)
pts = rng.random((500, 3))
src = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
dst = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts + [0.2, 0.0, 0.0]))
init = np.eye(4)
res = o3d.pipelines.registration.registration_icp(src, dst, 0.5, init)
shift = res.transformation[:3, 3]
import open3d.visualization  # the real subpackage, imported on demand
print(loaded, round(float(shift[0]), 4), round(float(abs(shift[1:]).max()), 4), hasattr(open3d.visualization, "draw_geometries"))
"""


def test_open3d_loads_without_ml_and_visualization():
    out = subprocess.run([sys.executable, "-c", CHECK], capture_output=True, text=True, check=True, cwd=ROOT).stdout.split()
    assert out == ["[]", "0.2", "0.0", "True"], out


def test_open3d_imported_before_is_returned_unchanged():
    code = "import open3d, sys; from floorscan.o3d import o3d; print(o3d is open3d, 'open3d.ml' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT).stdout.split()
    assert out == ["True", "True"]
